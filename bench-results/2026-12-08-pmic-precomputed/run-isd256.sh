#!/bin/sh
# ic-static-dynamic with the precomputed estimator for its maps (pmic.precompute_stride=4), the
# protocol of run256.sh (whole animation, 12 scored frames, 256², Mitsuba references), to set
# against pm-ic with the same estimator there.
BIN=${BIN:-chronolux}
REFS=${REFS:-/work/refs256}
OUT=${OUT:-$(dirname "$0")}
C="/work/shared/peers/cornell-moving.glb --frames 0..48 --measure 0..8,12,24,36,47 --reference $REFS --target-flip 0.05 --threads 1 --json"
for e in 25 50 12; do
  uptime > "$OUT/isd-pre-256-$e.uptime"
  $BIN bench quality $C --method ic-static-dynamic --set pmic.precompute_stride=4 --start-effort $e --max-effort $e > "$OUT/isd-pre-256-$e.json" 2> "$OUT/isd-pre-256-$e.log"
  uptime >> "$OUT/isd-pre-256-$e.uptime"
done
