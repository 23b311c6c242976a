#!/bin/bash
# Issue 17: stbpt's sample streams across frames, before (a scramble per frame) and after
# (one sequence per pixel across frames), one run, the two binaries interleaved.
# BEFORE, AFTER: chronolux binaries (ci profile, --features oidn) at ebe83ad and 3662605.
set -u
OUT=${OUT:-$(cd "$(dirname "$0")" && pwd)}
REFS=${REFS:-/work/peers-run/refs}
DEMO_REF=${DEMO_REF:-/work/refs/ref-demo-64-0to8}
CM=${CM:-/work/peers-run/cornell-moving.glb}
{ date -u; uptime; lscpu | grep -E "Model name|^CPU\(s\)"; } > "$OUT/machine.txt"
for round in a b; do
  for which in before after; do
    BIN=$([ $which = before ] && echo "$BEFORE" || echo "$AFTER")
    for k in 2 4; do
      "$BIN" bench quality "$CM" --frames 0..8 --reference "$REFS" --max-depth 8 --threads 2 \
        --method stbpt --set window=$k --denoise --target-flip 0.08 --start-effort 1 \
        --max-effort 1 --json > "$OUT/cm-$round-$which-k$k.json" 2> /dev/null
      "$BIN" bench quality "$CM" --frames 0..8 --reference "$REFS" --max-depth 8 --threads 2 \
        --method stbpt --set window=$k --target-flip 0.08 --start-effort 1 \
        --max-effort 1 --json > "$OUT/cmraw-$round-$which-k$k.json" 2> /dev/null
    done
    "$BIN" bench quality builtin:demo --frames 0..8 --reference "$DEMO_REF" --threads 1 \
      --method stbpt --target-flip 0.05 --start-effort 1 --max-effort 4 \
      --json > "$OUT/demo-$round-$which.json" 2> /dev/null
  done
  echo "round $round end $(date -u) $(uptime)" >> "$OUT/machine.txt"
done
