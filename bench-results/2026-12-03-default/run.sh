#!/bin/bash
# Issue 17 item 5: the README's first command with spacetime-dept (the new default) against
# stbpt (the former default), and the README's image pair and plot. B: chronolux (release
# profile, --features oidn), 2 threads, 2026-12-03, main at 2be925a + the default change.
# CPU seconds = user + sys of /usr/bin/time.
set -e
B=${B:?chronolux binary}
R=${R:?converged reference of the demo at 64x64, frames 0..=7 (chronolux reference builtin:demo --frames 0..8 --resolution 64x64)}
/usr/bin/time -f "%U %S %e" $B render --method spacetime-dept --output st49      # 108.3 CPU s
/usr/bin/time -f "%U %S %e" $B render --method stbpt --output stbpt49            # 750.0 CPU s
/usr/bin/time -f "%U %S %e" $B render --method path --spp 6 --frames 0..8 --output path6x8 --no-preview  # 19.6: 2.45 per frame
/usr/bin/time -f "%U %S %e" $B render --method path --spp 6 --frames 6..7 --output path6 --no-preview
# 64x64, frames 0..7: spacetime-dept 4.44, 4.74, 5.17 CPU s; path 18 spp 4.62, 4.57
/usr/bin/time -f "%U %S %e" $B render --method spacetime-dept --frames 0..8 --resolution 64x64 --output spacetime-dept-default --no-preview
/usr/bin/time -f "%U %S %e" $B render --method path --spp 18 --frames 0..8 --resolution 64x64 --output path-18spp --no-preview
ln -sfn "$R" reference
$B compare spacetime-dept-default reference --versus path-18spp --plot demo-default-vs-path.svg > compare-64.txt
# (by mistake, the first 64x64 run of `render` without --method was still stbpt: 6.47-7.03 CPU s,
# FLIP 0.0773, relMSE 0.0052, flicker 0.0339; its run.json is stbpt64.run.json)
# docs/demo-default-vs-path.png: st49/frame_0006.png | path6/frame_0006.png side by side.
# docs/demo.png (README's first image): 29.2 CPU s
/usr/bin/time -f "%U %S %e" $B render --method spacetime-dept --frames 24 --resolution 512x512 --spp 64 --output hero --no-preview
