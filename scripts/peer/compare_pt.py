#!/usr/bin/env python3
"""Chronolux vs Mitsuba 3, path tracing side by side in one run, interleaved.

  .venv/bin/python compare_pt.py --chronolux target/release/chronolux \
      --scene /work/shared/peers/cornell-moving.glb --frames 0,12 --rounds 3 \
      --spp 64 --res 256 --max-depth 8 --threads 2 \
      --refs /work/shared/peers/mitsuba-refs --work /tmp/cmp --out results.json

For each round r and frame f, in this order: ours, then Mitsuba (each a fresh process).
  ours:    chronolux render SCENE --method path --no-denoise --frames f --spp N --resolution RxR --max-depth D
           --threads T --seed r --output WORK/ours_r{r}_f{f} --no-preview
           seconds = run.json's wall_s of the frame (frame build + render + EXR/PNG write;
           scene loading excluded); process_cpu_s = CPU seconds of the whole process
  Mitsuba: mitsuba_frame.py --frame f --spp N ... --seed 1000*r+f+1
           seconds = its timed mi.render() (after a 1-spp warm-up render that compiles
           the kernel; excludes loading, the per-frame BVH update and the EXR write);
           cpu_s = its process CPU seconds during the timed render
Both images are scored against REFS/mitsuba_fNN.exr with relMSE (relmse.py's formula:
mean of (I-R)^2/(R^2+0.01)); efficiency = 1 / (seconds x relMSE). Prints one JSON document
with every measurement, per-frame medians over rounds, and the ratios ours/Mitsuba.
"""
import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "harness"))
from exr_io import read_exr  # noqa: E402
from relmse import hdr_flip, rel_mse  # noqa: E402


def children_cpu_s():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def run(cmd):
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"command failed ({p.returncode}): {' '.join(cmd)}\n{p.stderr}")
    return p.stdout


