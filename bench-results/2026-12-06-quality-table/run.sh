#!/bin/bash
# The quality table (issue 37, item 2): time to FLIP of candidate effort settings for the
# three routes with a table (spacetime-dept, stbpt, path), every one denoised (OIDN high),
# on the peer protocol: cornell-moving's 48 frames rendered, 12 scored against Mitsuba's
# converged references (frames 0-7, 12, 24, 36, 47), --max-depth 8, 2 threads.
# Each `bench quality` doubles the effort key from --start-effort to --max-effort.
# Run from the repository root: BIN=target/release/chronolux REFS=... [RES=256] bash THIS
set -u
OUT=${OUT:-$(cd "$(dirname "$0")" && pwd)}
BIN=${BIN:?chronolux binary}
CM=${CM:-../shared/peers/cornell-moving.glb}
REFS=${REFS:?folder of frame_NNNN.exr references}
RES=${RES:-256}
{ date -u; uptime; lscpu | grep -E "Model name|^CPU\(s\)"; grep -o -w 'avx512[a-z_]*' /proc/cpuinfo | sort -u | tr '\n' ' '; echo; } > $OUT/machine-$RES.txt
q() { # name, then the method's arguments
  local name=$1; shift
  echo "== $name $(date -u +%T) $(uptime)" >> $OUT/log.txt
  $BIN bench quality $CM --frames 0..48 --measure 0..8,12,24,36,47 --reference $REFS --max-depth 8 \
    --resolution ${RES}x${RES} --threads 2 --denoise --target-flip 0.04 "$@" --json > $OUT/$name-$RES.json 2> $OUT/$name-$RES.err
}
if [ "${ONLY:-}" = "" ] || [ "${ONLY:-}" = "256" ]; then
q st-spp2 --method spacetime-dept --set spp=2 --start-effort 16 --max-effort 64
q st-spp4 --method spacetime-dept --set spp=4 --start-effort 32 --max-effort 256
q st-spp8 --method spacetime-dept --set spp=8 --start-effort 64 --max-effort 256
q st-spp16 --method spacetime-dept --set spp=16 --start-effort 100 --max-effort 100
q path --method path --start-effort 2 --max-effort 32
q stbpt --method stbpt --set window=8 --set interleave=8 --start-effort 1 --max-effort 8
fi
if [ "${ONLY:-}" = "512" ]; then
q st-spp4 --method spacetime-dept --set spp=4 --start-effort 32 --max-effort 128
q st-spp2 --method spacetime-dept --set spp=2 --start-effort 32 --max-effort 64
q path --method path --start-effort 2 --max-effort 8
fi
echo "== end $(date -u +%T) $(uptime)" >> $OUT/log.txt
