#!/bin/bash
# Issue 37, item 5: the default route against path + OIDN, Cycles + OIDN and Mitsuba 3 in
# ONE run, at 256² and at 512², the tenth-run protocol: cornell-moving's 48 frames rendered
# (a frame-by-frame method renders only the scored ones), 12 scored (0-7, 12, 24, 36, 47)
# against Mitsuba's converged references of that resolution, --max-depth 8, 2 threads,
# CPU seconds per 12 scored frames (a quarter of the 48 frames' CPU).
# Ours, twice:
#  - literal: the command a user types, `render cornell-moving.glb --frames 0..48
#    --max-depth 8 --resolution RxR` (the registry's default route at --quality preview
#    for that pixel count, OIDN as the build found it, EXR + PNG + preview written),
#    CPU from /usr/bin/time, scored by score.py (the harness's FLIP and flicker);
#  - `bench quality` along the same route's photon axis, so 0.08 is bracketed and the
#    CPU to exactly 0.08 is interpolated (log-log) as for the peers.
# path + OIDN by `bench quality`; the peers by ../shared/peers/harness (copied to $H).
# Run from the repository root:
#   BIN=target/release/chronolux REFS256=... REFS512=... H=/work/peers-run/harness bash THIS
set -u
HERE=$(cd "$(dirname "$0")" && pwd)
OUT=${OUT:-$HERE}
BIN=${BIN:?chronolux binary (the default build: OIDN fetched by build.rs)}
H=${H:?a writable copy of ../shared/peers (its harness/ folder)}
CM=${CM:-$H/../cornell-moving.glb}
FL=0,1,2,3,4,5,6,7,12,24,36,47
PY=${PY:-/work/.venv-peers/bin/python}
{ date -u; git rev-parse HEAD; git status --short | head; uptime; lscpu | grep -E "Model name|^CPU\(s\)|Flags" | cut -c1-400; echo "avx512: $(grep -o -w 'avx512[a-z_]*' /proc/cpuinfo | sort -u | tr '\n' ' ')"; } > $OUT/machine.txt
q() { # name, resolution, refs, then the method's arguments
  local name=$1 res=$2 refs=$3; shift 3
  echo "== $name-$res $(date -u +%T) $(uptime)" >> $OUT/log.txt
  $BIN bench quality $CM --frames 0..48 --measure 0..8,12,24,36,47 --reference $refs --max-depth 8 \
    --resolution ${res}x${res} --threads 2 --denoise --target-flip 0.08 "$@" --json > $OUT/$name-$res.json 2> $OUT/$name-$res.err
}
literal() { # resolution, mitsuba reference folder
  local res=$1 dir=/tmp/chronolux-literal-$1
  echo "== literal-$res $(date -u +%T) $(uptime)" >> $OUT/log.txt
  rm -rf $dir
  /usr/bin/time -f "wall_s %e user_s %U sys_s %S" -o $OUT/literal-$res.time \
    $BIN render $CM --frames 0..48 --max-depth 8 --resolution ${res}x${res} -o $dir > $OUT/literal-$res.log 2>&1
  cp $dir/run.json $OUT/literal-$res.run.json
  $PY $HERE/../2026-12-07-literal/score.py $dir $2 > $OUT/literal-$res.score || $PY $HERE/../../2026-12-07-literal/score.py $dir $2 > $OUT/literal-$res.score
}
peers() { # resolution, mitsuba levels, cycles levels
  local res=$1
  echo "== mitsuba-$res $(date -u +%T) $(uptime)" >> $OUT/log.txt
  (cd $H && PEER_RES=$res DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so $PY mitsuba_time_to_flip.py --frame-list $FL --levels $2 --targets 0.10,0.08 --threads 2 > $OUT/mitsuba-$res.json 2> $OUT/mitsuba-$res.err)
  echo "== cycles-$res $(date -u +%T) $(uptime)" >> $OUT/log.txt
  (cd $H && PEER_RES=$res $PY cycles_time_to_flip.py --frame-list $FL --denoise --levels $3 --targets 0.08 > $OUT/cycles-$res.json 2> $OUT/cycles-$res.err)
}
echo "== start $(date -u +%T) $(uptime)" >> $OUT/log.txt
if [ -n "${CONFIRM256:-}" ]; then
  # 2026-12-07 on Embree: the user's command at 256² with the peers (OUT=.../at-256).
  literal 256 ${REFS256M:-$H/../mitsuba-refs}
  peers 256 32,64,128 4,8,16
  echo "== end $(date -u +%T) $(uptime)" >> $OUT/log.txt
  exit 0
fi
if [ -n "${CONFIRM512:-}" ]; then
  # The second run (OUT=.../confirm-512): the user's command at 512² once its table entry
  # became spp 4 + 64k (what bench quality's 64k level measured in the first run), with
  # the peers again, so its ratio is also one run's.
  literal 512 ${REFS512M:-$H/../mitsuba-refs-512}
  peers 512 64,128 2,4,8
  echo "== end $(date -u +%T) $(uptime)" >> $OUT/log.txt
  exit 0
fi
# The route render takes at each size (the registry's preview entries): spp 4, OIDN fast.
literal 256 ${REFS256M:-$H/../mitsuba-refs}
q default 256 $REFS256 --method spacetime-dept --set spp=4 --denoise-quality fast --start-effort 32 --max-effort 128
q path 256 $REFS256 --method path --start-effort 4 --max-effort 8
peers 256 32,64,128 4,8,16
literal 512 ${REFS512M:-$H/../mitsuba-refs-512}
q default 512 $REFS512 --method spacetime-dept --set spp=4 --denoise-quality fast --start-effort 32 --max-effort 128
q path 512 $REFS512 --method path --start-effort 2 --max-effort 8
peers 512 64,128 2,4,8
echo "== end $(date -u +%T) $(uptime)" >> $OUT/log.txt
