#!/bin/bash
# ic-static-dynamic vs pm-ic, cornell-moving, 256², frames 0–7 (the protocol), Mitsuba refs
B=chronolux
$B bench quality /work/shared/peers/cornell-moving.glb --method ic-static-dynamic --baseline pm-ic \
  --frames 0..8 --reference /work/refs256 --max-depth 8 --target-flip 0.1,0.09,0.08,0.07 \
  --start-effort 25 --max-effort 100 --threads 1 --json --report cm256-8.md > cm256-8.json 2> cm256-8.log
