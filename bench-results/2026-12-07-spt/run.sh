#!/usr/bin/env bash
# Issue 41 (spt part): `chronolux bench update` on the demo, one thread. Each change with the
# new defaults (flagged photons queued one by one, no pilots) and, interleaved in the same
# run, the previous defaults (`reshoot=flagged`, pilots traced) as the before; on `nudge`
# and `jump` also whole groups re-shot (`reshoot=group`: the paper's granularity and its
# random-order baseline, with the complete scan so that it gets clean), and the defaults
# twice more (CPU time is read at a 4 ms scheduler tick). Run from the repository root
# after `cargo build --profile ci -p chronolux`.
set -euo pipefail
out=bench-results/2026-12-07-spt
bin=target/ci/chronolux
{ date -u; lscpu | grep -E 'Model name|^CPU\(s\)'; grep -o 'avx512[a-z_0-9]*' /proc/cpuinfo | sort -u | tr '\n' ' '; echo; git rev-parse HEAD; } > $out/machine.txt
: > $out/load.txt
b() { uptime >> $out/load.txt; $bin bench update --threads 1 --json "$@"; }
for change in nudge jump occluder light; do
  b --change $change > $out/demo_${change}.json
  b --change $change --set reshoot=flagged --set trace_pilots=true > $out/demo_${change}_before.json
done
for change in nudge jump; do
  b --change $change --set reshoot=group > $out/demo_${change}_groups.json
  b --change $change > $out/demo_${change}_2.json
  b --change $change > $out/demo_${change}_3.json
done
b --change jump --set scan_paths=false --set reshoot=group > $out/demo_jump_paper.json
uptime >> $out/load.txt
