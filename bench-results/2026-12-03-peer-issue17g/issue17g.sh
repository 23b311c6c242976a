#!/bin/bash
# Issue 17 goal 3, seventh run: the sixth run's script unchanged, ours built for x86-64-v3
# (.cargo/config.toml). The sixth run's header: on a new machine type (Intel Xeon with AVX-512; the earlier
# runs: AMD EPYC, AVX2): the fifth run's stbpt + OIDN configurations (interleave 2, 1 spp,
# K 4 and 8; interleave 8, K 8, 3 and 4 spp), our path + OIDN, and spacetime-dept + OIDN
# with the automatic element count (4 spp, 256k and 512k photons per frame), against
# Mitsuba 3 and Cycles + OIDN
# on cornell-moving frames 0-7, 256x256, one run (ours before and after the peers).
# OUT: results folder (default: this script's); BIN: chronolux built with --features oidn.
set -u
OUT=${OUT:-$(cd "$(dirname "$0")" && pwd)}
BIN=${BIN:?chronolux binary built with --features oidn}
H=${HARNESS:-/work/peers-run/harness}
CM=${CM:-/work/peers-run/cornell-moving.glb}
REFS=${REFS:-/work/peers-run/refs-cm}
export LD_LIBRARY_PATH=${OIDN_LIB:-/work/.venv-oidn/lib/python3.11/site-packages/pyoidn/oidn/lib}
{ date -u; uptime; lscpu | grep -E "Model name|^CPU\(s\)|Flags" | cut -c1-400; grep -o -w 'avx512[a-z_]*' /proc/cpuinfo | sort -u | tr '\n' ' '; echo; } > $OUT/machine.txt
q() { # name, then the method's arguments
  local name=$1; shift
  $BIN bench quality $CM --frames 0..8 --reference $REFS --max-depth 8 --threads 2 --denoise \
    --target-flip 0.08 "$@" --json > $OUT/$name.json 2> $OUT/$name.err
}
ours() {
  q ours-$1-il2-k4 --method stbpt --set window=4 --set interleave=2 --start-effort 1 --max-effort 1
  q ours-$1-il2-k8 --method stbpt --set window=8 --set interleave=2 --start-effort 1 --max-effort 1
  q ours-$1-il8-e3 --method stbpt --set window=8 --set interleave=8 --start-effort 3 --max-effort 3
  q ours-$1-il8-e4 --method stbpt --set window=8 --set interleave=8 --start-effort 4 --max-effort 4
  q ours-$1-st256 --method spacetime-dept --set spp=4 --start-effort 256 --max-effort 256
  q ours-$1-st512 --method spacetime-dept --set spp=4 --start-effort 512 --max-effort 512
  q ours-$1-path --method path --start-effort 4 --max-effort 8
  echo "== ours $1 end $(date -u) $(uptime)" >> $OUT/log.txt
}
echo "== start $(date -u) $(uptime)" >> $OUT/log.txt
ours a
(cd $H && DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so /work/.venv-peers/bin/python mitsuba_time_to_flip.py --levels 16,32,64,128 --targets 0.10,0.08 --threads 2 > $OUT/mitsuba.json 2> $OUT/mitsuba.err)
echo "== mitsuba end $(date -u) $(uptime)" >> $OUT/log.txt
(cd $H && env -u LD_LIBRARY_PATH /work/.venv-peers/bin/python cycles_time_to_flip.py --denoise --levels 4,8,16 --targets 0.08 > $OUT/cycles.json 2> $OUT/cycles.err)
echo "== cycles end $(date -u) $(uptime)" >> $OUT/log.txt
ours b
