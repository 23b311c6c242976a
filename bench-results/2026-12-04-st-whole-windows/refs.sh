#!/bin/bash
# References for run.sh (both modes): frames 8..16 at 64², max depth 8, chronolux reference
# (relMSE 5e-5 or 4096 spp), one thread each, into $REFS/{demo,dolly,rigged,cm}.
B=${B:?chronolux binary}
REFS=${REFS:?output folder}
R="reference --frames 8..16 --resolution 64x64 --max-depth 8 --target-error 5e-5 --max-spp 4096 --threads 1"
$B $R builtin:demo -o $REFS/demo
$B $R builtin:dolly -o $REFS/dolly
$B $R ../../../shared/scenes/RiggedSimple.glb --stage cornell -o $REFS/rigged
$B $R ../../../shared/peers/cornell-moving.glb -o $REFS/cm
