#!/bin/sh
# bdpt levels 32 and 64 (the stbpt-vs-bdpt runs stopped at 16).
B=/work/refs-stbpt/chronolux-new
T=0.3,0.25,0.2,0.16,0.13,0.11,0.1,0.09,0.08,0.07,0.06
C="--frames 0..8 --target-flip $T --threads 1 --json --start-effort 32 --max-effort 64"
scene=$1; name=$2; ref=$3; shift 3
$B bench quality $scene "$@" --method bdpt --reference $ref $C --report $name-bdpt-hi.md > $name-bdpt-hi.json 2> $name-bdpt-hi.log
