#!/bin/bash
# ic-static-dynamic (gathered correction, m = 6) vs pm-ic, cornell-moving, 256², frames 0–7, Mitsuba refs;
# then the density correction (the previous default) alone, same levels.
B=${B:-chronolux}
$B bench quality /work/shared/peers/cornell-moving.glb --method ic-static-dynamic --baseline pm-ic \
  --frames 0..8 --reference /work/refs256 --max-depth 8 --target-flip 0.1,0.09,0.08,0.07 \
  --start-effort 25 --max-effort 100 --threads 1 --json --report cm256-g6.md --set correction_m=6 > cm256-g6.json 2> cm256-g6.log
$B bench quality /work/shared/peers/cornell-moving.glb --method ic-static-dynamic \
  --frames 0..8 --reference /work/refs256 --max-depth 8 --target-flip 0.1,0.09,0.08,0.07 \
  --start-effort 25 --max-effort 100 --threads 1 --json --report cm256-density.md > cm256-density.json 2> cm256-density.log
