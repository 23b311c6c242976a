#!/bin/bash
# spacetime-dept at its default 16 camera samples per pixel (dept-spatial's) against
# dept-spatial, both with the automatic element count: the dolly (moving camera: the
# per-pixel light is not reused, so the eye pass's noise is the flicker) and the demo.
cd "$(dirname "$0")"
B=${B:?chronolux binary}
export LD_LIBRARY_PATH=${OIDN_LIB:-/work/.venv-oidn/lib/python3.11/site-packages/pyoidn/oidn/lib}
T=0.3,0.25,0.2,0.16,0.13,0.11,0.1,0.09,0.08,0.07,0.06
for sc in dolly demo; do
  case $sc in
    dolly) S=builtin:dolly; R=/work/refs/ref-dolly-64;;
    demo) S=builtin:demo; R=/work/refs/ref-demo-64;;
  esac
  echo "== $sc start $(date -u) $(uptime)" >> log-spp16.txt
  $B bench quality $S --resolution 64x64 --method spacetime-dept --baseline dept-spatial --reference $R \
    --frames 0..8 --threads 1 --target-flip 0.3,0.25,0.2,0.16,0.13,0.11,0.1,0.09,0.08,0.07 --start-effort 2 --max-effort 512 --json > $sc-st16.json 2> $sc-st16.err
done
echo "== end $(date -u) $(uptime)" >> log-spp16.txt
