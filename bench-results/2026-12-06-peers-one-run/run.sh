#!/bin/bash
# Issue 37, item 5: the default route against path + OIDN, Cycles + OIDN and Mitsuba 3 in
# ONE run, at 256² and at 512², the tenth-run protocol: cornell-moving's 48 frames rendered
# (a frame-by-frame method renders only the scored ones), 12 scored (0-7, 12, 24, 36, 47)
# against Mitsuba's converged references of that resolution, --max-depth 8, 2 threads,
# CPU seconds per 12 scored frames interpolated (log-log) to mean HDR-FLIP 0.08.
# Ours: `bench quality` with the default route's own settings at the middle level
# (render's `--quality preview` for that resolution: the registry's table) and the photon
# count halved and doubled around it, so 0.08 is bracketed; path + OIDN the same way.
# Peers: ../shared/peers/harness (copied to $H, writable), PEER_RES selecting the size.
# Run from the repository root:
#   BIN=target/release/chronolux REFS256=... REFS512=... H=/work/peers-run/harness bash THIS
set -u
OUT=${OUT:-$(cd "$(dirname "$0")" && pwd)}
BIN=${BIN:?chronolux binary (the default build: OIDN fetched by build.rs)}
H=${H:?a writable copy of ../shared/peers (its harness/ folder)}
CM=${CM:-$H/../cornell-moving.glb}
FL=0,1,2,3,4,5,6,7,12,24,36,47
PY=${PY:-/work/.venv-peers/bin/python}
{ date -u; uptime; lscpu | grep -E "Model name|^CPU\(s\)|Flags" | cut -c1-400; grep -o -w 'avx512[a-z_]*' /proc/cpuinfo | sort -u | tr '\n' ' '; echo; } > $OUT/machine.txt
q() { # name, resolution, refs, then the method's arguments
  local name=$1 res=$2 refs=$3; shift 3
  echo "== $name-$res $(date -u +%T) $(uptime)" >> $OUT/log.txt
  $BIN bench quality $CM --frames 0..48 --measure 0..8,12,24,36,47 --reference $refs --max-depth 8 \
    --resolution ${res}x${res} --threads 2 --denoise --target-flip 0.08 "$@" --json > $OUT/$name-$res.json 2> $OUT/$name-$res.err
}
peers() { # resolution, mitsuba levels, cycles levels
  local res=$1
  echo "== mitsuba-$res $(date -u +%T) $(uptime)" >> $OUT/log.txt
  (cd $H && PEER_RES=$res DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so $PY mitsuba_time_to_flip.py --frame-list $FL --levels $2 --targets 0.10,0.08 --threads 2 > $OUT/mitsuba-$res.json 2> $OUT/mitsuba-$res.err)
  echo "== cycles-$res $(date -u +%T) $(uptime)" >> $OUT/log.txt
  (cd $H && PEER_RES=$res $PY cycles_time_to_flip.py --frame-list $FL --denoise --levels $3 --targets 0.08 > $OUT/cycles-$res.json 2> $OUT/cycles-$res.err)
}
echo "== start $(date -u +%T) $(uptime)" >> $OUT/log.txt
# 256²: the table's preview level is spp 4 + 64k photons.
q default 256 $REFS256 --method spacetime-dept --set spp=4 --start-effort 32 --max-effort 128
q path 256 $REFS256 --method path --start-effort 4 --max-effort 8
peers 256 32,64,128 4,8,16
# 512²: the table's preview level for 512² (ST512 below, from the 512² sweep).
q default 512 $REFS512 --method spacetime-dept ${ST512:?--set ... of the 512² preview level} 
q path 512 $REFS512 --method path --start-effort 2 --max-effort 8
peers 512 64,128 2,4,8
echo "== end $(date -u +%T) $(uptime)" >> $OUT/log.txt
