#!/bin/bash
# Issue 17: the denoiser's albedo/normal passes at 8 (AOV_SPP, the current), 4 and 2
# camera samples per pixel: CPU and FLIP of stbpt + OIDN on cornell-moving (the peer
# comparison's configurations), one run, the three builds interleaved, two rounds.
# B8, B4, B2: chronolux binaries (ci profile, --features oidn) differing only in AOV_SPP.
set -u
OUT=${OUT:-$(cd "$(dirname "$0")" && pwd)}
REFS=${REFS:-/work/peers-run/refs}
CM=${CM:-/work/peers-run/cornell-moving.glb}
{ date -u; uptime; } > "$OUT/machine.txt"
for round in a b; do
  for cfg in "8 8 3" "8 8 4" "2 8 1"; do
    set -- $cfg
    for aov in 8 4 2; do
      BIN=$(eval echo \$B$aov)
      "$BIN" bench quality "$CM" --frames 0..8 --reference "$REFS" --max-depth 8 --threads 2 \
        --method stbpt --set window=$2 --set interleave=$1 --denoise --target-flip 0.08 \
        --start-effort $3 --max-effort $3 --json > "$OUT/$round-il$1-k$2-e$3-aov$aov.json" 2> /dev/null
    done
  done
  echo "round $round end $(date -u) $(uptime)" >> "$OUT/machine.txt"
done
