#!/bin/bash
# The dolly with glTF's default specular layer on every material (spec.patch), main at
# aeabf58 + spec.patch as B: its reference (bdpt 512 spp, frames 8..16), then one bench
# quality run each of stbpt after (B) and before (OLD=1) against bdpt, the protocol of
# run.sh. Outputs: spec-ref/, spec-b.json, spec-a.json, spec-log.txt.
cd "$(dirname "$0")"
B=${B:?binary with spec.patch}
export SPEC=1
[ -d spec-ref ] || $B render builtin:dolly --method bdpt --spp 512 --frames 8..16 --resolution 64x64 --max-depth 8 --threads 1 -o spec-ref > /dev/null 2>&1
T=0.3,0.25,0.2,0.16,0.13,0.11,0.1,0.09,0.08,0.07,0.06,0.05
Q=(bench quality builtin:dolly --resolution 64x64 --max-depth 8 --method stbpt --frames 4..20
   --start-effort 1 --max-effort 64 --reference spec-ref --measure 8..16 --threads 1 --target-flip $T --json)
echo "== B $(date -u) $(uptime)" >> spec-log.txt
$B "${Q[@]}" --baseline bdpt > spec-b.json 2> spec-b.err
echo "== A (OLD=1) $(date -u) $(uptime)" >> spec-log.txt
OLD=1 $B "${Q[@]}" --baseline bdpt > spec-a.json 2> spec-a.err
echo "== end $(date -u) $(uptime)" >> spec-log.txt
