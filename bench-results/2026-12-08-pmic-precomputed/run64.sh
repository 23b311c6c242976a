#!/bin/sh
# 64², frames 0-23 (one whole segment), our own path references (relMSE <= 5e-4, made with
# `chronolux reference ... --frames 0..24 --resolution 64x64 --target-error 5e-4 --max-spp 1024`
# into REF): ic-static-dynamic against pm-ic, both at their defaults (the precomputed
# estimator), the protocol of bench-results/2026-12-08-isd-correction/run64.sh with lower
# start efforts (the precomputed estimator reaches the targets with fewer photons).
BIN=${BIN:-chronolux}
REF=${REF:-/tmp/isd64/ref-cm64}
OUT=${OUT:-$(dirname "$0")}
uptime > "$OUT/cm64.uptime"
$BIN bench quality /work/shared/peers/cornell-moving.glb --method ic-static-dynamic --baseline pm-ic \
  --frames 0..24 --reference "$REF" --target-flip 0.11,0.1,0.09,0.08 \
  --start-effort 3 --max-effort 100 --threads 1 --json --report "$OUT/cm64.md" > "$OUT/cm64.json" 2> "$OUT/cm64.log"
uptime >> "$OUT/cm64.uptime"
