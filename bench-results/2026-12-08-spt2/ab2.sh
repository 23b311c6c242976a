#!/bin/bash
# Second interleaved A/B of `chronolux bench update` (the code at c79a675), one thread, CPU
# clock (clock_gettime(CLOCK_PROCESS_CPUTIME_ID), as the bench reads it).
#   A = main at 76794e4 (the starting commit), --profile ci
#   B = c79a675 (branch work of /work/hspt2), --profile ci: allocation-free re-shooting, keys
#       in one pass, and the bench's random_pool order (A's JSON has no random_pool)
# Each round runs every change A then B back to back; two rounds. Output: *_A2_r*.json,
# *_B2_r*.json (summary.py reads them as binaries A2 and B2).
set -eu
cd "$(dirname "$0")"
BIN=../../target/ab
A=$BIN/chronolux-A-76794e4
B=$BIN/chronolux-B-c79a675
: > load2.txt
for round in 1 2; do
  for change in nudge jump occluder light; do
    for v in A B; do
      bin=${!v}
      echo "$(date -u +%H:%M:%S) round $round $change $v $(uptime)" >> load2.txt
      $bin bench update --change $change --threads 1 --json > ${change}_${v}2_r${round}.json
    done
  done
done
echo "$(date -u +%H:%M:%S) done $(uptime)" >> load2.txt
