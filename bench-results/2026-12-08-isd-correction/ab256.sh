#!/bin/bash
# Interleaved A/B at 256², frames 0–7 (quiet machine): density correction (previous default) vs gathered (m = 6), and pm-ic.
B=${B:-chronolux}
C="/work/shared/peers/cornell-moving.glb --frames 0..8 --reference /work/refs256 --max-depth 8 --target-flip 0.05 --threads 1 --json"
run() { $B bench quality $C --method $1 --start-effort $2 --max-effort $2 ${3:+--set $3} > ab-$1-$2-${3:-default}-$4.json 2> ab-$1-$2-${3:-default}-$4.log; }
uptime > ab-uptime.txt
run ic-static-dynamic 100 "" 1
run ic-static-dynamic 25 correction_m=6 1
run ic-static-dynamic 50 correction_m=6 1
run pm-ic 25 "" 1
run ic-static-dynamic 100 "" 2
run ic-static-dynamic 25 correction_m=6 2
uptime >> ab-uptime.txt
