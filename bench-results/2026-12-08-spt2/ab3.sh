#!/bin/bash
# Third interleaved A/B of `chronolux bench update` (the final code), one thread, CPU
# clock (clock_gettime(CLOCK_PROCESS_CPUTIME_ID), as the bench reads it).
#   A = main at 76794e4 (the starting commit), --profile ci
#   B = 9f85dbd (branch work of /work/hspt2), --profile ci: allocation-free re-shooting, quantized points in the summaries, keys
#       in one pass, and the bench's random_pool order (A's JSON has no random_pool)
# Each round runs every change A then B back to back; two rounds. Output: *_A3_r*.json,
# *_B3_r*.json (summary.py reads them as binaries A3 and B3).
set -eu
cd "$(dirname "$0")"
BIN=../../target/ab
A=$BIN/chronolux-A-76794e4
B=$BIN/chronolux-B-9f85dbd
: > load3.txt
for round in 1 2; do
  for change in nudge jump occluder light; do
    for v in A B; do
      bin=${!v}
      echo "$(date -u +%H:%M:%S) round $round $change $v $(uptime)" >> load3.txt
      $bin bench update --change $change --threads 1 --json > ${change}_${v}3_r${round}.json
    done
  done
done
echo "$(date -u +%H:%M:%S) done $(uptime)" >> load3.txt
