#!/bin/bash
# One segment over the whole animation (segment=48: the static cache gathered once, not
# twice) against the automatic one-second segments of run.sh, same protocol.
B=${B:-chronolux}
REFS=${REFS:-/work/refs256}
C="/work/shared/peers/cornell-moving.glb --frames 0..48 --measure 0..8,12,24,36,47 --reference $REFS --target-flip 0.05 --threads 1 --json"
run() { $B bench quality $C --method $1 --start-effort $2 --max-effort $2 ${4:+--set $4} > $1-$2-$3.json 2> $1-$2-$3.log; }
uptime >> uptime.txt
run ic-static-dynamic 25 seg48-1 segment=48
run ic-static-dynamic 50 seg48-1 segment=48
uptime >> uptime.txt
