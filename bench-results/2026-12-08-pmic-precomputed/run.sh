#!/bin/sh
# ic-selective against pm-ic WITH the same estimator (pm-ic's precompute_stride=4: the light
# groups' precomputed irradiance ic-selective reads), the protocol of
# bench-results/2026-12-08-icsel-light/run.sh (same references, same targets, whole
# 12-frame windows, 64², --threads 1); and pm-ic with it against pm-ic with the k-NN estimate.
# Run from the scratch folder holding movlight.gltf, ref-light and ref-cm (made by that script).
set -e
BIN=${BIN:-target/ci/chronolux}
OUT=${OUT:-$(dirname "$0")}
{ date -u; lscpu | grep -E "Model name|^CPU\(s\)|Thread"; lscpu | grep -o "avx512[a-z0-9_]*" | sort -u | tr '\n' ' '; echo; } > "$OUT/machine.txt"
b() { name=$1; shift; uptime > "$OUT/$name.uptime"; "$BIN" bench quality "$@" --threads 1 --json --report "$OUT/$name.md" > "$OUT/$name.json" 2> "$OUT/$name.log"; uptime >> "$OUT/$name.uptime"; }
b light-vs-pre movlight.gltf --stage cornell --method ic-selective --baseline pm-ic --baseline-set precompute_stride=4 \
    --reference ref-light --frames 0..12 --target-flip 0.077,0.075,0.07 --start-effort 1 --max-effort 16
b cm-vs-pre /work/shared/peers/cornell-moving.glb --method ic-selective --baseline pm-ic --baseline-set precompute_stride=4 \
    --reference ref-cm --frames 4..16 --target-flip 0.12,0.11,0.1,0.095 --start-effort 2 --max-effort 32
b light-pre-vs-knn movlight.gltf --stage cornell --method pm-ic --set precompute_stride=4 --baseline pm-ic \
    --reference ref-light --frames 0..12 --target-flip 0.077,0.075,0.07 --start-effort 1 --max-effort 16
