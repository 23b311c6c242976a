#!/usr/bin/env bash
# The tnear change leaves images bit-identical: `path` (16 spp) and the default route
# (spacetime-dept, no denoiser) on cornell-moving, frames 0-2, rendered by the binaries
# before (504ebff) and after (the tnear commit); every EXR compared byte for byte.
#   images_identical.sh BEFORE_BIN AFTER_BIN OUT
set -euo pipefail
OLD=$1 NEW=$2 OUT=$3
SCENE=${SCENE:-/work/shared/peers/cornell-moving.glb}
for b in old new; do
    bin=$OLD; [ $b = new ] && bin=$NEW
    "$bin" render "$SCENE" --method path --no-denoise --spp 16 --frames 0..3 --resolution 96x96 --threads 2 --output "$OUT/path_$b" > /dev/null 2>&1
    "$bin" render "$SCENE" --frames 0..3 --resolution 64x64 --no-denoise --threads 2 --output "$OUT/route_$b" > /dev/null 2>&1
done
for k in path route; do
    for f in "$OUT/${k}_old"/*.exr; do
        cmp -s "$f" "$OUT/${k}_new/$(basename "$f")" && echo "$k $(basename "$f") identical" || echo "$k $(basename "$f") DIFFERS"
    done
done
