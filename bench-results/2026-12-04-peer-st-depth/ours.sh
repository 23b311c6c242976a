# Our configurations of the tenth run (2026-12-04): the eighth/ninth runs' protocol with
# spacetime-dept honouring --max-depth (a3c97e2). Run from the repository root as
#   OURS=bench-results/2026-12-04-peer-st-depth/ours.sh OUT=$PWD/bench-results/2026-12-04-peer-st-depth \
#     BIN=... CM=... REFS=... OIDN_LIB=... bash bench-results/2026-12-03-peer-whole-clip/run.sh
#   python3 bench-results/2026-12-03-peer-whole-clip/summarize.py \
#     bench-results/2026-12-04-peer-st-depth path,il8-k8,st,st-fast > bench-results/2026-12-04-peer-st-depth/summary.md
ours() {
  q ours-$1-path --method path --start-effort 4 --max-effort 8
  q ours-$1-il8-k8 --method stbpt --set window=8 --set interleave=8 --start-effort 1 --max-effort 4
  # spacetime-dept with --max-depth honoured, OIDN high and fast
  q ours-$1-st --method spacetime-dept --set spp=4 --start-effort 32 --max-effort 128
  q ours-$1-st-fast --method spacetime-dept --set spp=4 --denoise-quality fast --start-effort 32 --max-effort 128
  echo "== ours $1 end $(date -u) $(uptime)" >> $OUT/log.txt
}
