#!/bin/bash
# Clusters of small triangles as DEPT elements (element_map.rs). A: chronolux built from
# 8b5ff43 (rendering code as 2fad2e0, before), B: the same plus the clusters (after);
# release profile, x86-64-v3, 2 threads, 2026-12-03. CPU s = user + sys of /usr/bin/time;
# peak memory = max RSS. A and B interleaved, 3 rounds.
set -e
A=${A:?binary before}; B=${B:?binary after}
RDEMO=${RDEMO:?converged reference of the demo, 64x64, frames 0..8 (chronolux reference --frames 0..8 --resolution 64x64)}
S=../../../shared/scenes
# Reference: TransmissionTest (static, 128,775 triangles), frame 0 at 96x96.
[ -d ref-tt ] || $B reference $S/TransmissionTest.glb --frames 0..1 --resolution 96x96 --max-spp 4096 --target-error 2e-4 --output ref-tt
[ -e ref-demo ] || ln -s "$RDEMO" ref-demo
for r in 1 2 3; do
  for v in A B; do bin=${!v}
    /usr/bin/time -f "$v default-tt %U %S %e %M" $bin render $S/TransmissionTest.glb --frames 0..1 --resolution 96x96 --output tt-$v --no-preview 2>&1 | tail -1
    $B compare tt-$v ref-tt | tail -1
  done
  /usr/bin/time -f "path16-tt %U %S %e %M" $B render $S/TransmissionTest.glb --method path --spp 16 --frames 0..1 --resolution 96x96 --output tt-path --no-preview 2>&1 | tail -1
  $B compare tt-path ref-tt | tail -1
done
for v in A B; do bin=${!v}
  /usr/bin/time -f "$v hq-tt %U %S %e %M" $bin render $S/TransmissionTest.glb --spp 256 --photons 400000 --frames 0..1 --resolution 96x96 --output tth-$v --no-preview 2>&1 | tail -1
  $B compare tth-$v ref-tt | tail -1
  # The demo (61 clusters on its spheres' small triangles), the README's 64x64 comparison.
  /usr/bin/time -f "$v demo64 %U %S %e %M" $bin render --frames 0..8 --resolution 64x64 --output demo-$v --no-preview 2>&1 | tail -1
  $B compare demo-$v ref-demo | tail -1
done
