#!/bin/bash
# A/B: OIDN filter created per frame (A) against one filter kept across frames (B).
# Interleaved rounds of the same render with --denoise; CPU s (user + sys) per run, and
# whether the frames are bit-identical. Usage: A=bin B=bin keep-filter.sh ROUNDS > out.txt
# A: main at 9d91885; B: the same with the oidn::Device leaked once and one
# oidn::RayTracing kept in the static beside it (image_dimensions and albedo_normal per
# frame), not committed: no difference beyond the rounds' spread (keep-filter.txt).
set -eu
CM=${CM:-../shared/peers/cornell-moving.glb}
T=$(mktemp -d)
run() { /usr/bin/time -f "%U %S" -o $T/t "$1" render "$CM" --method stbpt --set window=8 \
  --set interleave=8 --spp 2 --frames 0..24 --resolution 256x256 --max-depth 8 --threads 2 \
  --no-preview --denoise --output "$2" > /dev/null 2>&1; awk '{printf "%.2f", $1 + $2}' $T/t; }
for r in $(seq 1 "${1:-3}"); do
  a=$(run "$A" $T/a); b=$(run "$B" $T/b)
  same=$(for f in $T/a/*.exr; do cmp -s "$f" "$T/b/$(basename "$f")" || echo differ; done | sort -u)
  echo "round $r: A $a CPU s, B $b CPU s, frames ${same:-bit-identical}"
done
