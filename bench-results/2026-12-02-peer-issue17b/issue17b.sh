#!/bin/bash
# Issue 17 goal 3, second run: the best of ours (stbpt + OIDN, window K = 2/4/8 at 1-2 spp)
# against Mitsuba 3 and Cycles + OIDN on cornell-moving frames 0-7, 256x256, one run.
set -u
# OUT (results folder) and BIN (ours, built with --features oidn) can be given; the
# defaults are this run's. The third run (../2026-12-02-peer-issue17c) sets both.
OUT=${OUT:-/work/peers-run/results-issue17b}
BIN=${BIN:-/work/peers-run/chronolux-oidn}
# (unset for Blender: pyoidn's libur_loader breaks bpy's libsycl; the first Cycles call failed on it and was re-run with env -u at 09:55)
export LD_LIBRARY_PATH=/work/ci-clone2/.venv-oidn/lib/python3.11/site-packages/pyoidn/oidn/lib
{ date -u; uptime; lscpu | grep -E "Model name|^CPU\(s\)|Flags" | cut -c1-400; grep -o -w 'avx512[a-z_]*' /proc/cpuinfo | sort -u | tr '\n' ' '; echo; } > $OUT/machine.txt
ours() {
  for w in 2 4 8; do
    $BIN bench quality /work/peers-run/cornell-moving.glb --frames 0..8 --reference /work/peers-run/refs \
      --max-depth 8 --threads 2 --method stbpt --set window=$w --denoise --target-flip 0.08 \
      --start-effort 1 --max-effort 2 --json > $OUT/ours-$1-w$w.json 2> $OUT/ours-$1-w$w.err
  done
  $BIN bench quality /work/peers-run/cornell-moving.glb --frames 0..8 --reference /work/peers-run/refs \
    --max-depth 8 --threads 2 --method path --denoise --target-flip 0.08 \
    --start-effort 2 --max-effort 16 --json > $OUT/ours-$1-path.json 2> $OUT/ours-$1-path.err
  echo "== ours $1 end $(date -u) $(uptime)" >> $OUT/log.txt
}
echo "== start $(date -u) $(uptime)" >> $OUT/log.txt
ours a
(cd /work/peers-run/harness && DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so /work/.venv-peers/bin/python mitsuba_time_to_flip.py --levels 16,32,64,128 --targets 0.10,0.08 --threads 2 > $OUT/mitsuba.json 2> $OUT/mitsuba.err)
echo "== mitsuba end $(date -u) $(uptime)" >> $OUT/log.txt
(cd /work/peers-run/harness && env -u LD_LIBRARY_PATH /work/.venv-peers/bin/python cycles_time_to_flip.py --denoise --levels 4,8,16 --targets 0.08 > $OUT/cycles.json 2> $OUT/cycles.err)
echo "== cycles end $(date -u) $(uptime)" >> $OUT/log.txt
ours b
