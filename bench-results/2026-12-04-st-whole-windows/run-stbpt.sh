#!/bin/bash
# Issue 17, goal 1 with whole windows: stbpt against frame-by-frame bdpt at equal FLIP, both at
# their defaults, --max-depth 8, frames 4..20 rendered and 8..16 scored (stbpt's window is at
# most K = 4 frames on each side), the references of run.sh (frames 8..16). One
# `bench quality` run per scene with --baseline bdpt; CPU per scored frame (bench quality's).
cd "$(dirname "$0")"
B=${B:?chronolux binary}
R=${REFS:?folder with demo/ dolly/ rigged/ cm/}
T=0.3,0.25,0.2,0.16,0.13,0.11,0.1,0.09,0.08,0.07,0.06
for sc in demo dolly rigged cm; do
  case $sc in
    demo) S=(builtin:demo);;
    dolly) S=(builtin:dolly);;
    rigged) S=(../../../shared/scenes/RiggedSimple.glb --stage cornell);;
    cm) S=(../../../shared/peers/cornell-moving.glb);;
  esac
  echo "== $sc start $(date -u) $(uptime)" >> log-stbpt.txt
  $B bench quality "${S[@]}" --resolution 64x64 --max-depth 8 --method stbpt \
    --baseline bdpt --reference $R/$sc --frames 4..20 --measure 8..16 --threads 1 \
    --target-flip $T --start-effort 1 --max-effort 64 --json > stbpt-$sc.json 2> stbpt-$sc.err
done
echo "== end $(date -u) $(uptime)" >> log-stbpt.txt
