#!/usr/bin/env bash
# Chronolux vs Mitsuba 3 (llvm_ad_rgb), measured side by side in one run, interleaved.
#
#   scripts/bench_vs_mitsuba.sh [OUT_DIR]
#
# Environment (all optional):
#   VENV=path        Python 3.11 venv with the peer harness requirements (default
#                    scripts/peer/.venv; created with requirements-nobpy.txt when missing)
#   SCENE=path.glb   default /work/shared/peers/cornell-moving.glb
#   REFS=dir         Mitsuba references, default /work/shared/peers/mitsuba-refs
#   FRAMES=0,12      frames of the path-tracing comparison
#   ROUNDS=3         interleaved rounds (ours, Mitsuba, ours, Mitsuba, ...)
#   SPP=64 THREADS=2 MAX_DEPTH=8 RES=256
#   RAYS=1000000     rays per set of the ray-casting comparison (keep >= 1M: below that
#                    Mitsuba's per-call overhead dominates its timing)
#   BENCH_PT=1       also time ours with `chronolux bench pt` in the path-tracing comparison
#   QUALITY_FRAMES=0..8 TARGETS=0.14,0.10,0.08 QUALITY_STARTS="1 3"
#                    time-to-FLIP (issue 3): frames, target HDR-FLIPs, and the start of each
#                    doubling grid (one interleaved run per start, then pooled); the
#                    references REFS/mitsuba_fNN.exr must exist for these frames
#   SKIP_PT=1 / SKIP_RAYS=1 / SKIP_OURS=1 / SKIP_QUALITY=1   skip a part
#
# Writes OUT_DIR/{machine.txt, pt.json, rays_ours_rN.json, rays_mitsuba_<set>_rN.json,
# ours_rays.json, ours_pt.json, quality_startS.{json,md}, quality_merged.md}; every figure
# in BENCHMARKS.md comes from these files.
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
PEER="$ROOT/scripts/peer"
VENV="${VENV:-$PEER/.venv}"
SCENE="${SCENE:-/work/shared/peers/cornell-moving.glb}"
REFS="${REFS:-/work/shared/peers/mitsuba-refs}"
FRAMES="${FRAMES:-0,12}"
ROUNDS="${ROUNDS:-3}"
SPP="${SPP:-64}"
THREADS="${THREADS:-2}"
MAX_DEPTH="${MAX_DEPTH:-8}"
RES="${RES:-256}"
RAYS="${RAYS:-1000000}"
OUT="${1:-$ROOT/bench-results/$(date +%Y%m%d-%H%M%S)}"
mkdir -p "$OUT"
export DRJIT_CACHE_DIR="${DRJIT_CACHE_DIR:-$PEER/.drjit-cache}"

# 1. Mitsuba: Python 3.11 venv with the harness requirements minus bpy, and LLVM >= 16.
if [ ! -x "$VENV/bin/python" ]; then
    echo "setting up $VENV" >&2
    python3.11 -m venv "$VENV"
    "$VENV/bin/pip" install -q -r "$PEER/requirements-nobpy.txt"
