#!/bin/bash
# References for the goal-2 bench (spacetime-dept vs dept-spatial, whole windows): frames 8..16 at 64².
source /work/env.sh
B=/work/s19/chronolux
R="reference --frames 8..16 --resolution 64x64 --max-depth 8 --target-error 5e-5 --max-spp 4096 --threads 1"
$B $R builtin:demo -o refs/demo > refs/demo.log 2>&1
$B $R builtin:dolly -o refs/dolly > refs/dolly.log 2>&1
$B $R /work/shared/scenes/RiggedSimple.glb --stage cornell -o refs/rigged > refs/rigged.log 2>&1
echo done > refs/done
