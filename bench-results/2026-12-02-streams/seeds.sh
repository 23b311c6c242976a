#!/bin/bash
# Issue 17: the sample-stream change on the demo over seeds 1-4 (streams.sh used seed 0):
# relMSE and flicker, which rose there in seed 0, before and after, one run.
# BEFORE, AFTER: as in streams.sh.
set -u
OUT=${OUT:-$(cd "$(dirname "$0")" && pwd)}
DEMO_REF=${DEMO_REF:-/work/refs/ref-demo-64-0to8}
echo "seeds: $(date -u) $(uptime)" >> "$OUT/machine.txt"
for seed in 1 2 3 4; do
  for which in before after; do
    BIN=$([ $which = before ] && echo "$BEFORE" || echo "$AFTER")
    "$BIN" bench quality builtin:demo --frames 0..8 --reference "$DEMO_REF" --threads 1 \
      --method stbpt --target-flip 0.05 --start-effort 1 --max-effort 4 --seed $seed \
      --json > "$OUT/seed$seed-$which.json" 2> /dev/null
  done
done
