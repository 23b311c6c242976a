#!/usr/bin/env bash
# Issue 38, deliverable 2 (shading and sampling costs cut), in one run: the binary before
# the cuts (OLD) and after (NEW), rounds interleaved, each against Mitsuba 3 on the path
# tracer (scripts/peer/compare_pt.py, cornell-moving frames 0 and 12, 64 spp, 256², max
# depth 8), and the default route's process CPU on the whole 48-frame animation at 256².
#
#   OLD=/path/old/chronolux NEW=target/release/chronolux VENV=/work/.venv-peers \
#       bench-results/2026-12-07-shading/run.sh OUT_DIR [ROUNDS]
set -euo pipefail
OUT=${1:?usage: run.sh OUT_DIR [ROUNDS]}
ROUNDS=${2:-3}
VENV=${VENV:-/work/.venv-peers}
HERE=$(cd "$(dirname "$0")" && pwd)
ROOT=$HERE/../..
SCENE=${SCENE:-$ROOT/../shared/peers/cornell-moving.glb}
REFS=${REFS:-$ROOT/../shared/peers/mitsuba-refs}
mkdir -p "$OUT"
{ date -u; lscpu | grep -E "Model name|Flags"; uptime; } > "$OUT/machine.txt"
for r in $(seq 1 "$ROUNDS"); do
    for who in old new; do
        bin=$OLD; [ $who = new ] && bin=$NEW
        "$VENV/bin/python" "$ROOT/scripts/peer/compare_pt.py" --chronolux "$bin" --scene "$SCENE" \
            --frames 0,12 --rounds 1 --spp 64 --res 256 --max-depth 8 --threads 2 --refs "$REFS" \
            --work "$OUT/pt_tmp" --out "$OUT/pt_${who}_r$r.json" > /dev/null 2>&1
        rm -rf "$OUT/pt_tmp"
    done
done
for r in $(seq 1 "${ROUTE_ROUNDS:-2}"); do
    for who in old new; do
        bin=$OLD; [ $who = new ] && bin=$NEW
        rm -rf "$OUT/route_tmp"
        /usr/bin/time -f "route $who r$r %U %S %e" -a -o "$OUT/route.txt" "$bin" render "$SCENE" \
            --frames 0..48 --max-depth 8 --resolution 256x256 --output "$OUT/route_tmp" > /dev/null 2>&1
    done
done
rm -rf "$OUT/route_tmp"
uptime >> "$OUT/machine.txt"
"$VENV/bin/python" - "$OUT" "$ROUNDS" <<'PY'
import json, statistics, sys
out, rounds = sys.argv[1], int(sys.argv[2])
for who in ["old", "new"]:
    eff = {}
    for r in range(1, rounds + 1):
        d = json.load(open(f"{out}/pt_{who}_r{r}.json"))
        for f, s in d["summary"].items():
            q = s["ratio_ours_over_mitsuba"]
            eff.setdefault(f, {"wall": [], "cpu": [], "relmse_ratio": []})
            eff[f]["wall"] += q["efficiency_per_round"]
            eff[f]["cpu"] += q["efficiency_cpu_per_round"]
            eff[f]["relmse_ratio"].append(q["relmse"])
    for f, e in eff.items():
        print(f"path efficiency {who} {f}: wall {statistics.median(e['wall']):.3f}x Mitsuba, "
              f"CPU {statistics.median(e['cpu']):.3f}x (per round {[round(x, 3) for x in e['cpu']]}), "
              f"relMSE ratio {statistics.median(e['relmse_ratio']):.3f}")
rows = [l.split() for l in open(f"{out}/route.txt") if l.startswith("route")]
cpu = {w: [float(r[3]) + float(r[4]) for r in rows if r[1] == w] for w in ["old", "new"]}
print("default route CPU s old", cpu["old"], "new", cpu["new"],
      f"new/old {statistics.median(cpu['new']) / statistics.median(cpu['old']):.3f}")
PY
