#!/bin/sh
# Issue 41, ic-selective with per-light-group maps and precomputed irradiance: the
# 2026-12-07 protocol (BENCHMARKS.md, "Issue 13 / 41"), with the lowest effort lowered so
# that ic-selective's levels bracket the targets (start 1 on the moving light, 2 on
# cornell-moving), and one more bench against ic-selective with refresh=1 (every stratum
# re-cast each frame: the precomputed estimator without the selective update).
# Run from a scratch folder holding movlight.gltf (python3 scripts/make_moving_light_scene.py).
# BIN: the binary (cargo build --profile ci -p chronolux). Results next to this script.
set -e
BIN=${BIN:-target/ci/chronolux}
OUT=${OUT:-$(dirname "$0")}
{ date -u; lscpu | grep -E "Model name|^CPU\(s\)|Thread"; lscpu | grep -o "avx512[a-z0-9_]*" | sort -u | tr '\n' ' '; echo; } > "$OUT/machine.txt"
[ -d ref-light ] || "$BIN" reference movlight.gltf --stage cornell --frames 0..12 --resolution 64x64 \
    --target-error 1e-3 --max-spp 512 --threads 1 -o ref-light
[ -d ref-cm ] || "$BIN" reference /work/shared/peers/cornell-moving.glb --frames 4..16 --resolution 64x64 \
    --target-error 1e-3 --max-spp 512 --threads 1 -o ref-cm
uptime > "$OUT/light.uptime"
"$BIN" bench quality movlight.gltf --stage cornell --method ic-selective --baseline pm-ic \
    --reference ref-light --frames 0..12 --target-flip 0.077,0.075,0.07 \
    --start-effort 1 --max-effort 16 --threads 1 --json --report "$OUT/light.md" > "$OUT/light.json" 2> "$OUT/light.log"
uptime >> "$OUT/light.uptime"
uptime > "$OUT/cm.uptime"
"$BIN" bench quality /work/shared/peers/cornell-moving.glb --method ic-selective --baseline pm-ic \
    --reference ref-cm --frames 4..16 --target-flip 0.12,0.11,0.1,0.095 \
    --start-effort 2 --max-effort 32 --threads 1 --json --report "$OUT/cm.md" > "$OUT/cm.json" 2> "$OUT/cm.log"
uptime >> "$OUT/cm.uptime"
uptime > "$OUT/refresh1.uptime"
"$BIN" bench quality movlight.gltf --stage cornell --method ic-selective --baseline ic-selective \
    --baseline-set refresh=1 --reference ref-light --frames 0..12 --target-flip 0.077,0.075,0.07 \
    --start-effort 1 --max-effort 16 --threads 1 --json --report "$OUT/refresh1.md" > "$OUT/refresh1.json" 2> "$OUT/refresh1.log"
uptime >> "$OUT/refresh1.uptime"
