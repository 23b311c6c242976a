#!/bin/bash
# A 441k-triangle animated scene (gen.py: a 261k-triangle sphere sliding over a 180k-triangle
# floor, one point light), 64x64, frames 0..3, 2 threads; A (before) and B (clusters) as in
# run.sh, one run each (A was killed by the kernel's OOM killer at 24 GB). 2026-12-03.
set -u
A=${A:?binary before}; B=${B:?binary after}
python3 gen.py 512 256 300 heavy.glb
for m in spacetime-dept dept-spatial spt; do for v in A B; do bin=${!v}
  /usr/bin/time -f "$v $m %U %S %e %MkB rc=%x" $bin render heavy.glb --method $m --frames 0..4 --resolution 64x64 --output hv-$v-$m --no-preview 2>&1 | tail -1
done; done
/usr/bin/time -f "path %U %S %e %MkB rc=%x" $B render heavy.glb --method path --frames 0..4 --resolution 64x64 --output hv-path --no-preview 2>&1 | tail -1
