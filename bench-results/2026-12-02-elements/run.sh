#!/bin/bash
# Issue 17: the element size from the photons (auto_elements) against the former fixed 100
# elements per diagonal, for spacetime-dept (--set spp=4) and its baseline dept-spatial,
# and frame-by-frame path; one bench quality run per method and setting, one scene after
# the other, --threads 1, frames 0-7, 64x64 (cornell-moving 256x256 against the Mitsuba
# references). B: chronolux (ci profile) of the commit under test.
# REFS: folders of converged frames (chronolux reference, target relMSE 5e-5/1e-4).
cd "$(dirname "$0")"
B=${B:?chronolux binary}
export LD_LIBRARY_PATH=${OIDN_LIB:-/work/.venv-oidn/lib/python3.11/site-packages/pyoidn/oidn/lib}  # the binary links OIDN
T=0.3,0.25,0.2,0.16,0.13,0.11,0.1,0.09,0.08,0.07,0.06
{ date -u; uptime; lscpu | grep -E "Model name|^CPU\(s\)|Flags" | cut -c1-300; } > machine.txt
for sc in rigged dolly cm demo; do
  case $sc in
    rigged) S=/work/shared/scenes/RiggedSimple.glb; X="--stage cornell --resolution 64x64"; R=/work/refs/ref-rigged-64;;
    dolly) S=builtin:dolly; X="--resolution 64x64"; R=/work/refs/ref-dolly-64;;
    demo) S=builtin:demo; X="--resolution 64x64"; R=/work/refs/ref-demo-64;;
    cm) S=/work/peers-run/cornell-moving.glb; X="--max-depth 8"; R=/work/peers-run/refs-cm;;
  esac
  echo "== $sc start $(date -u) $(uptime)" >> log.txt
  for el in 0 100; do
    $B bench quality $S $X --method spacetime-dept --set spp=4 --set elements=$el --reference $R --frames 0..8 --threads 1 \
      --target-flip $T --start-effort 2 --max-effort 64 --json > $sc-st-e$el.json 2> $sc-st-e$el.err
    $B bench quality $S $X --method dept-spatial --set elements=$el --reference $R --frames 0..8 --threads 1 \
      --target-flip $T --start-effort 2 --max-effort 256 --json > $sc-ds-e$el.json 2> $sc-ds-e$el.err
  done
  $B bench quality $S $X --method path --reference $R --frames 0..8 --threads 1 \
    --target-flip $T --start-effort 1 --max-effort 64 --json > $sc-path.json 2> $sc-path.err
  echo "== $sc end $(date -u) $(uptime)" >> log.txt
done
