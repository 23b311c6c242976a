#!/bin/bash
# spacetime-dept on the fly-through of a still interior (builtin:flythrough: the dolly's camera
# through the demo's room, nothing else moving), 128², the whole 48-frame clip rendered by the
# default command, frames 20–26 scored against path-traced references (whole windows: K = 8).
# One run, interleaved: still solution on (the default) and off, each twice. CPU s = user + sys.
# REF: chronolux reference builtin:flythrough --frames 20..28 --resolution 128x128 \
#        --target-error 5e-4 --max-spp 2048 --threads 1 -o ref-fly128
set -e
B=${B:-chronolux}
REF=${REF:-ref-fly128}
OUT=${OUT:-out}
mkdir -p "$OUT"
for rep in 1 2; do
  for still in true false; do
    d="$OUT/fly-$still-$rep"
    /usr/bin/time -f "%U %S" -o "$d.time" "$B" render builtin:flythrough --frames 0..48 \
      --resolution 128x128 --threads 1 --set still_set=$still -o "$d" > "$d.log" 2>&1
    mkdir -p "$d-scored"; for f in 20 21 22 23 24 25 26; do ln -sf "$(realpath $d)/frame_00$f.exr" "$d-scored/"; done
    "$B" compare "$d-scored" "$REF" > "$d.compare" 2>&1
    echo "still=$still rep=$rep cpu=$(awk '{print $1+$2}' "$d.time") $(grep -i "mean" "$d.compare" | head -3 | tr '\n' ' ')"
  done
done
