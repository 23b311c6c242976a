#!/usr/bin/env python3
"""Mitsuba 3's side of `chronolux bench quality`: time to reach target HDR-FLIP errors.

  .venv/bin/python mitsuba_quality.py --scene /work/shared/peers/cornell-moving.glb \
      --frames 0..8 --reference REFDIR --target-flip 0.14,0.10,0.08 --max-depth 8 \
      --threads 2 --json --report report.md

The same procedure as `chronolux bench quality` (crates/chronolux/src/quality.rs):
for spp = start, 2·start, 4·start, ... up to --max-effort, every frame of --frames is
rendered independently (mitsuba_frame.py's scene construction: harness/peer_mitsuba.py,
`path` integrator, independent sampler, box filter) and scored against
REFDIR/frame_NNNN.exr; the first level whose mean HDR-FLIP over frames (or the worst
frame with --criterion max) is at or below a target is that target's time. Stops when
every target is met. --start-effort N --max-effort N measures one level only (used to
interleave with our renderer level by level).

Timing per level (wall and process CPU seconds, summed over frames):
  wall_s / cpu_s      mi.render() only (incl. film develop + copy to numpy), as the brief
                      asks; the kernel is compiled by an untimed 1-spp warm-up first
  update_s            moving the animated mesh to the frame's time (vertex update + BVH
                      rebuild: Mitsuba's counterpart of our frame construction, which
                      `bench quality` includes in its wall_s), reported apart
  wall_with_update_s  wall_s + update_s
FLIP: flip-evaluator (HDR mode, linear inputs, negatives clamped, exposure range from the
reference), as relmse.py/harness metrics.py. relMSE and flicker as chronolux_core::metrics
(= harness/metrics.py): flicker = mean over consecutive frame pairs of
mean |(I_t - I_{t-1}) - (R_t - R_{t-1})| / mean(R_t).
Seeds: 1_000_003 * effort + frame + seed (independent across levels and frames).
The JSON has the fields of `chronolux bench quality --json` (method "mitsuba") plus
per-frame FLIP and the extra timing fields above.
"""
import time

T_START = time.perf_counter()

import argparse  # noqa: E402
import json  # noqa: E402
import os  # noqa: E402
import resource  # noqa: E402
import sys  # noqa: E402

import numpy as np  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "harness"))


def cpu_s():
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def parse_frames(s):
    s = s.strip()
    if "..=" in s:
        a, b = s.split("..=")
        return list(range(int(a), int(b) + 1))
    if ".." in s:
        a, b = s.split("..")
        return list(range(int(a), int(b)))
    if "," in s:
        return [int(x) for x in s.split(",")]
    return [int(s)]


def rel_mse(img, ref):
    return float(np.mean((img - ref) ** 2 / (ref ** 2 + 1e-2)))


def flicker(ip, it, rp, rt):
    return float(np.mean(np.abs((it - ip) - (rt - rp))) / rt.mean())


