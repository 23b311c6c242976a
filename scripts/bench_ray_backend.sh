#!/usr/bin/env bash
# Issue 38 in one run: the ray-query backends (Embree, the own BVH) against Mitsuba 3 on the
# same rays, and the path tracer's efficiency against Mitsuba on cornell-moving with each
# backend. Rounds interleaved (ours own BVH, ours Embree, Mitsuba), so all three see the
# same machine state.
#
#   VENV=/work/.venv-peers scripts/bench_ray_backend.sh OUT_DIR [ROUNDS]
#
# VENV: a virtual environment with scripts/peer/requirements-nobpy.txt (Mitsuba 3, flip).
# RAYS_ONLY=1: the ray part only (no path tracing, no default route).
# BIN_OLD=PATH: a second chronolux (the baseline of an A/B), traced on Embree in every round
#   right before BIN, so both see the same machine state; reported as "embree-old".
# Rays are compared in process CPU seconds (both sides pinned to --threads 2; the machine is
# shared); each round runs 3 timed passes per query on both sides and keeps the median.
set -euo pipefail
OUT=${1:?usage: bench_ray_backend.sh OUT_DIR [ROUNDS]}
ROUNDS=${2:-3}
VENV=${VENV:-/work/.venv-peers}
HERE=$(cd "$(dirname "$0")" && pwd)
BIN=${BIN:-$HERE/../target/release/chronolux}
SCENE=${SCENE:-$HERE/../../shared/peers/cornell-moving.glb}
REFS=${REFS:-$HERE/../../shared/peers/mitsuba-refs}
mkdir -p "$OUT/rays"
{ date -u; lscpu | grep -E "Model name|Flags"; uptime; git -C "$HERE/.." rev-parse HEAD; } > "$OUT/machine.txt"
"$BIN" bench rays "$SCENE" --rays 1000000 --threads 2 --rounds 1 --dump-rays "$OUT/rays" > /dev/null
ACCELS="bvh embree"
[ -n "${BIN_OLD:-}" ] && ACCELS="bvh embree-old embree"
for r in $(seq 1 "$ROUNDS"); do
    for accel in $ACCELS; do
        bin=$BIN
        [ "$accel" = embree-old ] && bin=$BIN_OLD
        CHRONOLUX_ACCEL=${accel%-old} "$bin" bench rays "$SCENE" --rays 1000000 --threads 2 --rounds 3 --json \
            > "$OUT/rays_${accel}_r$r.json"
    done
    for set in box hemi; do
        "$VENV/bin/python" "$HERE/peer/mitsuba_rays.py" --scene "$SCENE" --frame 0 --threads 2 \
            --rays "$OUT/rays/cornell-moving_$set.rays" --reps 3 | tail -1 > "$OUT/rays_mitsuba_${set}_r$r.json"
    done
done
summary() {
"$VENV/bin/python" - "$OUT" "$ROUNDS" "$ACCELS" <<'PY'
import json, statistics, sys
out, rounds, accels = sys.argv[1], int(sys.argv[2]), sys.argv[3].split()
med = statistics.median
R = range(1, rounds + 1)
for s in ["box", "hemi"]:
    mit = [json.load(open(f"{out}/rays_mitsuba_{s}_r{r}.json")) for r in R]
    # Per round: ours / Mitsuba's rays per CPU second; the median over rounds.
    mc = [m["ray_intersect_preliminary"]["mrays_per_cpu_s"] for m in mit]
    ms = [m["ray_test"]["mrays_per_cpu_s"] for m in mit]
    print(f"{s} Mitsuba: closest {med(mc):.2f}, shadow {med(ms):.2f} M rays per CPU s; hits "
          f"{mit[0]['ray_intersect_preliminary']['hit_fraction']:.4f} / {mit[0]['ray_test']['hit_fraction']:.4f}")
    for accel in accels:
        ours = [json.load(open(f"{out}/rays_{accel}_r{r}.json"))["scenes"][0]["sets"][s] for r in R]
        cells = []
        for k, m in [("closest", mc), ("shadow", ms), ("closest_packets", mc), ("shadow_packets", ms)]:
            rate = [o[k]["mrays_per_cpu_s_median"] for o in ours]
            ratio = [a / b for a, b in zip(rate, m)]
            cells.append(f"{k} {med(rate):.2f} ({med(ratio):.2f}x, rounds {min(ratio):.2f}-{max(ratio):.2f})")
        print(f"{s} {accel}: " + ", ".join(cells) + f"; hits {ours[0]['closest']['hit_fraction']:.4f} / {ours[0]['shadow']['hit_fraction']:.4f}")
PY
}
if [ -n "${RAYS_ONLY:-}" ]; then
    uptime >> "$OUT/machine.txt"
    summary
    exit 0
fi
for accel in embree bvh; do
    CHRONOLUX_ACCEL=$accel "$VENV/bin/python" "$HERE/peer/compare_pt.py" --chronolux "$BIN" \
        --scene "$SCENE" --frames 0,12 --rounds "$ROUNDS" --spp 64 --res 256 --max-depth 8 \
        --threads 2 --refs "$REFS" --work "$OUT/pt_$accel" --out "$OUT/pt_$accel.json" > /dev/null
done
# The default route (`render` with nothing but the resolution) on each backend: process CPU
# seconds of the whole 48-frame animation, interleaved.
for r in $(seq 1 "${ROUTE_ROUNDS:-2}"); do
    for res in 256 512; do
        for accel in bvh embree; do
            rm -rf "$OUT/route_tmp"
            CHRONOLUX_ACCEL=$accel /usr/bin/time -f "route $res $accel r$r %U %S %e" -a -o "$OUT/route.txt" \
                "$BIN" render "$SCENE" --frames 0..48 --max-depth 8 --resolution ${res}x${res} \
                --output "$OUT/route_tmp" > /dev/null 2>&1
        done
    done
done
rm -rf "$OUT/route_tmp"
uptime >> "$OUT/machine.txt"
summary
"$VENV/bin/python" - "$OUT" <<'PY'
import json, sys
out = sys.argv[1]
for accel in ["embree", "bvh"]:
    d = json.load(open(f"{out}/pt_{accel}.json"))
    for f, v in d["summary"].items():
        r = v["ratio_ours_over_mitsuba"]
        print(f"path {accel} {f}: ours {v['chronolux']['seconds']:.2f} s relMSE {v['chronolux']['relmse']:.2e}, "
              f"Mitsuba {v['mitsuba']['seconds']:.2f} s relMSE {v['mitsuba']['relmse']:.2e}; efficiency ratio "
              f"{r['efficiency_median']:.2f} (wall), CPU per round {[round(x, 2) for x in r['efficiency_cpu_per_round']]}")
PY
awk '{cpu[$2" "$3]=cpu[$2" "$3]" "($5+$6)} END {for (k in cpu) print "route", k, "CPU s:", cpu[k]}' "$OUT/route.txt" | sort
