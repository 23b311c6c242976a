#!/bin/bash
# Issue 37: the denoiser is most of the default route's CPU (OIDN `high` costs 7.7 µs of CPU
# per pixel on this EPYC: 0.5 s per 256² frame, 2 s per 512² frame, against 2.1 CPU s per
# 512² frame in all). Does OIDN's `fast` network reach each level's error for less CPU?
# The tenth-run protocol (cornell-moving, 48 rendered, 12 scored against Mitsuba's
# references of that size, --max-depth 8, 2 threads, CPU s per 12 scored frames), every
# level swept (--target-flip 0.04 keeps the doubling going to --max-effort).
# Run from the repository root: BIN=... REFS256=... REFS512=... CM=... bash THIS
set -u
OUT=${OUT:-$(cd "$(dirname "$0")" && pwd)}
BIN=${BIN:?}; CM=${CM:?cornell-moving.glb}
{ date -u; uptime; lscpu | grep -E "Model name|^CPU\(s\)"; grep -o -w 'avx[0-9a-z_]*' /proc/cpuinfo | sort -u | tr '\n' ' '; echo; } > $OUT/machine.txt
q() { # name, resolution, refs, then the method's arguments
  local name=$1 res=$2 refs=$3; shift 3
  echo "== $name-$res $(date -u +%T) $(uptime)" >> $OUT/log.txt
  $BIN bench quality $CM --frames 0..48 --measure 0..8,12,24,36,47 --reference $refs --max-depth 8 \
    --resolution ${res}x${res} --threads 2 --denoise --target-flip 0.04 "$@" --json > $OUT/$name-$res.json 2> $OUT/$name-$res.err
}
R=${ONLY-256 512}
for res in $R; do
  refs=$REFS256; [ $res = 512 ] && refs=$REFS512
  q st-spp2-fast $res $refs --method spacetime-dept --set spp=2 --denoise-quality fast --start-effort 32 --max-effort 256
  q st-spp4-fast $res $refs --method spacetime-dept --set spp=4 --denoise-quality fast --start-effort 64 --max-effort 256
  q path-fast $res $refs --method path --denoise-quality fast --start-effort 4 --max-effort 16
done
echo "== end $(date -u +%T)" >> $OUT/log.txt
# Added after the above (same session, right after): spp 3 at 512², between spp 2's
# flicker (0.0161, just over half Cycles') and spp 4's cost.
if [ -n "${SPP3:-}" ]; then
  q st-spp3-fast 512 $REFS512 --method spacetime-dept --set spp=3 --denoise-quality fast --start-effort 64 --max-effort 256
fi
