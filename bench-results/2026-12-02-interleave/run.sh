#!/bin/bash
# Issue 17, interleaved generation (stbpt `interleave`): time to FLIP against the full
# generation, one run, configurations interleaved. BIN: chronolux built with
# `--features oidn` (ci profile); OUT: results folder; REFS: the Mitsuba references of
# cornell-moving (frame_000N.exr), DEMO_REF: converged demo frames 0-7 at 64x64.
set -u
OUT=${OUT:-$(dirname "$0")}
BIN=${BIN:?chronolux binary}
REFS=${REFS:-/work/peers-run/refs}
DEMO_REF=${DEMO_REF:-/work/refs/ref-demo-64-0to8}
CM=${CM:-../shared/peers/cornell-moving.glb}
{ date -u; uptime; lscpu | grep -E "Model name|^CPU\(s\)"; } > "$OUT/machine.txt"
q() { # name, then bench quality arguments
  local name=$1; shift
  "$BIN" bench quality "$@" --json > "$OUT/$name.json" 2> "$OUT/$name.err"
}
for round in a b; do
  # cornell-moving, 256x256, frames 0-7, denoised (as the peer comparison), 2 threads
  for cfg in "1 2 1" "1 4 1" "1 8 1" "2 4 1" "2 8 1" "2 4 2" "2 8 2" "4 8 2"; do
    set -- $cfg
    q "cm-$round-il$1-k$2-e$3" "$CM" --frames 0..8 --reference "$REFS" --max-depth 8 --threads 2 \
      --method stbpt --set window=$2 --set interleave=$1 --denoise --target-flip 0.08 \
      --start-effort $3 --max-effort $3
  done
  # the demo, 64x64, frames 0-7, no denoiser, 1 thread
  for cfg in "1 1" "1 2" "1 4" "2 1" "2 2" "2 4" "2 8" "4 4" "4 8"; do
    set -- $cfg
    q "demo-$round-il$1-e$2" builtin:demo --frames 0..8 --reference "$DEMO_REF" --threads 1 \
      --method stbpt --set interleave=$1 --target-flip 0.05 --start-effort $2 --max-effort $2
  done
  echo "round $round end $(date -u) $(uptime)" >> "$OUT/machine.txt"
done
