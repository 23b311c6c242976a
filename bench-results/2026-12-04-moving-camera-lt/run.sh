#!/bin/bash
# stbpt with light tracing under a moving camera (entries re-weighted for g's camera
# density of x1), on builtin:dolly, the protocol of ../2026-12-04-st-whole-windows/run.sh
# stbpt (frames 4..20 rendered, 8..16 scored, 64², --max-depth 8, 1..64 spp, one thread),
# against bdpt in one run; and stbpt before the change (A) against after (B) in one
# bench quality run each, same references.
#   A    main at c5e741a (light tracing off whenever the camera may move)
#   B    main with the change
#   REF  the dolly's references (../2026-12-04-st-whole-windows/refs.sh: frames 8..16)
cd "$(dirname "$0")"
A=${A:?binary before} B=${B:?binary after} REF=${REF:?references}
T=0.3,0.25,0.2,0.16,0.13,0.11,0.1,0.09,0.08,0.07,0.06,0.05
Q=(bench quality builtin:dolly --resolution 64x64 --max-depth 8 --method stbpt --frames 4..20
   --start-effort 1 --max-effort 64 --reference $REF --measure 8..16 --threads 1 --target-flip $T --json)
echo "== B vs bdpt $(date -u) $(uptime)" >> log.txt
$B "${Q[@]}" --baseline bdpt > b-vs-bdpt.json 2> b-vs-bdpt.err
echo "== A vs bdpt $(date -u) $(uptime)" >> log.txt
$A "${Q[@]}" --baseline bdpt > a-vs-bdpt.json 2> a-vs-bdpt.err
echo "== end $(date -u) $(uptime)" >> log.txt
