#!/bin/bash
# Issue 17 item 4 (no technique slower than frame-by-frame path on skinned characters and with
# a moving camera): spacetime-dept (--set spp=4) against path, one bench quality run each
# (spacetime-dept first, then path), build 2716f9b (ci profile).
cd "$(dirname "$0")"
B=/work/peers-run/chronolux-sliver
T=0.3,0.25,0.2,0.16,0.13,0.11,0.1,0.09,0.08
for sc in rigged dolly; do
  case $sc in
    rigged) S=/work/shared/scenes/RiggedSimple.glb; X="--stage cornell"; R=/work/refs-stbpt/ref-rigged-64b;;
    dolly) S=builtin:dolly; X=""; R=/work/refs/ref-dolly-64;;
  esac
  uptime > vp-$sc.uptime
  $B bench quality $S $X --method spacetime-dept --set spp=4 --reference $R --frames 0..8 --threads 1 \
    --target-flip $T --start-effort 2 --max-effort 128 --json > vp-$sc-st.json 2> vp-$sc-st.log
  $B bench quality $S $X --method path --reference $R --frames 0..8 --threads 1 \
    --target-flip $T --start-effort 1 --max-effort 64 --json > vp-$sc-path.json 2> vp-$sc-path.log
  uptime >> vp-$sc.uptime
done
