#!/bin/sh
# stbpt (auto strategies, K chosen) against stbpt with adaptive=false (all strategies,
# K = 4 fixed: what stbpt did before this branch on these scenes, where K stayed 4), one run.
B=/work/target-stbpt2/chronolux-bench
T=0.3,0.25,0.2,0.16,0.13,0.11,0.1,0.09,0.08,0.07,0.06
C="--frames 0..8 --target-flip $T --threads 1 --json"
scene=$1; name=$2; ref=$3; shift 3
uptime > $name-fixed.uptime
$B bench quality $scene "$@" --method stbpt --baseline stbpt --baseline-set adaptive=false --reference $ref $C --max-effort 16 --report $name-vs-fixed.md > $name-vs-fixed.json 2> $name-vs-fixed.log
uptime >> $name-fixed.uptime
