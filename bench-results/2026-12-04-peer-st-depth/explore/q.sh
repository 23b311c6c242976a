#!/bin/bash
# q NAME EFFORT [args...]: spacetime-dept + OIDN on cornell-moving, 48 frames, 12 scored
source /work/env.sh
B=${B:-/work/target-main/release/chronolux}
name=$1; e=$2; shift 2
$B bench quality /work/peers-run/cornell-moving.glb --frames 0..48 --measure 0..8,12,24,36,47 --reference /work/refs-cm --max-depth 8 --threads 2 --denoise --target-flip 0.08 --method spacetime-dept --start-effort $e --max-effort $e "$@" --json > $name.json 2> $name.err
python3 -c "
import json;d=json.load(open('$name.json'))
for r in d['results']:
  for l in r['levels']: print('$name', l['effort'], round(l['cpu_s'],1), round(l['flip_mean'],4), round(l['flicker'],4), round(l['relmse_mean'],5))"
