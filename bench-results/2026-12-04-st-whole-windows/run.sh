#!/bin/bash
# Issue 17, goal 2: spacetime-dept against dept-spatial at equal FLIP, both at their defaults
# (16 camera samples, automatic elements), --max-depth 8 (both honour it since a3c97e2),
# with WHOLE temporal windows: frames 0..24 rendered, 8..16 scored (spacetime-dept's
# window and light history are 8 frames on each side). One `bench quality` run per scene,
# `--baseline dept-spatial`, so both are measured in one run. dept-spatial is frame by
# frame, so bench quality renders only its scored frames; spacetime-dept renders all 24,
# and summarize.py takes its CPU per scored frame as (CPU of the run) x 8 / 24.
# References: refs.sh (chronolux reference, frames 8..16, 64x64, max depth 8).
cd "$(dirname "$0")"
B=${B:?chronolux binary}
R=${REFS:?folder with demo/ dolly/ rigged/}
T=0.3,0.25,0.2,0.16,0.13,0.11,0.1,0.09,0.08,0.07,0.06
for sc in demo dolly rigged cm; do
  case $sc in
    demo) S=(builtin:demo);;
    dolly) S=(builtin:dolly);;
    rigged) S=(../../../shared/scenes/RiggedSimple.glb --stage cornell);;
    cm) S=(../../../shared/peers/cornell-moving.glb);;
  esac
  echo "== $sc start $(date -u) $(uptime)" >> log.txt
  $B bench quality "${S[@]}" --resolution 64x64 --max-depth 8 --method spacetime-dept \
    --baseline dept-spatial --reference $R/$sc --frames 0..24 --measure 8..16 --threads 1 \
    --target-flip $T --start-effort 2 --max-effort 2048 --json > $sc.json 2> $sc.err
done
echo "== end $(date -u) $(uptime)" >> log.txt
