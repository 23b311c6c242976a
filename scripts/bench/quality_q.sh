# Sourced by the A/B scripts under bench-results/: `q NAME BIN ARGS...` runs
# `BIN bench quality ARGS... --target-flip 0.05 --json` into $OUT/NAME.json (stderr in
# $OUT/NAME.err) and prints one line per effort level: CPU s, FLIP, relMSE, flicker.
q() { # name bin args...
  local name=$1 bin=$2; shift 2
  "$bin" bench quality "$@" --target-flip 0.05 --json > "$OUT/$name.json" 2> "$OUT/$name.err"
  python3 - "$OUT/$name.json" "$name" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
for l in d["results"][0]["levels"]:
    print(f'{sys.argv[2]:28s} effort {l["effort"]:3d} CPU {l["cpu_s"]:7.2f} s  FLIP {l["flip_mean"]:.4f}  relMSE {l["relmse_mean"]:.4e}  flicker {l["flicker"]:.4f}')
PY
}
