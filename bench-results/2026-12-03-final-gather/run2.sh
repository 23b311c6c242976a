#!/bin/bash
source /work/env.sh
BIN=/work/exp/native/chronolux-gather
CM=/work/peers-run/cornell-moving.glb; REFS=/work/peers-run/refs-cm
OUT=/work/exp/gather
q() { local name=$1; shift
  /usr/bin/time -f "%U %S %e" $BIN bench quality $CM --frames 0..8 --reference $REFS --max-depth 8 --threads 2 --denoise --target-flip 0.08 "$@" --json > $OUT/$name.json 2> $OUT/$name.err; }
q g8-32 --method spacetime-dept --set spp=8 --set gather=true --start-effort 32 --max-effort 32
q g8-64 --method spacetime-dept --set spp=8 --set gather=true --start-effort 64 --max-effort 64
q st8-256 --method spacetime-dept --set spp=8 --start-effort 256 --max-effort 256
