#!/bin/bash
# The same protocol as run.sh with the dynamic cache confined by higher influence thresholds
# (influence_low=0.3, influence_high=1: beta > 0 only where the change is over 30 % of the
# static irradiance), interleaved with a second default run.
B=${B:-chronolux}
REFS=${REFS:-/work/refs256}
C="/work/shared/peers/cornell-moving.glb --frames 0..48 --measure 0..8,12,24,36,47 --reference $REFS --target-flip 0.05 --threads 1 --json"
run() { $B bench quality $C --method $1 --start-effort $2 --max-effort $2 ${4:+--set influence_low=$4 --set influence_high=$5} > $1-$2-$3.json 2> $1-$2-$3.log; }
uptime >> uptime.txt
run ic-static-dynamic 25 infl03-1 0.3 1
run ic-static-dynamic 50 infl03-1 0.3 1
run ic-static-dynamic 50 2
uptime >> uptime.txt
