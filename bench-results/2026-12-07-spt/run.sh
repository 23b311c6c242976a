#!/usr/bin/env bash
# Issue 41 (spt part): `chronolux bench update` on the demo, one thread, each change with
# the new defaults (single flagged photons in the queue, no pilots) and, interleaved in the
# same run, the previous defaults (`reshoot=flagged`, pilots traced) as the before.
# Run from the repository root after `cargo build --profile ci -p chronolux`.
set -euo pipefail
out=bench-results/2026-12-07-spt
bin=target/ci/chronolux
{ date -u; lscpu | grep -E 'Model name|^CPU\(s\)'; grep -o 'avx512[a-z_0-9]*' /proc/cpuinfo | sort -u | tr '\n' ' '; echo; git rev-parse HEAD; } > $out/machine.txt
for change in nudge jump occluder light; do
  uptime >> $out/load.txt
  $bin bench update --change $change --threads 1 --json > $out/demo_${change}.json
  uptime >> $out/load.txt
  $bin bench update --change $change --threads 1 --json \
    --set reshoot=flagged --set trace_pilots=true > $out/demo_${change}_before.json
done
uptime >> $out/load.txt
$bin bench update --change jump --threads 1 --json \
  --set scan_paths=false --set reshoot=group > $out/demo_jump_paper.json
uptime >> $out/load.txt
