#!/bin/bash
# ic-static-dynamic against pm-ic at 256² over the WHOLE animation (48 frames = two 24-frame
# segments, every window whole), scored on the 12 frames with Mitsuba references (0-7, 12, 24,
# 36, 47; REFS holds them as frame_00NN.exr), as the default route's protocol (issue 37).
# pm-ic is stateless: bench quality renders only the measured frames; ic-static-dynamic renders
# all 48 and is charged 12/48 of its CPU. One level per call, interleaved.
B=${B:-chronolux}
REFS=${REFS:-/work/refs256}
C="/work/shared/peers/cornell-moving.glb --frames 0..48 --measure 0..8,12,24,36,47 --reference $REFS --target-flip 0.05 --threads 1 --json"
run() { $B bench quality $C --method $1 --start-effort $2 --max-effort $2 > $1-$2-$3.json 2> $1-$2-$3.log; }
lscpu | grep -E "Model name|Flags" > machine.txt
uptime > uptime.txt
run ic-static-dynamic 25 1
run pm-ic 25 1
run ic-static-dynamic 50 1
run pm-ic 50 1
run ic-static-dynamic 25 2
uptime >> uptime.txt
