#!/bin/bash
# Issue 17 with WHOLE temporal windows and --max-depth 8, both methods at their defaults, 64²,
# one `bench quality` run per scene with a baseline, so both are measured in one run; 8..16
# scored, CPU per scored frame (bench quality's: a run's CPU x scored / rendered frames; a
# frame-by-frame baseline renders only the scored frames). References: refs.sh (frames 8..16).
#   run.sh        spacetime-dept against dept-spatial, frames 0..24 rendered (its window and
#                 light history are 8 frames on each side), efforts 2k..2048k photons per frame
#                 -> SCENE.json, SCENE.err, log.txt (the first run, capped at 512k: first-512/)
#   run.sh stbpt  stbpt against bdpt, frames 4..20 rendered (K is at most 4), 1..64 spp
#                 -> stbpt-SCENE.json, stbpt-SCENE.err, log-stbpt.txt
cd "$(dirname "$0")"
B=${B:?chronolux binary}
R=${REFS:?folder with demo/ dolly/ rigged/ cm/}
T=0.3,0.25,0.2,0.16,0.13,0.11,0.1,0.09,0.08,0.07,0.06
if [ "${1:-}" = stbpt ]; then
  P=stbpt- LOG=log-stbpt.txt
  M=(--method stbpt --baseline bdpt --frames 4..20 --start-effort 1 --max-effort 64)
else
  P= LOG=log.txt
  M=(--method spacetime-dept --baseline dept-spatial --frames 0..24 --start-effort 2 --max-effort 2048)
fi
for sc in demo dolly rigged cm; do
  case $sc in
    demo) S=(builtin:demo);;
    dolly) S=(builtin:dolly);;
    rigged) S=(../../../shared/scenes/RiggedSimple.glb --stage cornell);;
    cm) S=(../../../shared/peers/cornell-moving.glb);;
  esac
  echo "== $sc start $(date -u) $(uptime)" >> $LOG
  $B bench quality "${S[@]}" --resolution 64x64 --max-depth 8 "${M[@]}" --reference $R/$sc \
    --measure 8..16 --threads 1 --target-flip $T --json > $P$sc.json 2> $P$sc.err
done
echo "== end $(date -u) $(uptime)" >> $LOG
