#!/bin/sh
# stbpt with the caustic photon estimate (--set caustic_photons=200000) against stbpt
# without it (the baseline, its default), one bench quality run. Demo, 64x64, frames 0-7.
B=${B:-/work/target-caustics/ci/chronolux}
uptime > quality.uptime
/usr/bin/time -v $B bench quality --method stbpt --set caustic_photons=200000 --baseline stbpt \
  --reference /work/refs/ref-demo-64-0to8 --frames 0..8 --threads 1 --json \
  --target-flip 0.2,0.16,0.13,0.11,0.1,0.09,0.08 --max-effort 16 \
  --report quality.md > quality.json 2> quality.log
uptime >> quality.uptime
