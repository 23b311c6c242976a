#!/bin/sh
# pm-ic with the precomputed estimator (precompute_stride=4) at 256², the protocol of
# bench-results/2026-12-08-isd-whole/run.sh (whole animation rendered, the 12 frames with
# Mitsuba references scored; pm-ic is stateless, so only they are rendered), to set
# ic-static-dynamic's 256² figures against pm-ic with the cheaper estimator.
BIN=${BIN:-chronolux}
REFS=${REFS:-/work/refs256}
OUT=${OUT:-$(dirname "$0")}
C="/work/shared/peers/cornell-moving.glb --frames 0..48 --measure 0..8,12,24,36,47 --reference $REFS --target-flip 0.05 --threads 1 --json"
for e in ${EFFORTS:-25 50}; do
  uptime > "$OUT/pm-ic-pre-256-$e.uptime"
  $BIN bench quality $C --method pm-ic --set precompute_stride=4 --start-effort $e --max-effort $e > "$OUT/pm-ic-pre-256-$e.json" 2> "$OUT/pm-ic-pre-256-$e.log"
  uptime >> "$OUT/pm-ic-pre-256-$e.uptime"
done
