#!/usr/bin/env python3
"""Time-to-FLIP, Chronolux's path tracer vs Mitsuba 3, interleaved by effort level.

  .venv/bin/python quality_side_by_side.py --chronolux target/release/chronolux \
      --scene /work/shared/peers/cornell-moving.glb --frames 0..8 --reference REFDIR \
      --target-flip 0.14,0.10,0.08 --max-depth 8 --threads 2 --work OUT/quality \
      --out OUT/quality.json --report OUT/quality.md

For spp = 1, 2, 4, ... (or --start-effort S: S, 2S, 4S, ...; one level per process, so the two alternate under the same load):
  ours:    chronolux bench quality SCENE --frames F --reference REFDIR --target-flip T
           --max-depth D --threads N --start-effort E --max-effort E --json
  Mitsuba: mitsuba_quality.py --scene SCENE --frames F --reference REFDIR --target-flip T
           --max-depth D --threads N --start-effort E --max-effort E --json
Each side stops once its every target is met (or at --max-effort). The time to a target
is the wall time of the first level reaching it, exactly as one `bench quality` run
reports it (levels are independent renders: no level reuses another's samples).
Writes the combined JSON (every level of both, the loadavg before each process) and a
Markdown table: target -> ours time, Mitsuba time, ratio, flicker of both.
"""
import argparse
import json
import os
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))


def run(cmd):
    p = subprocess.run(cmd, capture_output=True, text=True)
    sys.stderr.write(p.stderr)
    if p.returncode != 0:
        sys.exit(f"command failed ({p.returncode}): {' '.join(cmd)}")
    return json.loads(p.stdout.strip().splitlines()[-1])


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--chronolux", required=True)
    ap.add_argument("--scene", default="/work/shared/peers/cornell-moving.glb")
    ap.add_argument("--frames", default="0..8")
    ap.add_argument("--reference", required=True)
    ap.add_argument("--target-flip", default="0.14,0.10,0.08")
    ap.add_argument("--max-depth", type=int, default=8)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--start-effort", type=int, default=1,
                    help="first level (it doubles from there; e.g. 3 gives 3, 6, 12, ... between "
                         "the default run's powers of two)")
    ap.add_argument("--max-effort", type=int, default=512)
    ap.add_argument("--work", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--report", default=None)
    a = ap.parse_args()
    os.makedirs(a.work, exist_ok=True)
    targets = sorted((float(t) for t in a.target_flip.split(",")), reverse=True)
    common = ["--frames", a.frames, "--reference", a.reference, "--target-flip", a.target_flip,
              "--max-depth", str(a.max_depth), "--threads", str(a.threads), "--json"]
    sides = {"ours": {"levels": [], "done": False}, "mitsuba": {"levels": [], "done": False}}
    t_start = time.strftime("%Y-%m-%d %H:%M:%S %Z")
    e = a.start_effort
    while e <= a.max_effort and not all(s["done"] for s in sides.values()):
        lvl = ["--start-effort", str(e), "--max-effort", str(e)]
        for who in ["ours", "mitsuba"]:
            s = sides[who]
            if s["done"]:
                continue
            load = os.getloadavg()[0]
            if who == "ours":
                cmd = [a.chronolux, "bench", "quality", a.scene, *common, *lvl,
                       "--report", os.path.join(a.work, f"ours_spp{e}.md")]
            else:
                cmd = [sys.executable, os.path.join(HERE, "mitsuba_quality.py"), "--scene", a.scene,
                       *common, *lvl, "--report", os.path.join(a.work, f"mitsuba_spp{e}.md")]
            t0 = time.perf_counter()
            res = run(cmd)
            with open(os.path.join(a.work, f"{who}_spp{e}.json"), "w") as fh:
                json.dump(res, fh)
            level = dict(res["results"][0]["levels"][0])
            level["loadavg1_before"] = load
            level["process_s"] = time.perf_counter() - t0
            s["levels"].append(level)
            crit = level["flip_mean"]
            s["done"] = all(crit <= t for t in targets)
            print(f"{who} spp {e}: {level['wall_s']:.2f} s, FLIP {crit:.4f} (load {load:.2f})",
                  file=sys.stderr, flush=True)
        e *= 2

    rows = []
    for t in targets:
        row = {"target": t}
        for who, s in sides.items():
            l = next((l for l in s["levels"] if l["flip_mean"] <= t), None)
            row[who] = None if l is None else {k: l[k] for k in ("effort", "wall_s", "cpu_s", "flip_mean", "flicker")}
        if row["ours"] and row["mitsuba"]:
            row["time_ratio_ours_over_mitsuba"] = row["ours"]["wall_s"] / row["mitsuba"]["wall_s"]
            row["cpu_ratio_ours_over_mitsuba"] = row["ours"]["cpu_s"] / row["mitsuba"]["cpu_s"]
        rows.append(row)
    doc = {"date_start": t_start, "date_end": time.strftime("%Y-%m-%d %H:%M:%S %Z"),
           "settings": vars(a), "targets": rows, "ours": sides["ours"]["levels"],
           "mitsuba": sides["mitsuba"]["levels"]}
    with open(a.out, "w") as fh:
        json.dump(doc, fh, indent=1)

    def f(x, d=2):
        return "not reached" if x is None else f"{x:.{d}f}"

    md = ("| target HDR-FLIP (mean over frames) | ours spp | ours time (s) | Mitsuba spp | Mitsuba time (s) "
          "| **time ours / Mitsuba** | CPU-s ours / Mitsuba | ours flicker | Mitsuba flicker |\n"
          "|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n")
    for r in rows:
        o, m = r["ours"] or {}, r["mitsuba"] or {}
        md += (f"| {r['target']} | {o.get('effort', '-')} | {f(o.get('wall_s'))} | {m.get('effort', '-')} "
               f"| {f(m.get('wall_s'))} | **{f(r.get('time_ratio_ours_over_mitsuba'))}** "
               f"| {f(r.get('cpu_ratio_ours_over_mitsuba'))} | {f(o.get('flicker'), 4)} | {f(m.get('flicker'), 4)} |\n")
    md += ("\nEvery level (wall and CPU seconds of the 8-frame render, FLIP mean over frames, "
           "loadavg before the process):\n\n| spp | ours wall | ours CPU | ours FLIP | ours flicker | ours load "
           "| Mitsuba wall | Mitsuba CPU | Mitsuba FLIP | Mitsuba flicker | Mitsuba load |\n"
           "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n")
    effs = sorted({l["effort"] for s in sides.values() for l in s["levels"]})
    for e in effs:
        o = next((l for l in sides["ours"]["levels"] if l["effort"] == e), {})
        m = next((l for l in sides["mitsuba"]["levels"] if l["effort"] == e), {})
        md += (f"| {e} | {f(o.get('wall_s'))} | {f(o.get('cpu_s'))} | {f(o.get('flip_mean'), 4)} "
               f"| {f(o.get('flicker'), 4)} | {f(o.get('loadavg1_before'), 1)} | {f(m.get('wall_s'))} "
               f"| {f(m.get('cpu_s'))} | {f(m.get('flip_mean'), 4)} | {f(m.get('flicker'), 4)} "
               f"| {f(m.get('loadavg1_before'), 1)} |\n")
    if a.report:
        with open(a.report, "w") as fh:
            fh.write(md)
    print(md)


if __name__ == "__main__":
    main()
