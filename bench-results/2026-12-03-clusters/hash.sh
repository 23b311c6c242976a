#!/bin/bash
# Neighbour grid hash (reconstruct.rs CellHasher): A = the clusters commit (SipHash),
# B = the multiply-rotate hash; sky-lit BoxAnimated (the whole model moves, so rows are
# rebuilt every frame), 96x96, frames 0..7, 4k photons, 2 threads; interleaved, 3 rounds.
# CPU s = user + sys. Images must be bit-identical.
set -e
A=${A:?binary before}; B=${B:?binary after}
S=../../../shared/scenes
for r in 1 2 3; do for v in A B; do bin=${!v}
  /usr/bin/time -f "$v %U %S %e" $bin render $S/BoxAnimated.glb --photons 4000 --frames 0..8 --resolution 96x96 --threads 2 --output hash-$v --no-preview 2>&1 | tail -1
done; done
for f in hash-A/*.exr; do cmp "$f" hash-B/$(basename $f); done && echo "images bit-identical"
