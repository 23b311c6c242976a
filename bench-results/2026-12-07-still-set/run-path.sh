#!/bin/bash
# The same fly-through, frame-by-frame `path` + OIDN at its default quality (the quality
# table's spp), scored as run.sh scores, for "never slower than our own path + denoiser".
set -e
B=${B:-chronolux}
REF=${REF:-ref-fly128}
OUT=${OUT:-out}
mkdir -p "$OUT"
for spp in 8 16 32; do
  d="$OUT/fly-path-$spp"
  /usr/bin/time -f "%U %S" -o "$d.time" "$B" render builtin:flythrough --frames 20..27 --method path \
    --spp $spp --resolution 128x128 --threads 1 -o "$d" > "$d.log" 2>&1
  "$B" compare "$d" "$REF" > "$d.compare" 2>&1
  echo "path spp=$spp cpu(7 frames)=$(awk '{print $1+$2}' "$d.time") $(grep "^summary" "$d.compare")"
done
