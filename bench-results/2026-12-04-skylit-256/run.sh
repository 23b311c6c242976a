#!/bin/bash
# Sky-lit glTF models at the README's resolution (256², frames 0-7, 2 threads): the default
# (`spacetime-dept`, 16 spp eye pass, 4k photons per frame: `bench quality`'s first level)
# against frame-by-frame `path`, CPU seconds at equal mean HDR-FLIP against references made
# here (`chronolux reference`, estimated relMSE <= 5e-5). B: chronolux (release, main at
# 2f3a57c); S: ../shared/scenes. 2026-12-04, AMD EPYC (machine.txt).
set -e
B=${B:?chronolux binary}
S=${S:-../../../shared/scenes}
T=0.2,0.15,0.12,0.1,0.08,0.06,0.05,0.04,0.03,0.025,0.02,0.015,0.012,0.01,0.008,0.006,0.005,0.004,0.003
for sc in BoxAnimated RiggedSimple AnimatedMorphCube; do
  $B reference $S/$sc.glb --frames 0..8 --resolution 256x256 --max-spp 2048 --target-error 5e-5 --output ref-$sc > $sc-ref.log 2>&1
  $B bench quality $S/$sc.glb --method path --reference ref-$sc --frames 0..8 --threads 2 --target-flip $T --start-effort 2 --max-effort 64 --json > $sc-path.json 2> $sc-path.err
  $B bench quality $S/$sc.glb --method spacetime-dept --reference ref-$sc --frames 0..8 --threads 2 --target-flip $T --start-effort 4 --max-effort 4 --json > $sc-st.json 2> $sc-st.err
  # light reuse per frame (run.json stats.light_spp; 16 = none):
  $B render $S/$sc.glb --frames 0..8 --resolution 96x96 --photons 4000 --output light-$sc --no-preview > /dev/null 2>&1
  python3 -c "import json; print('$sc', [f['stats']['light_spp'] for f in json.load(open('light-$sc/run.json'))['frames']])" >> light-spp.txt
  rm -rf light-$sc
done
