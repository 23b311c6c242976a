#!/bin/bash
# Reuse on the still part of a deforming mesh (stbpt, FrameDelta::triangle_changed), on
# builtin:banner, the protocol of ../2026-12-04-st-whole-windows/run.sh stbpt (frames 4..20
# rendered, 8..16 scored, 64², --max-depth 8, 1..64 spp, one thread).
#   B    a build of main at 03bcd2e with per-instance.patch (CHRONOLUX_PER_INSTANCE=1 makes
#        triangle_changed answer per instance, as before 03bcd2e; unset: main's behaviour)
#   REF  the banner's references: chronolux reference --frames 8..16 --resolution 64x64
#        --max-depth 8 --target-error 5e-5 --max-spp 4096 --threads 1 builtin:banner
# Outputs: vs-bdpt.json (stbpt against bdpt, one run), then ROUNDS interleaved rounds of
# stbpt alone, per instance (A) and per triangle (B): a-N.json, b-N.json; log.txt.
cd "$(dirname "$0")"
B=${B:?chronolux binary}
REF=${REF:?reference folder}
ROUNDS=${ROUNDS:-3}
T=0.3,0.25,0.2,0.16,0.13,0.11,0.1,0.09,0.08,0.07,0.06
Q=(bench quality builtin:banner --resolution 64x64 --max-depth 8 --method stbpt --frames 4..20
   --start-effort 1 --max-effort 64 --reference $REF --measure 8..16 --threads 1 --target-flip $T --json)
echo "== vs bdpt $(date -u) $(uptime)" >> log.txt
$B "${Q[@]}" --baseline bdpt > vs-bdpt.json 2> vs-bdpt.err
for r in $(seq 1 $ROUNDS); do
  echo "== round $r A $(date -u) $(uptime)" >> log.txt
  CHRONOLUX_PER_INSTANCE=1 $B "${Q[@]}" > a-$r.json 2> a-$r.err
  echo "== round $r B $(date -u) $(uptime)" >> log.txt
  $B "${Q[@]}" > b-$r.json 2> b-$r.err
done
echo "== end $(date -u) $(uptime)" >> log.txt
