#!/bin/bash
# ic-static-dynamic at 100k photons (to bracket pm-ic's FLIP at 50k), same protocol as run.sh.
B=${B:-chronolux}
REFS=${REFS:-/work/refs256}
C="/work/shared/peers/cornell-moving.glb --frames 0..48 --measure 0..8,12,24,36,47 --reference $REFS --target-flip 0.05 --threads 1 --json"
$B bench quality $C --method ic-static-dynamic --start-effort 100 --max-effort 100 > ic-static-dynamic-100-1.json 2> ic-static-dynamic-100-1.log
uptime >> uptime.txt
