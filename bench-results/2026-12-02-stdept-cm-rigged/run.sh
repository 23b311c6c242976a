#!/bin/bash
B=/work/refs/chronolux-ebd8fe5
for sc in cm rigged; do
  case $sc in cm) S=/work/shared/peers/cornell-moving.glb; X="";; rigged) S=/work/shared/scenes/RiggedSimple.glb; X="--stage cornell";; esac
  $B bench quality $S $X --method spacetime-dept --set spp=4 --baseline dept-spatial --reference /work/refs-stbpt/ref-$sc-64 \
    --frames 0..8 --target-flip 0.2,0.15,0.12,0.1,0.09 --start-effort 2 --max-effort 128 --threads 1 --json --report $sc.md > $sc.json 2> $sc.log
done
