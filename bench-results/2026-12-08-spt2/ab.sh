#!/bin/bash
# Interleaved A/B(/C) of `chronolux bench update`, one thread, CPU clock
# (clock_gettime(CLOCK_PROCESS_CPUTIME_ID), as the bench reads it).
#   A = main at 76794e4 (the starting commit), --profile ci
#   B = f23ca8f (branch work of /work/hspt2), --profile ci
#   C = B with the three per-kind arrays of 76794e4's SignedAccumulators instead of one
#       64-byte SideSums per side (to measure that change alone; nudge and jump only)
# Each round runs every change A, B (, C) back to back; two rounds.
set -eu
cd "$(dirname "$0")"
BIN=../../target/ab
A=$BIN/chronolux-A-76794e4
B=$BIN/chronolux-B-f23ca8f
C=$BIN/chronolux-C-f23ca8f-three-arrays
{ lscpu; echo; grep -o -w 'avx512[a-z_0-9]*' /proc/cpuinfo | sort -u | tr '\n' ' '; echo; } > machine.txt
: > load.txt
for round in 1 2; do
  for change in nudge jump occluder light; do
    for v in A B C; do
      if [ $v = C ] && [ $change != nudge ] && [ $change != jump ]; then continue; fi
      bin=${!v}
      echo "$(date -u +%H:%M:%S) round $round $change $v $(uptime)" >> load.txt
      $bin bench update --change $change --threads 1 --json > ${change}_${v}_r${round}.json
    done
  done
done
echo "$(date -u +%H:%M:%S) done $(uptime)" >> load.txt
