#!/bin/sh
# "After": stbpt (this branch, ci profile) against bdpt.
B=/work/refs-stbpt/chronolux-new
T=0.3,0.25,0.2,0.16,0.13,0.11,0.1,0.09,0.08,0.07,0.06
C="--frames 0..8 --target-flip $T --threads 1 --json"
scene=$1; name=$2; ref=$3; shift 3
$B bench quality $scene "$@" --method stbpt --baseline bdpt --reference $ref $C --max-effort 16 --report $name-stbpt.md > $name-stbpt.json 2> $name-stbpt.log
