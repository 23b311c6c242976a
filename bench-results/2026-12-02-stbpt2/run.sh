#!/bin/sh
# One scene: stbpt (this branch, auto strategies) against bdpt to 16 spp generated per frame,
# path to 64 spp, bdpt 32-64 spp. All --threads 1, 64x64, frames 0-7, every frame scored.
B=/work/target-stbpt2/chronolux-bench
T=0.3,0.25,0.2,0.16,0.13,0.11,0.1,0.09,0.08,0.07,0.06
C="--frames 0..8 --target-flip $T --threads 1 --json"
scene=$1; name=$2; ref=$3; shift 3
uptime > $name.uptime
$B bench quality $scene "$@" --method stbpt --baseline bdpt --reference $ref $C --max-effort 16 --report $name-stbpt.md > $name-stbpt.json 2> $name-stbpt.log
uptime >> $name.uptime
$B bench quality $scene "$@" --method path --reference $ref $C --max-effort 64 --report $name-path.md > $name-path.json 2> $name-path.log
uptime >> $name.uptime
$B bench quality $scene "$@" --method bdpt --reference $ref $C --start-effort 32 --max-effort 64 --report $name-bdpt-hi.md > $name-bdpt-hi.json 2> $name-bdpt-hi.log
uptime >> $name.uptime
