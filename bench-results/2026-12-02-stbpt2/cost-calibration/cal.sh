#!/bin/sh
B=/work/target-stbpt2/chronolux-stbpt2-d
for pair in "rigged|/work/shared/scenes/RiggedSimple.glb --stage cornell|/work/refs-stbpt/ref-rigged-64b" "cm|/work/shared/peers/cornell-moving.glb|/work/refs-stbpt/ref-cm-64b" "demo||/work/refs-stbpt/ref-demo-64"; do
  name=$(echo "$pair" | cut -d'|' -f1); sc=$(echo "$pair" | cut -d'|' -f2); ref=$(echo "$pair" | cut -d'|' -f3)
  for m in path bdpt; do
    $B bench quality $sc --method $m --reference $ref --frames 0..8 --target-flip 0.01 --threads 1 --json --start-effort 8 --max-effort 8 > $name-$m.json 2>/dev/null
    $B render $sc --method $m --frames 0..8 --resolution 64x64 --spp 8 --threads 1 -o $name-$m-render > /dev/null 2>&1
  done
done
echo done > all.done
