#!/usr/bin/env bash
# Exploration behind the tnear change: Embree 4.4 (the embreex wheel's, as chronolux loads
# it) and Mitsuba's own Embree 3.13.4 (mitsuba::rtc*, in its wheel) called from C on the
# same dumped rays and the same 42 world-space triangles (frame 0 of cornell-moving), one
# thread, thread CPU time, best of 5 passes over 1M rays. eb.c is the program.
#   explore/run.sh OUT   (tris.bin: dump_tris.py; OUT/rays: chronolux bench rays --dump-rays OUT/rays)
set -euo pipefail
HERE=$(cd "$(dirname "$0")" && pwd)
OUT=${1:?OUT}
E4=${E4:-/root/.cache/chronolux/embree-4.4.0/lib/libembree4-4aef3270.so.4}
E3=${E3:-/work/.venv-peers/lib/python3.11/site-packages/mitsuba/libembree3.so}
gcc -O2 -march=native -o "$OUT/eb" "$HERE/eb.c" -ldl
gcc -DE3 -O2 -march=native -o "$OUT/eb3" "$HERE/eb.c" -ldl
# Arguments: LIB TRIS RAYS DEVICE_CONFIG QUALITY(1 medium, 2 high) GEOMETRIES SCENE_FLAGS FTZ ARGS KINDS...
# ARGS: 0 = NULL, 2 = RTCOccludedArguments/RTCIntersectArguments with feature_mask TRIANGLE,
# 3 = the same with RTC_RAY_QUERY_FLAG_COHERENT. Kinds: o = occluded, i = intersect,
# 1/4/8/16 = rays per call, 16s = packets of 16 from rays grouped by direction octant.
for round in 1 2 3; do
  for set in box hemi; do
    R=$OUT/rays/cornell-moving_$set.rays
    echo "== round $round $set"
    for tn in 1.17549435e-38 0; do
      for ftz in 0 1; do
        TNEAR=$tn "$OUT/eb" "$E4" "$HERE/tris.bin" "$R" "" 1 2 0 $ftz 0 o1 o16 i1 i16 | sed "s/^/E4 tnear=$tn /"
      done
    done
    TNEAR=0 "$OUT/eb" "$E4" "$HERE/tris.bin" "$R" "" 2 2 0 0 0 o1 o16 i1 i16 | sed "s/^/E4 tnear=0 /"
    TNEAR=0 "$OUT/eb" "$E4" "$HERE/tris.bin" "$R" "" 1 2 4 0 0 o1 i1 | sed "s/^/E4 tnear=0 robust /"
    TNEAR=0 "$OUT/eb" "$E4" "$HERE/tris.bin" "$R" "" 1 2 0 0 2 o1 o16 i1 i16 | sed "s/^/E4 tnear=0 /"
    TNEAR=0 "$OUT/eb" "$E4" "$HERE/tris.bin" "$R" "" 1 2 0 0 3 o16 o16s i16 i16s | sed "s/^/E4 tnear=0 /"
    TNEAR=0 "$OUT/eb" "$E4" "$HERE/tris.bin" "$R" "" 1 2 0 0 0 o4 o8 o16s i16s | sed "s/^/E4 tnear=0 /"
    TNEAR=0 "$OUT/eb" "$E4" "$HERE/tris.bin" "$R" "frequency_level=simd512" 1 2 0 0 0 o1 o16 i1 i16 | sed "s/^/E4 tnear=0 /"
    TNEAR=0 "$OUT/eb" "$E4" "$HERE/tris.bin" "$R" "tri_accel=bvh4.triangle4" 1 2 0 0 0 o1 o16 i1 i16 | sed "s/^/E4 tnear=0 /"
    for tn in 1.17549435e-38 0; do
      TNEAR=$tn "$OUT/eb3" "$E3" "$HERE/tris.bin" "$R" "" 2 2 0 0 0 o1 o16 i1 i16 | sed "s/^/E3 tnear=$tn /"
    done
  done
done
