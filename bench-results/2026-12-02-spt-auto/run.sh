#!/bin/bash
# Issue 11 item 6 again, with the automatic element count (87eada2) for all three: spt
# against dept-spatial (one bench run), then spacetime-dept alone; the demo, 64x64,
# frames 0-7, --threads 1, the same commands as the first run (BENCHMARKS, issue 11).
cd "$(dirname "$0")"
B=${B:?chronolux binary}; R=${R:-/work/refs/ref-demo-64}
{ date -u; uptime; } > log.txt
$B bench quality --resolution 64x64 --method spt --baseline dept-spatial --reference $R --frames 0..8 \
  --target-flip 0.2,0.15,0.12,0.1,0.09,0.08 --start-effort 8 --max-effort 256 --threads 1 --json > spt-dept.json 2> spt-dept.err
$B bench quality --resolution 64x64 --method spacetime-dept --reference $R --frames 0..8 \
  --target-flip 0.2,0.15,0.12,0.1,0.09,0.08 --start-effort 8 --max-effort 256 --threads 1 --json > st.json 2> st.err
{ date -u; uptime; } >> log.txt
