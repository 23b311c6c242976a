#!/bin/sh
# stbpt (defaults: cap K = 4, adaptive) against bdpt after the sample-stream change, one
# `bench quality` run per scene (as bench-results/2026-12-02-stbpt2/run.sh's first line),
# 64x64, frames 0-7, --threads 1. BIN: chronolux (ci profile). Ratios:
#   python3 ../../2026-12-02-stbpt/ratios.py cm demo dolly rigged   (in this folder)
set -u
T=0.3,0.25,0.2,0.16,0.13,0.11,0.1,0.09,0.08,0.07,0.06
C="--frames 0..8 --target-flip $T --threads 1 --json --max-effort 16"
SH=${SHARED:-../../../../shared}
q() { name=$1; scene=$2; ref=$3; shift 3
  uptime > $name.uptime
  $BIN bench quality $scene "$@" --method stbpt --baseline bdpt --reference $ref $C \
    --report $name-stbpt.md > $name-stbpt.json 2> $name-stbpt.log
  uptime >> $name.uptime
}
q cm $SH/peers/cornell-moving.glb /work/refs-stbpt/ref-cm-64b
q demo builtin:demo /work/refs-stbpt/ref-demo-64
q dolly builtin:dolly /work/refs/ref-dolly-64
q rigged $SH/scenes/RiggedSimple.glb /work/refs-stbpt/ref-rigged-64b --stage cornell
