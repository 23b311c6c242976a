#!/bin/bash
# The path probe (spacetime-dept renders a frame as `path` where it cannot gain):
# 1. the three sky-lit glTF models of "Sky-lit models at 256²" (256², frames 0-7,
#    2 threads, references of bench-results/2026-12-04-skylit-256/run.sh), the default
#    (spacetime-dept, 4k photons: `bench quality`'s effort 4) against `path` at 16 spp,
#    interleaved, two rounds;
# 2. what the probe costs where it keeps spacetime-dept: the dolly (every frame probed
#    in its block: a moving camera), 128², frames 0-15, probe on and off (same images).
# B: chronolux (release of main at e39d9c3, --features oidn); REFS: folder with ref-<scene>; S: ../shared/scenes.
set -e
B=${B:?chronolux binary}
S=${S:-../../../shared/scenes}
REFS=${REFS:?folder of ref-SCENE}
q() { $B bench quality "$@" --threads 2 --target-flip 0.01 --json; }
for round in 1 2; do
  for sc in BoxAnimated RiggedSimple AnimatedMorphCube; do
    q $S/$sc.glb --method spacetime-dept --reference $REFS/ref-$sc --frames 0..8 --start-effort 4 --max-effort 4 > $sc-st-$round.json 2> $sc-st-$round.err
    q $S/$sc.glb --method path --reference $REFS/ref-$sc --frames 0..8 --start-effort 16 --max-effort 16 > $sc-path-$round.json 2> $sc-path-$round.err
  done
  for probe in true false; do
    /usr/bin/time -f "dolly probe=$probe round $round: %U user %S sys %e wall" $B render builtin:dolly --frames 0..16 --resolution 128x128 --set path_probe=$probe --output dolly-$probe --no-preview > /dev/null 2>> dolly-time.txt
  done
  for f in 0 7 15; do cmp dolly-true/frame_$(printf %04d $f).exr dolly-false/frame_$(printf %04d $f).exr && echo "dolly frame $f identical" >> dolly-time.txt; done
  rm -rf dolly-true dolly-false
done
python3 - <<'PY'
import json
def lv(f):
    l = json.load(open(f))["results"][0]["levels"][0]
    return l["cpu_s"], l["flip_mean"], l["flicker"]
for sc in ["BoxAnimated", "RiggedSimple", "AnimatedMorphCube"]:
    for r in (1, 2):
        st, p = lv(f"{sc}-st-{r}.json"), lv(f"{sc}-path-{r}.json")
        print(f"{sc} round {r}: spacetime-dept CPU {st[0]:.2f} s FLIP {st[1]:.4f} flicker {st[2]:.3f}; "
              f"path 16 spp CPU {p[0]:.2f} s FLIP {p[1]:.4f} flicker {p[2]:.3f}; path/st CPU {p[0] / st[0]:.3f}")
PY
