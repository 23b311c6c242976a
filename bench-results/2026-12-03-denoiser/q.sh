# Sourced by fast.sh, cleanaux-ab.sh and quality-option.sh: q BIN NAME ARGS... runs the peer
# protocol of ../2026-12-03-peer-whole-clip/run.sh (cornell-moving, 48 frames rendered, the
# 12 with Mitsuba references scored, --denoise) into $OUT/NAME.json (stderr NAME.err).
q() { local bin=$1 name=$2; shift 2
  "$bin" bench quality "$CM" --frames 0..48 --measure 0..8,12,24,36,47 --reference "$REFS" \
    --max-depth 8 --threads 2 --denoise --target-flip 0.08 "$@" --json > "$OUT/$name.json" 2> "$OUT/$name.err"; }
IL8="--method stbpt --set window=8 --set interleave=8 --start-effort 1 --max-effort 4"
PATH_ARGS="--method path --start-effort 4 --max-effort 8"
