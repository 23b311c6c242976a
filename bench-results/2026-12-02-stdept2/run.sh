#!/bin/bash
# Build 30ed2b9 (ci profile): cargo build --profile ci -p chronolux
B=/tmp/chronolux-stdept2-30ed2b9
cd "$(dirname "$0")"
for sc in demo cm rigged; do
  case $sc in
    demo) S=builtin:demo; X=""; R=/work/refs/ref-demo-64-0to8;;
    cm) S=/work/shared/peers/cornell-moving.glb; X=""; R=/work/refs-stbpt/ref-cm-64;;
    rigged) S=/work/shared/scenes/RiggedSimple.glb; X="--stage cornell"; R=/work/refs-stbpt/ref-rigged-64;;
  esac
  uptime > $sc.uptime
  $B bench quality $S $X --method spacetime-dept --set spp=4 --baseline dept-spatial --reference $R \
    --frames 0..8 --target-flip 0.2,0.15,0.12,0.1,0.09 --start-effort 2 --max-effort 128 --threads 1 --json --report $sc.md > $sc.json 2> $sc.log
  uptime >> $sc.uptime
done
