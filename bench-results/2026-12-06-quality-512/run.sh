#!/bin/bash
# The quality table at 512² (issue 37): candidate effort settings of spacetime-dept and
# path, denoised (OIDN high), on the peer protocol (cornell-moving's 48 frames rendered,
# 12 scored against Mitsuba's converged 512² references, --max-depth 8, 2 threads). The
# first table (bench-results/2026-12-06-quality-table) measured them at 256²; at 512² the
# photon pass weighs less against the camera samples, so fewer samples per pixel win.
# Run from the repository root: BIN=target/release/chronolux REFS=... bash THIS
set -u
OUT=${OUT:-$(cd "$(dirname "$0")" && pwd)}
BIN=${BIN:?chronolux binary}
CM=${CM:-../shared/peers/cornell-moving.glb}
REFS=${REFS:?folder of frame_NNNN.exr 512x512 references}
{ date -u; uptime; lscpu | grep -E "Model name|^CPU\(s\)"; grep -o -w 'avx512[a-z_]*' /proc/cpuinfo | sort -u | tr '\n' ' '; echo; } > $OUT/machine.txt
q() { # name, then the method's arguments
  local name=$1; shift
  echo "== $name $(date -u +%T) $(uptime)" >> $OUT/log.txt
  $BIN bench quality $CM --frames 0..48 --measure 0..8,12,24,36,47 --reference $REFS --max-depth 8 \
    --resolution 512x512 --threads 2 --denoise --target-flip 0.04 "$@" --json > $OUT/$name.json 2> $OUT/$name.err
}
q st-spp1 --method spacetime-dept --set spp=1 --start-effort 32 --max-effort 256
q st-spp2 --method spacetime-dept --set spp=2 --start-effort 32 --max-effort 256
q st-spp4 --method spacetime-dept --set spp=4 --start-effort 128 --max-effort 256
q path --method path --start-effort 2 --max-effort 16
echo "== end $(date -u +%T) $(uptime)" >> $OUT/log.txt
