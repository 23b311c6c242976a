#!/bin/bash
# Issue 17 goal 3: best of ours (stbpt, the default) vs Mitsuba 3 on cornell-moving 0-7, one run.
set -u
OUT=/work/peers-run/results-issue17
BIN=/work/peers-run/chronolux17
{ date -u; uptime; lscpu | grep -E "Model name|^CPU\(s\)"; grep -o -w 'avx512[a-z_]*' /proc/cpuinfo | sort -u | tr '\n' ' '; echo; } > $OUT/machine.txt
echo "== mitsuba start $(date -u) $(uptime)" >> $OUT/log.txt
(cd /work/peers-run/harness && DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so /work/.venv-peers/bin/python mitsuba_time_to_flip.py --levels 16,32,64,128 --targets 0.10,0.08 --threads 2 > $OUT/mitsuba.json 2> $OUT/mitsuba.err)
echo "== mitsuba end $(date -u) $(uptime)" >> $OUT/log.txt
$BIN bench quality /work/peers-run/cornell-moving.glb --frames 0..8 --reference /work/peers-run/refs \
  --max-depth 8 --threads 2 --method stbpt --target-flip 0.10,0.08 \
  --start-effort 2 --max-effort 32 --report $OUT/ours.md --json > $OUT/ours.json 2> $OUT/ours.err
echo "== ours end $(date -u) $(uptime)" >> $OUT/log.txt
