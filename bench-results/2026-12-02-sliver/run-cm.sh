#!/bin/bash
# cornell-moving, spacetime-dept vs dept-spatial, after (sliver) and before (7b7288c), one run.
cd "$(dirname "$0")"
S=/work/shared/peers/cornell-moving.glb; R=/work/refs-stbpt/ref-cm-64
for b in sliver 7b7288c; do
  B=/work/peers-run/chronolux-$b
  uptime > cm-$b.uptime
  $B bench quality $S --method spacetime-dept --set spp=4 --baseline dept-spatial --reference $R \
    --frames 0..8 --target-flip 0.2,0.15,0.12,0.1,0.09 --start-effort 2 --max-effort 128 --threads 1 --json --report cm-$b.md > cm-$b.json 2> cm-$b.log
  uptime >> cm-$b.uptime
done
