#!/bin/bash
# A/B of two chronolux binaries, interleaved; CPU seconds from /usr/bin/time.
source /work/env.sh
A=$1; B=$2; OUT=$3; ROUNDS=${4:-2}
mkdir -p $OUT
for r in $(seq 1 $ROUNDS); do
 for tag in a b; do
  BIN=$A; [ $tag = b ] && BIN=$B
  /usr/bin/time -f "$tag r$r pt %U %S %e" $BIN bench pt /work/shared/peers/cornell-moving.glb --spp 16 --frames 0 --resolution 256x256 --max-depth 8 --threads 2 --rounds 1 --json > $OUT/pt_${tag}_$r.json 2>> $OUT/time.txt
  rm -rf $OUT/r_$tag; /usr/bin/time -f "$tag r$r default %U %S %e" $BIN render --frames 0..8 --resolution 256x256 --threads 2 --no-preview -o $OUT/r_$tag > /dev/null 2>> $OUT/time.txt
  /usr/bin/time -f "$tag r$r rays %U %S %e" $BIN bench rays builtin:demo --rounds 1 --json > $OUT/rays_${tag}_$r.json 2>> $OUT/time.txt
 done
done
grep -h "^[ab] r" $OUT/time.txt
