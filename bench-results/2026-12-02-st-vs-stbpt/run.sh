#!/bin/bash
# Which technique is best per scene (issue 17 item 5's rule): stbpt (its defaults) against
# spacetime-dept (its defaults: 16 spp, automatic elements) at equal FLIP; one bench quality
# run per method, frames 0-7, --threads 2 (as a user renders), 64x64 (cornell-moving 256x256
# against the Mitsuba references, --max-depth 8). B: chronolux (ci profile).
cd "$(dirname "$0")"
B=${B:?chronolux binary}
export LD_LIBRARY_PATH=${OIDN_LIB:-/work/.venv-oidn/lib/python3.11/site-packages/pyoidn/oidn/lib}  # if the binary links OIDN
T=0.2,0.15,0.12,0.1,0.09,0.08,0.07,0.06,0.05
{ date -u; uptime; lscpu | grep -E "Model name|^CPU\(s\)"; } > machine.txt
for sc in rigged dolly demo cm; do
  case $sc in
    rigged) S=/work/shared/scenes/RiggedSimple.glb; X="--stage cornell --resolution 64x64"; R=/work/refs/ref-rigged-64;;
    dolly) S=builtin:dolly; X="--resolution 64x64"; R=/work/refs/ref-dolly-64;;
    demo) S=builtin:demo; X="--resolution 64x64"; R=/work/refs/ref-demo-64;;
    cm) S=/work/peers-run/cornell-moving.glb; X="--max-depth 8"; R=/work/peers-run/refs-cm;;
  esac
  echo "== $sc start $(date -u) $(uptime)" >> log.txt
  $B bench quality $S $X --method stbpt --reference $R --frames 0..8 --threads 2 \
    --target-flip $T --start-effort 1 --max-effort 16 --json > $sc-stbpt.json 2> $sc-stbpt.err
  $B bench quality $S $X --method spacetime-dept --reference $R --frames 0..8 --threads 2 \
    --target-flip $T --start-effort 8 --max-effort 512 --json > $sc-st.json 2> $sc-st.err
done
echo "== end $(date -u) $(uptime)" >> log.txt
