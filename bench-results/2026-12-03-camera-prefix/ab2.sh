#!/usr/bin/env bash
# Tighter A/B: for each configuration, A and B alternate ROUNDS times (the machine's speed
# drifts over minutes, so pairs taken back to back give the usable ratios); then the ray
# queries of one `render` per binary and scene (exact, load-independent).
# usage: as ab.sh (A, B, CM, RCM, RDEMO, RRIG, SCENES) ab2.sh OUT ROUNDS
set -euo pipefail
OUT=$1; ROUNDS=${2:-4}; mkdir -p "$OUT"
. "$(dirname "$0")/../../scripts/bench/quality_q.sh"
for r in $(seq 1 "$ROUNDS"); do for ab in A B; do bin=${!ab}
  q "cm256-oidn-$ab$r" "$bin" "$CM" --frames 0..8 --reference "$RCM" --max-depth 8 --threads 2 \
    --denoise --method stbpt --set window=8 --set interleave=2 --start-effort 1 --max-effort 1
done; done
for r in $(seq 1 "$ROUNDS"); do for ab in A B; do bin=${!ab}
  q "rigged64-$ab$r" "$bin" "$SCENES/RiggedSimple.glb" --stage cornell --frames 0..8 \
    --reference "$RRIG" --threads 1 --method stbpt --start-effort 4 --max-effort 4
done; done
for r in $(seq 1 "$ROUNDS"); do for ab in A B; do bin=${!ab}
  q "demo64-$ab$r" "$bin" builtin:demo --frames 0..8 --reference "$RDEMO" --threads 1 \
    --method stbpt --start-effort 4 --max-effort 4
done; done
# Ray queries (closest-hit + shadow) summed over the frames of one render each.
for ab in A B; do bin=${!ab}
  for sc in "cm:$CM:256x256:--set window=8 --set interleave=2 --spp 1 --max-depth 8" \
            "rigged:$SCENES/RiggedSimple.glb:64x64:--stage cornell --spp 4" \
            "demo:builtin:demo:64x64:--spp 4" "dolly:builtin:dolly:64x64:--spp 4"; do
    IFS=: read -r name scene res extra <<<"$sc"
    [ "$scene" = builtin ] && { scene="builtin:$res"; res=${extra%%:*}; extra=${extra#*:}; }
    rm -rf "$OUT/r-$name-$ab"
    # shellcheck disable=SC2086
    "$bin" render "$scene" --method stbpt --frames 0..8 --resolution "$res" --threads 2 \
      --no-preview --output "$OUT/r-$name-$ab" $extra 2>/dev/null >/dev/null
    python3 - "$OUT/r-$name-$ab/run.json" "$name-$ab" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
fr = d["frames"]
rays = sum(f["stats"]["rays"] for f in fr); sh = sum(f["stats"]["shadow_rays"] for f in fr)
ret = sum(f["stats"]["reuse"]["retraced"] for f in fr)
print(f'{sys.argv[2]:12s} closest-hit {rays:9d} shadow {sh:9d} re-traced landings {ret:8d}')
PY
  done
done