def markdown(res):
    m = res["results"][0]
    s = f"# Equal-quality benchmark: {res['method']}\n\nFrames {res['frames']}, criterion: {res['criterion']} HDR-FLIP over frames.\n\n"
    s += "| target FLIP | mitsuba time (s) | mitsuba effort | mitsuba flicker |\n|---|---|---|---|\n"
    for t, l in zip(res["targets"], m["reached"]):
        if l is None:
            s += f"| {t} | not reached | - | not reached |\n"
        else:
            s += f"| {t} | {l['wall_s']:.2f} | {l['effort']} | {l['flicker']:.4f} |\n"
    s += ("\n## mitsuba: every effort level\n\n| effort | wall (s) | CPU (s) | update (s) | FLIP mean | FLIP max "
          "| relMSE | flicker |\n|---|---|---|---|---|---|---|---|\n")
    for l in m["levels"]:
        s += (f"| {l['effort']} | {l['wall_s']:.2f} | {l['cpu_s']:.2f} | {l['update_s']:.3f} | {l['flip_mean']:.4f} "
              f"| {l['flip_max']:.4f} | {l['relmse_mean']:.5f} | {l['flicker']:.4f} |\n")
    return s


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene", default="/work/shared/peers/cornell-moving.glb")
    ap.add_argument("--frames", required=True, help="A..B (half-open), A..=B, N or a,b,c")
    ap.add_argument("--reference", required=True, help="folder of frame_NNNN.exr")
    ap.add_argument("--target-flip", required=True)
    ap.add_argument("--criterion", default="mean", choices=["mean", "max"])
    ap.add_argument("--start-effort", type=int, default=1)
    ap.add_argument("--max-effort", type=int, default=4096)
    ap.add_argument("--max-depth", type=int, default=8)
    ap.add_argument("--fps", type=float, default=24.0)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--variant", default="llvm_ad_rgb")
    ap.add_argument("--save", default=None, help="write every rendered frame here (fNN_sppN.exr)")
    ap.add_argument("--report", default=None)
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args()
    os.environ.setdefault("DRJIT_CACHE_DIR", os.path.join(HERE, ".drjit-cache"))

    from exr_io import read_exr, write_exr
    from relmse import hdr_flip
    import peer_mitsuba as pm

    frames = parse_frames(a.frames)
    targets_given = [float(t) for t in a.target_flip.split(",")]
    targets = sorted(targets_given, reverse=True)
    refs = [read_exr(os.path.join(a.reference, f"frame_{f:04d}.exr")).astype(np.float64) for f in frames]
    h, w = refs[0].shape[:2]
    assert w == h, "mitsuba_frame.py's scene construction renders square images (RES x RES/aspect)"
    pm.RES = w
    pm.MAX_DEPTH = a.max_depth
    if a.variant.startswith("llvm"):
        pm.pick_libllvm()
    import drjit as dr
    dr.set_thread_count(a.threads)
    r = pm.MitsubaAnim(a.variant, a.scene)
    r.set_time(frames[0] / a.fps)
    t0 = time.perf_counter()
    r.render(1, 999_999)  # untimed warm-up: traces + compiles the kernel (or loads it from the cache)
    warmup_s = time.perf_counter() - t0

    levels, reached = [], [None] * len(targets)
    effort = a.start_effort
    while True:
        imgs, render_s, update_s, cpu = [], 0.0, 0.0, 0.0
        for f in frames:
            t0 = time.perf_counter()
            r.set_time(f / a.fps)
            t1 = time.perf_counter()
            c1 = cpu_s()
            img = r.render(effort, 1_000_003 * effort + f + a.seed).astype(np.float64)
            t2 = time.perf_counter()
            cpu += cpu_s() - c1
            update_s += t1 - t0
            render_s += t2 - t1
            imgs.append(img)
            if a.save:
                os.makedirs(a.save, exist_ok=True)
                write_exr(os.path.join(a.save, f"f{f:02d}_spp{effort}.exr"), img)
        flips = [hdr_flip(R, I) for I, R in zip(imgs, refs)]
        rel = [rel_mse(I, R) for I, R in zip(imgs, refs)]
        fl = [flicker(imgs[k - 1], imgs[k], refs[k - 1], refs[k]) for k in range(1, len(imgs))]
        level = {"effort": effort, "wall_s": render_s, "cpu_s": cpu,
                 "flip_mean": float(np.mean(flips)), "flip_max": float(np.max(flips)),
                 "relmse_mean": float(np.mean(rel)), "flicker": float(np.mean(fl)) if fl else None,
                 "update_s": update_s, "wall_with_update_s": render_s + update_s,
                 "flip_per_frame": flips, "loadavg1": round(os.getloadavg()[0], 2)}
        print(f"mitsuba effort {effort}: {render_s:.2f} s wall (+{update_s:.3f} s update), {cpu:.2f} s CPU, "
              f"FLIP mean {level['flip_mean']:.4f} max {level['flip_max']:.4f}, flicker {level['flicker']}",
              file=sys.stderr, flush=True)
        levels.append(level)
        for k, t in enumerate(targets):
            v = level["flip_max"] if a.criterion == "max" else level["flip_mean"]
            if reached[k] is None and v <= t:
                reached[k] = level
        if all(x is not None for x in reached) or effort >= a.max_effort:
            break
        effort = min(effort * 2, a.max_effort)

    k0 = targets.index(targets_given[0])
    import mitsuba as mi
    res = {"method": "mitsuba", "baseline": None, "criterion": a.criterion, "frames": frames,
           "target_flip": targets_given[0],
           "method_time_s": reached[k0]["wall_s"] if reached[k0] else None,
           "baseline_time_s": None, "speedup": None,
           "method_flicker": reached[k0]["flicker"] if reached[k0] else None, "baseline_flicker": None,
           "targets": targets, "results": [{"method": "mitsuba", "levels": levels, "reached": reached}],
           "peer": {"mitsuba": mi.__version__, "drjit": dr.__version__, "variant": a.variant,
                    "threads": dr.thread_count(), "warmup_s": warmup_s, "load_s": r.load_s,
                    "process_s": time.perf_counter() - T_START}}
    if a.report:
        with open(a.report, "w") as fh:
            fh.write(markdown(res))
    print(json.dumps(res) if a.json else markdown(res), flush=True)


if __name__ == "__main__":
    main()
