#!/usr/bin/env bash
# Step 1 of the 2026-12-08 spt work: the code of ae86d4c with the CPU clock switched to
# clock_gettime(CLOCK_PROCESS_CPUTIME_ID) (commit "bench update: CPU clock ..."), 3 runs
# each of nudge and jump. Run from the repository root; the binary is a copy of
# `cargo build --profile ci -p chronolux` at that commit.
set -euo pipefail
out=bench-results/2026-12-08-spt
bin=${BIN:-target/chronolux-baseline}
{ date -u; lscpu | grep -E 'Model name|^CPU\(s\)'; grep -o 'avx512[a-z_0-9]*' /proc/cpuinfo | sort -u | tr '\n' ' '; echo; git rev-parse HEAD; } > $out/baseline_machine.txt
: > $out/baseline_load.txt
for r in 1 2 3; do
  for change in nudge jump; do
    uptime >> $out/baseline_load.txt
    $bin bench update --threads 1 --json --change $change > $out/baseline_${change}_$r.json
  done
done
uptime >> $out/baseline_load.txt
