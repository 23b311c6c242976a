#!/bin/bash
# 64², frames 0–23 (one whole segment), our own path references (relMSE ≤ 5e-4):
# the gathered correction (m = 6) against pm-ic in one run, then the density correction alone.
B=${B:-chronolux}
while pgrep -f "run256.sh" > /dev/null; do sleep 10; done
[ -d /tmp/isd/ref-cm64 ] || $B reference /work/shared/peers/cornell-moving.glb --frames 0..24 --resolution 64x64 \
   --target-error 5e-4 --max-spp 1024 -o /tmp/isd/ref-cm64 > ref64.log 2>&1
$B bench quality /work/shared/peers/cornell-moving.glb --method ic-static-dynamic --baseline pm-ic \
  --frames 0..24 --reference /tmp/isd/ref-cm64 --target-flip 0.11,0.1,0.09,0.08 \
  --start-effort 25 --max-effort 100 --threads 1 --json --report cm64-g6.md --set correction_m=6 > cm64-g6.json 2> cm64-g6.log
$B bench quality /work/shared/peers/cornell-moving.glb --method ic-static-dynamic \
  --frames 0..24 --reference /tmp/isd/ref-cm64 --target-flip 0.11,0.1,0.09,0.08 \
  --start-effort 25 --max-effort 100 --threads 1 --json --report cm64-density.md > cm64-density.json 2> cm64-density.log
