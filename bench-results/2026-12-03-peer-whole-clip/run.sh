#!/bin/bash
# Issue 17 goal 3 over the whole animation: cornell-moving's 48 frames rendered, scored on
# every frame that has a Mitsuba reference (0-7, 12, 24, 36, 47: the start, the middle with
# whole windows, the end), the peers rendering and scoring the same 12 frames
# (harness copies with --frame-list: harness-fl.patch). Ours: CPU of the whole run (48
# frames; a frame-by-frame method renders only the scored 12), compared per frame.
# OUT: results folder (default: this script's); BIN: chronolux built with --features oidn.
set -u
OUT=${OUT:-$(cd "$(dirname "$0")" && pwd)}
BIN=${BIN:?chronolux binary built with --features oidn}
H=${HARNESS:-/work/peers-run/harness-fl}
CM=${CM:-/work/peers-run/cornell-moving.glb}
REFS=${REFS:-/work/peers-run/refs-cm48}
FL=0,1,2,3,4,5,6,7,12,24,36,47
export LD_LIBRARY_PATH=${OIDN_LIB:-/work/.venv-oidn/lib/python3.11/site-packages/pyoidn/oidn/lib}
{ date -u; uptime; lscpu | grep -E "Model name|^CPU\(s\)|Flags" | cut -c1-400; grep -o -w 'avx512[a-z_]*' /proc/cpuinfo | sort -u | tr '\n' ' '; echo; } > $OUT/machine.txt
q() { # name, then the method's arguments
  local name=$1; shift
  $BIN bench quality $CM --frames 0..48 --measure 0..8,12,24,36,47 --reference $REFS --max-depth 8 \
    --threads 2 --denoise --target-flip 0.08 "$@" --json > $OUT/$name.json 2> $OUT/$name.err
}
ours() {
  q ours-$1-path --method path --start-effort 4 --max-effort 8
  q ours-$1-il2-k8 --method stbpt --set window=8 --set interleave=2 --start-effort 1 --max-effort 2
  q ours-$1-il8-k8 --method stbpt --set window=8 --set interleave=8 --start-effort 1 --max-effort 4
  q ours-$1-il16-k8 --method stbpt --set window=8 --set interleave=16 --start-effort 2 --max-effort 8
  q ours-$1-st --method spacetime-dept --set spp=4 --start-effort 128 --max-effort 512
  echo "== ours $1 end $(date -u) $(uptime)" >> $OUT/log.txt
}
# OURS=FILE: a file that redefines ours() (a later run's configurations, same protocol).
if [ -n "${OURS:-}" ]; then . "$OURS"; fi
echo "== start $(date -u) $(uptime)" >> $OUT/log.txt
ours a
(cd $H && DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so /work/.venv-peers/bin/python mitsuba_time_to_flip.py --frame-list $FL --levels 32,64,128 --targets 0.10,0.08 --threads 2 > $OUT/mitsuba.json 2> $OUT/mitsuba.err)
echo "== mitsuba end $(date -u) $(uptime)" >> $OUT/log.txt
(cd $H && env -u LD_LIBRARY_PATH /work/.venv-peers/bin/python cycles_time_to_flip.py --frame-list $FL --denoise --levels 4,8,16 --targets 0.08 > $OUT/cycles.json 2> $OUT/cycles.err)
echo "== cycles end $(date -u) $(uptime)" >> $OUT/log.txt
ours b
