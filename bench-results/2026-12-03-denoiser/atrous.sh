#!/bin/bash
# Feasibility check: an edge-avoiding a-trous filter (atrous.py) on stbpt's noisy frames
# against Open Image Denoise on the same frames, HDR-FLIP against the Mitsuba references.
# BIN: chronolux built with --features oidn; PY: python with numpy and OpenEXR;
# REFS: the Mitsuba references linked as frame_NNNN.exr; W: a scratch folder.
set -eu
D=$(cd "$(dirname "$0")" && pwd)
FL=0,1,2,3,4,5,6,7,12
cd "$W"
$BIN render ${CM:-$D/../../../shared/peers/cornell-moving.glb} --method stbpt --set window=8 --set interleave=8 \
  --spp 2 --frames 0..24 --resolution 256x256 --max-depth 8 --threads 2 --no-preview --denoise \
  --passes albedo,normal,depth --output out-d2
mkdir -p oidn noisy
$PY $D/split.py out-d2 RGB oidn $FL
$PY $D/split.py out-d2 "ViewLayer.Noisy Image" noisy $FL
for d in noisy oidn; do echo "$d: $($BIN compare $d $REFS | tail -1)"; done
# sigma_normal sigma_depth sigma_luminance (0: no luminance stop) iterations
for cfg in "128 1 4 5" "128 1 16 5" "128 1 0 5" "64 0.5 0 4"; do
  d=at-$(echo $cfg | tr ' ' _); mkdir -p $d
  $PY $D/atrous.py out-d2 $d $FL $cfg
  echo "a-trous $cfg: $($BIN compare $d $REFS | tail -1)"
done
