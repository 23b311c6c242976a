#!/usr/bin/env bash
# A/B of stbpt without (A) and with (B) the shift, interleaved, ROUNDS rounds, on
# cornell-moving (256², frames 0–7, N = 2, K = 8, max depth 8, 2 threads) with OIDN at
# 1 spp and without at 4 spp.
# usage: A=<before> B=<after> CM=<cornell-moving.glb> RCM=<its 256² refs> ab.sh OUT ROUNDS
set -euo pipefail
OUT=$1; ROUNDS=${2:-3}; mkdir -p "$OUT"
. "$(dirname "$0")/../../scripts/bench/quality_q.sh"
for r in $(seq 1 "$ROUNDS"); do for ab in A B; do bin=${!ab}
  q "cm256-oidn-$ab$r" "$bin" "$CM" --frames 0..8 --reference "$RCM" --max-depth 8 --threads 2 \
    --denoise --method stbpt --set window=8 --set interleave=2 --start-effort 1 --max-effort 1
done; done
for r in $(seq 1 "$ROUNDS"); do for ab in A B; do bin=${!ab}
  q "cm256-4spp-$ab$r" "$bin" "$CM" --frames 0..8 --reference "$RCM" --max-depth 8 --threads 2 \
    --method stbpt --set window=8 --set interleave=2 --start-effort 4 --max-effort 4
done; done