fi
if ! ls -1 /usr/lib/*/libLLVM* 2>/dev/null | grep -Eq 'libLLVM(-|\.so\.)(1[6-9]|[2-9][0-9])'; then
    echo "installing libllvm19 (Dr.Jit's LLVM backend needs LLVM >= 16)" >&2
    apt-get install -y libllvm19
fi
PY="$VENV/bin/python"

# 2. Ours, release build.
cargo build --release -p chronolux --manifest-path "$ROOT/Cargo.toml" >&2
BIN="${CARGO_TARGET_DIR:-$ROOT/target}/release/chronolux"

{
    echo "date: $(date -Iseconds)"
    echo "host nproc: $(nproc)"
    grep -m1 'model name' /proc/cpuinfo
    echo "loadavg at start: $(cat /proc/loadavg)"
    echo "chronolux: $(git -C "$ROOT" rev-parse --short HEAD) $("$BIN" --version)"
    "$PY" -c 'import mitsuba, drjit; print("mitsuba", mitsuba.__version__, "drjit", drjit.__version__)'
} | tee "$OUT/machine.txt" >&2

# 3. Path tracing: efficiency = 1 / (s/frame x relMSE), interleaved rounds.
if [ -z "${SKIP_PT:-}" ]; then
    "$PY" "$PEER/compare_pt.py" --chronolux "$BIN" --scene "$SCENE" --frames "$FRAMES" \
        --rounds "$ROUNDS" --spp "$SPP" --res "$RES" --max-depth "$MAX_DEPTH" \
        --threads "$THREADS" --refs "$REFS" --work "$OUT/pt" --out "$OUT/pt.json" \
        ${BENCH_PT:+--bench-pt} >/dev/null
    "$PY" - "$OUT/pt.json" <<'PYEOF'
import json, sys
d = json.load(open(sys.argv[1]))
for f, s in d["summary"].items():
    c, m, r = s["chronolux"], s["mitsuba"], s["ratio_ours_over_mitsuba"]
    print(f"{f}: ours {c['seconds']:.3f} s relMSE {c['relmse']:.5f} | Mitsuba {m['seconds']:.3f} s "
          f"relMSE {m['relmse']:.5f} | efficiency ours/Mitsuba {r['efficiency_median']:.2f} "
          f"(per round {', '.join(f'{x:.2f}' for x in r['efficiency_per_round'])})")
PYEOF
fi

# 4. Ray casting on the same rays: ours (bench rays, 1 round) then Mitsuba, interleaved.
if [ -z "${SKIP_RAYS:-}" ]; then
    stem="$(basename "${SCENE%.*}")"
    for r in $(seq 1 "$ROUNDS"); do
        "$BIN" bench rays "$SCENE" --rays "$RAYS" --threads "$THREADS" --rounds 1 --json \
            --dump-rays "$OUT/rays" > "$OUT/rays_ours_r$r.json"
        for set in box hemi; do
            "$PY" "$PEER/mitsuba_rays.py" --scene "$SCENE" --frame 0 --threads "$THREADS" \
                --rays "$OUT/rays/${stem}_$set.rays" --reps 1 > "$OUT/rays_mitsuba_${set}_r$r.json"
        done
    done
    "$PY" - "$OUT" "$ROUNDS" <<'PYEOF'
import json, statistics, sys
out, rounds = sys.argv[1], int(sys.argv[2])
med = statistics.median
for s in ["box", "hemi"]:
    ours = [json.load(open(f"{out}/rays_ours_r{r}.json"))["scenes"][0]["sets"][s] for r in range(1, rounds + 1)]
    mit = [json.load(open(f"{out}/rays_mitsuba_{s}_r{r}.json")) for r in range(1, rounds + 1)]
    oc = med(o["closest"]["mrays_per_s_median"] for o in ours)
    osh = med(o["shadow"]["mrays_per_s_median"] for o in ours)
    mp = med(m["ray_intersect_preliminary"]["mrays_per_s"] for m in mit)
    mf = med(m["ray_intersect"]["mrays_per_s"] for m in mit)
    mt = med(m["ray_test"]["mrays_per_s"] for m in mit)
    print(f"{s}: closest ours {oc:.2f} vs Mitsuba preliminary {mp:.2f} / full {mf:.2f} Mrays/s "
          f"(ratio {oc/mp:.2f} / {oc/mf:.2f}); shadow ours {osh:.2f} vs {mt:.2f} (ratio {osh/mt:.2f}); "
          f"hits ours {ours[0]['closest']['hits']} / {ours[0]['shadow']['hits']}, "
          f"Mitsuba {mit[0]['ray_intersect_preliminary']['hits']} / {mit[0]['ray_test']['hits']}")
PYEOF
fi

# 5. Ours alone: rays on the demo and the generated 1M-triangle scene; samples/s on the demo.
if [ -z "${SKIP_OURS:-}" ]; then
    "$BIN" bench rays --threads "$THREADS" --json > "$OUT/ours_rays.json"
    "$BIN" bench pt --spp 16 --resolution 256x256 --max-depth "$MAX_DEPTH" --frames 0..3 \
        --threads "$THREADS" --json > "$OUT/ours_pt.json"
    "$BIN" bench pt "$SCENE" --spp "$SPP" --resolution 256x256 --max-depth "$MAX_DEPTH" \
        --frames 0 --threads "$THREADS" --rounds 3 --json > "$OUT/ours_pt_cornell.json"
fi
# 6. Time to FLIP (issue 3): bench quality vs mitsuba_quality.py, interleaved by level.
if [ -z "${SKIP_QUALITY:-}" ]; then
    QREFS="$OUT/quality_refs"
    mkdir -p "$QREFS"
    "$PY" - "$REFS" "$QREFS" "${QUALITY_FRAMES:-0..8}" <<'PYEOF'
import os, sys
refs, out, fr = sys.argv[1:4]
a, b = fr.split("..=") if "..=" in fr else fr.split("..")
hi = int(b) + 1 if "..=" in fr else int(b)
for f in range(int(a), hi):
    dst = os.path.join(out, f"frame_{f:04d}.exr")
    if not os.path.exists(dst):
        os.symlink(os.path.abspath(os.path.join(refs, f"mitsuba_f{f:02d}.exr")), dst)
PYEOF
    runs=()
    for start in ${QUALITY_STARTS:-1 3}; do
        "$PY" "$PEER/quality_side_by_side.py" --chronolux "$BIN" --scene "$SCENE" \
            --frames "${QUALITY_FRAMES:-0..8}" --reference "$QREFS" \
            --target-flip "${TARGETS:-0.14,0.10,0.08}" --max-depth "$MAX_DEPTH" --threads "$THREADS" \
            --start-effort "$start" --work "$OUT/quality$start" \
            --out "$OUT/quality_start$start.json" --report "$OUT/quality_start$start.md" >/dev/null
        runs+=("$OUT/quality_start$start.json")
    done
    "$PY" "$PEER/quality_merge.py" "${runs[@]}" --md "$OUT/quality_merged.md"
fi
echo "results in $OUT" >&2
