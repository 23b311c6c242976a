#!/bin/bash
# RiggedSimple (--stage cornell), spacetime-dept vs dept-spatial, before (7b7288c) and after
# the sliver subdivision rule; ci-profile builds of each (cargo build --profile ci -p chronolux).
cd "$(dirname "$0")"
S=/work/shared/scenes/RiggedSimple.glb; R=/work/refs-stbpt/ref-rigged-64
for b in sliver 7b7288c; do
  B=/work/peers-run/chronolux-$b
  uptime > $b.uptime
  $B bench quality $S --stage cornell --method spacetime-dept --set spp=4 --baseline dept-spatial --reference $R \
    --frames 0..8 --target-flip 0.2,0.15,0.12,0.1,0.09 --start-effort 2 --max-effort 128 --threads 1 --json --report $b.md > $b.json 2> $b.log
  uptime >> $b.uptime
done
# Ratios: python3 ../2026-12-02-stdept2/equal_flip.py {sliver,7b7288c,cm-sliver,cm-7b7288c}.json
