#!/bin/sh
# "Before": stbpt and path with the ci build of main at 4856022 (no stbpt change since).
B=/work/refs-stbpt/chronolux-main
T=0.3,0.25,0.2,0.16,0.13,0.11,0.1,0.09,0.08
C="--frames 0..8 --target-flip $T --threads 1 --json"
scene=$1; name=$2; ref=$3; shift 3
$B bench quality $scene "$@" --method path --reference $ref $C --max-effort 64 --report $name-path.md > $name-path.json 2> $name-path.log
$B bench quality $scene "$@" --method stbpt --reference $ref $C --max-effort 16 --report $name-stbpt-before.md > $name-stbpt-before.json 2> $name-stbpt-before.log
