#!/usr/bin/env bash
# Interleaved A/B: A = step-1 baseline (ae86d4c + CPU clock, target/chronolux-baseline),
# B = this branch (target/chronolux-new). One run each of nudge, jump, light, occluder.
set -euo pipefail
out=bench-results/2026-12-08-spt
: > $out/ab_load.txt
for change in nudge jump light occluder; do
  for v in baseline new; do
    uptime >> $out/ab_load.txt
    target/chronolux-$v bench update --threads 1 --json --change $change > $out/ab_${v}_${change}.json
  done
done
uptime >> $out/ab_load.txt
