#!/bin/bash
# 256², frames 0–1, 25k photons: ic-static-dynamic default, with β forced to 1 (every point
# served by the dynamic cache, i.e. pm-ic's estimator on the same photons), and pm-ic.
B=chronolux
while pgrep -f "run64.sh" > /dev/null; do sleep 10; done
C="--frames 0..2 --reference /work/refs256 --max-depth 8 --target-flip 0.08 --start-effort 25 --max-effort 25 --threads 1 --json"
$B bench quality /work/shared/peers/cornell-moving.glb --method ic-static-dynamic $C > b-isd.json 2> b-isd.log
$B bench quality /work/shared/peers/cornell-moving.glb --method ic-static-dynamic $C --set influence_sigmas=0 --set influence_low=0 --set influence_high=1e-6 > b-isd-beta1.json 2> b-isd-beta1.log
$B bench quality /work/shared/peers/cornell-moving.glb --method pm-ic $C > b-pmic.json 2> b-pmic.log
