#!/bin/bash
B=/work/main/target/ci/chronolux
C="--frames 0..2 --reference /work/refs256 --max-depth 8 --target-flip 0.08 --start-effort 25 --max-effort 25 --threads 1 --json"
$B bench quality /work/shared/peers/cornell-moving.glb --method ic-static-dynamic $C > q-density.json 2> q-density.log
$B bench quality /work/shared/peers/cornell-moving.glb --method ic-static-dynamic $C --set correction_m=6 > q-g6.json 2> q-g6.log
$B bench quality /work/shared/peers/cornell-moving.glb --method ic-static-dynamic $C --set correction_m=12 > q-g12.json 2> q-g12.log
