#!/bin/bash
# ic-static-dynamic vs pm-ic, cornell-moving, 64², our own path references (relMSE ≤ 5e-4), unlimited depth:
# frames 0–7 and 0–23 (BENCHMARKS' protocol), one run each after the 256² run.
B=chronolux
while pgrep -f "run256.sh" > /dev/null; do sleep 10; done
for n in 8 24; do
$B bench quality /work/shared/peers/cornell-moving.glb --method ic-static-dynamic --baseline pm-ic \
  --frames 0..$n --reference /work/isd/ref-cm64 --target-flip 0.11,0.1,0.09,0.08 \
  --start-effort 25 --max-effort 100 --threads 1 --json --report cm64-$n.md > cm64-$n.json 2> cm64-$n.log
done
