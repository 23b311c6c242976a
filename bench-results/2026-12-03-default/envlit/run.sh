#!/bin/bash
# Env-lit glTF scenes (no lights in the file: the default sky is added), frames 0..7 at 96x96,
# 2 threads, against converged references made here. B: chronolux (release), 2026-12-03.
set -e
B=${B:?chronolux binary}
T=0.2,0.15,0.12,0.1,0.08,0.06,0.05,0.04,0.03
S=../../../../shared/scenes
$B reference $S/BoxAnimated.glb --frames 0..8 --resolution 96x96 --max-spp 8192 --target-error 2e-5 --output ref-box2
$B reference $S/InterpolationTest.glb --frames 0..8 --resolution 96x96 --max-spp 8192 --target-error 2e-5 --output ref-it
$B bench quality $S/BoxAnimated.glb --method path --reference ref-box2 --frames 0..8 --threads 2 --target-flip $T --start-effort 1 --max-effort 64 --report path.md
$B bench quality $S/BoxAnimated.glb --method path --reference ref-box2 --frames 0..8 --threads 2 --target-flip $T --start-effort 8 --max-effort 16 --report path2.md
$B bench quality $S/BoxAnimated.glb --method spacetime-dept --reference ref-box2 --frames 0..8 --threads 2 --target-flip $T --start-effort 4 --max-effort 256 --report st.md
$B bench quality $S/BoxAnimated.glb --method stbpt --reference ref-box2 --frames 0..8 --threads 2 --target-flip $T --start-effort 1 --max-effort 16 --report stbpt.md
for m in path:1:32 stbpt:1:8 spacetime-dept:4:64; do IFS=: read meth a b <<< "$m"
  $B bench quality $S/InterpolationTest.glb --method $meth --reference ref-it --frames 0..8 --threads 2 --target-flip $T --start-effort $a --max-effort $b --report it-$meth.md
done
$B bench quality $S/InterpolationTest.glb --method path --reference ref-it --frames 0..8 --threads 2 --target-flip 0.01 --start-effort 8 --max-effort 16 --report it-path2.md
# After the sky MIS in the DEPT eye pass (dept/view.rs), same session:
$B bench quality $S/BoxAnimated.glb --method spacetime-dept --reference ref-box2 --frames 0..8 --threads 2 --target-flip 0.01 --start-effort 4 --max-effort 8 --report st-mis.md
$B bench quality $S/InterpolationTest.glb --method spacetime-dept --reference ref-it --frames 0..8 --threads 2 --target-flip 0.01 --start-effort 4 --max-effort 8 --report it-st-mis.md
$B bench quality $S/BoxAnimated.glb --method path --reference ref-box2 --frames 0..8 --threads 2 --target-flip 0.005 --start-effort 16 --max-effort 32 --report path3.md
$B bench quality $S/InterpolationTest.glb --method path --reference ref-it --frames 0..8 --threads 2 --target-flip 0.005 --start-effort 32 --max-effort 64 --report it-path3.md
# 256 spp, both binaries: render --method spacetime-dept --spp 256 --frames 0..8 --resolution 96x96, compare with ref-it:
# before relMSE 3.7835e-5, after 2.8463e-5
