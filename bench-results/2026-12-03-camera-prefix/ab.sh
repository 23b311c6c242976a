#!/usr/bin/env bash
# A/B of stbpt before and after the camera-prefix re-trace, interleaved, ROUNDS rounds.
# usage: A=<before binary> B=<after binary> CM=<cornell-moving.glb> RCM=<its 256² refs>
#        RDEMO=<demo 64² refs> RRIG=<RiggedSimple --stage cornell 64² refs>
#        SCENES=<../shared/scenes> RDOLLY=<dolly 64² refs> ab.sh OUT ROUNDS
set -euo pipefail
OUT=$1; ROUNDS=${2:-3}; mkdir -p "$OUT"
. "$(dirname "$0")/../../scripts/bench/quality_q.sh"
for r in $(seq 1 "$ROUNDS"); do
  for ab in A B; do
    bin=${!ab}
    q "cm256-oidn-$ab$r" "$bin" "$CM" --frames 0..8 --reference "$RCM" --max-depth 8 --threads 2 \
      --denoise --method stbpt --set window=8 --set interleave=2 --start-effort 1 --max-effort 1
    q "cm256-2spp-$ab$r" "$bin" "$CM" --frames 0..8 --reference "$RCM" --resolution 256x256 --max-depth 8 \
      --threads 2 --method stbpt --start-effort 2 --max-effort 2
    q "demo64-$ab$r" "$bin" builtin:demo --frames 0..8 --reference "$RDEMO" --threads 2 \
      --method stbpt --start-effort 4 --max-effort 4
    q "rigged64-$ab$r" "$bin" "$SCENES/RiggedSimple.glb" --stage cornell --frames 0..8 \
      --reference "$RRIG" --threads 2 --method stbpt --start-effort 4 --max-effort 4
    q "dolly64-$ab$r" "$bin" builtin:dolly --frames 0..8 --reference "$RDOLLY" --threads 2 \
      --method stbpt --start-effort 4 --max-effort 4
  done
done