def score(test, ref, flip):
    import numpy as np
    t = read_exr(test).astype(np.float64)
    r = read_exr(ref).astype(np.float64)
    out = {"relmse": rel_mse(t, r), "mean": float(t.mean())}
    if flip:
        out["hdr_flip"] = hdr_flip(r, t)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--chronolux", required=True)
    ap.add_argument("--scene", default="/work/shared/peers/cornell-moving.glb")
    ap.add_argument("--frames", default="0,12")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--res", type=int, default=256)
    ap.add_argument("--max-depth", type=int, default=8)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--refs", default="/work/shared/peers/mitsuba-refs")
    ap.add_argument("--work", required=True)
    ap.add_argument("--flip", action="store_true", help="also compute HDR-FLIP (1-3 s per image)")
    ap.add_argument("--out", default=None, help="also write the JSON document here")
    ap.add_argument("--bench-pt", action="store_true",
                    help="also time ours with `chronolux bench pt` (render only, no I/O) right after "
                         "each render; its seconds are scored with the render's relMSE (same settings)")
    a = ap.parse_args()
    frames = [int(f) for f in a.frames.split(",")]
    os.makedirs(a.work, exist_ok=True)
    rows = []
    for r in range(a.rounds):
        for f in frames:
            ref = os.path.join(a.refs, f"mitsuba_f{f:02d}.exr")
            # ours
            od = os.path.join(a.work, f"ours_r{r}_f{f}")
            t0 = time.perf_counter()
            c0 = children_cpu_s()
            # The path tracer, undenoised: `render`'s defaults are spacetime-dept + OIDN.
            run([a.chronolux, "render", a.scene, "--method", "path", "--no-denoise",
                 "--frames", str(f), "--spp", str(a.spp),
                 "--resolution", f"{a.res}x{a.res}", "--max-depth", str(a.max_depth),
                 "--threads", str(a.threads), "--seed", str(r), "--output", od, "--no-preview"])
            proc_s = time.perf_counter() - t0
            proc_cpu_s = children_cpu_s() - c0
            man = json.load(open(os.path.join(od, "run.json")))
            rec = next(x for x in man["frames"] if x["frame"] == f)
            ours = {"who": "chronolux", "round": r, "frame": f, "seconds": rec["wall_s"],
                    "process_s": proc_s, "process_cpu_s": proc_cpu_s, "loadavg1": os.getloadavg()[0],
                    **score(os.path.join(od, rec["file_exr"]), ref, a.flip)}
            if a.bench_pt:
                c0 = children_cpu_s()
                bp = json.loads(run([a.chronolux, "bench", "pt", a.scene, "--frames", str(f),
                                     "--spp", str(a.spp), "--resolution", f"{a.res}x{a.res}",
                                     "--max-depth", str(a.max_depth), "--threads", str(a.threads),
                                     "--rounds", "1", "--json"]))
                ours["bench_pt_s"] = bp["frames"][0]["render_s_median"]
                ours["bench_pt_process_cpu_s"] = children_cpu_s() - c0
                ours["bench_pt_msamples_per_s"] = bp["frames"][0]["msamples_per_s"]
                ours["bench_pt_mrays_per_s"] = bp["frames"][0]["mrays_per_s"]
            rows.append(ours)
            print(json.dumps(ours), file=sys.stderr, flush=True)
            # Mitsuba
            mo = os.path.join(a.work, f"mitsuba_r{r}_f{f}.exr")
            line = run([sys.executable, os.path.join(HERE, "mitsuba_frame.py"), "--scene", a.scene,
                        "--frame", str(f), "--spp", str(a.spp), "--res", str(a.res),
                        "--max-depth", str(a.max_depth), "--threads", str(a.threads),
                        "--seed", str(1000 * r + f + 1), "--out", mo]).strip().splitlines()[-1]
            m = json.loads(line)
            mit = {"who": "mitsuba", "round": r, "frame": f, "seconds": m["seconds"],
                   "seconds_total": m["seconds_total"], "update_s": m["update_s"],
                   "cpu_s": m["cpu_s"], "loadavg1": m["loadavg1"], **score(mo, ref, a.flip)}
            rows.append(mit)
            print(json.dumps(mit), file=sys.stderr, flush=True)

    def med(who, f, key):
        return statistics.median(x[key] for x in rows if x["who"] == who and x["frame"] == f)

    summary = {}
    for f in frames:
        s = {}
        for who in ["chronolux", "mitsuba"]:
            eff = [1.0 / (x["seconds"] * x["relmse"]) for x in rows if x["who"] == who and x["frame"] == f]
            s[who] = {"seconds": med(who, f, "seconds"), "relmse": med(who, f, "relmse"),
                      "efficiency_median": statistics.median(eff)}
            s[who]["efficiency_of_medians"] = 1.0 / (s[who]["seconds"] * s[who]["relmse"])
            if a.flip:
                s[who]["hdr_flip"] = med(who, f, "hdr_flip")
        if a.bench_pt:
            eff = [1.0 / (x["bench_pt_s"] * x["relmse"]) for x in rows if x["who"] == "chronolux" and x["frame"] == f]
            s["chronolux"]["bench_pt_s"] = med("chronolux", f, "bench_pt_s")
            s["chronolux"]["bench_pt_efficiency_median"] = statistics.median(eff)
        s["chronolux"]["process_cpu_s"] = med("chronolux", f, "process_cpu_s")
        s["mitsuba"]["cpu_s"] = med("mitsuba", f, "cpu_s")
        c, m = s["chronolux"], s["mitsuba"]
        s["ratio_ours_over_mitsuba"] = {
            "seconds": c["seconds"] / m["seconds"],
            "relmse": c["relmse"] / m["relmse"],
            "efficiency_median": c["efficiency_median"] / m["efficiency_median"],
            "efficiency_of_medians": c["efficiency_of_medians"] / m["efficiency_of_medians"],
            # per-round ratios (measured back to back)
            "efficiency_per_round": [
                (1 / (x["seconds"] * x["relmse"])) / (1 / (y["seconds"] * y["relmse"]))
                for x in rows if x["who"] == "chronolux" and x["frame"] == f
                for y in rows if y["who"] == "mitsuba" and y["frame"] == f and y["round"] == x["round"]],
            # efficiency on CPU-seconds: ours' whole process (loading, EXR/PNG included) vs
            # Mitsuba's timed render
            "efficiency_cpu_per_round": [
                (y["cpu_s"] * y["relmse"]) / (x["process_cpu_s"] * x["relmse"])
                for x in rows if x["who"] == "chronolux" and x["frame"] == f
                for y in rows if y["who"] == "mitsuba" and y["frame"] == f and y["round"] == x["round"]],
        }
        if a.bench_pt:
            s["ratio_ours_over_mitsuba"]["efficiency_bench_pt_per_round"] = [
                (y["seconds"] * y["relmse"]) / (x["bench_pt_s"] * x["relmse"])
                for x in rows if x["who"] == "chronolux" and x["frame"] == f
                for y in rows if y["who"] == "mitsuba" and y["frame"] == f and y["round"] == x["round"]]
            s["ratio_ours_over_mitsuba"]["efficiency_bench_pt_median"] = (
                c["bench_pt_efficiency_median"] / m["efficiency_median"])
        summary[f"frame_{f}"] = s
    cpu = next((ln.split(":", 1)[1].strip() for ln in open("/proc/cpuinfo") if ln.startswith("model name")), "")
    doc = {"date": time.strftime("%Y-%m-%d %H:%M:%S %Z"), "cpu": cpu, "nproc": os.cpu_count(),
           "settings": vars(a), "summary": summary, "runs": rows}
    text = json.dumps(doc, indent=2)
    print(text)
    if a.out:
        with open(a.out, "w") as fh:
            fh.write(text + "\n")


if __name__ == "__main__":
    main()
