#!/bin/bash
# Interleaved A/B of two builds on stbpt's serving (cornell-moving 256², frames 0-23,
# N = 8, K = 8, 2 spp, OIDN off, 2 threads): CPU s of the run from bench quality's JSON.
# A B OUT ROUNDS
A=$1; B=$2; OUT=$3; R=${4:-3}
CM=/work/peers-run/cornell-moving.glb; REFS=/work/peers-run/refs-cm
for r in $(seq 1 $R); do
  for x in a b; do
    BIN=$A; [ $x = b ] && BIN=$B
    $BIN bench quality $CM --frames 0..24 --measure 0..8 --reference $REFS --max-depth 8 --threads 2 \
      --method stbpt --set window=8 --set interleave=8 --start-effort 2 --max-effort 2 --target-flip 0.08 \
      --json > $OUT/$x-$r.json 2> $OUT/$x-$r.err
    python3 -c "import json,sys;d=json.load(open('$OUT/$x-$r.json'));l=d['results'][0]['levels'][0];print('$x',$r,l['cpu_s'],l['wall_s'],l['flip_mean'],l['flicker'])"
  done
done
