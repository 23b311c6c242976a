#!/usr/bin/env python3
"""Mitsuba 3 ray casting on the SAME rays `chronolux bench rays --dump-rays DIR` traced.

  .venv/bin/python mitsuba_rays.py --scene SCENE.glb --frame F --rays DIR/cornell-moving_box.rays \
      --threads 2 --reps 3

Builds the Mitsuba scene with the peer harness (harness/peer_mitsuba.py, the scene the
Mitsuba references were rendered from), moves it to frame F, loads the rays (little-endian
f32 ox oy oz dx dy dz) and times, after one untimed call each (tracing + LLVM compile):
  ray_intersect_preliminary  closest hit: t, primitive, barycentrics (what our
                             FrameScene::intersect returns)
  ray_intersect              closest hit plus the full SurfaceInteraction
  ray_test                   any hit (shadow rays), tmax = inf
Prints one JSON line with the median seconds, Mrays/s, hit counts and Σt (compare them with
DIR/<scene>_<set>.json to check both renderers did the same work).

Timed: the query and its outputs only (the rays are uploaded and evaluated before), in wall
seconds and in process CPU seconds (`time.process_time`, all threads). Compare CPU seconds:
Dr.Jit's pool runs `--threads` workers and the calling thread helps with the work while it
waits, so its wall time on a 2-CPU machine shared with other sessions is not ours.
"""
import argparse
import json
import os
import statistics
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "harness"))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene", default="/work/shared/peers/cornell-moving.glb")
    ap.add_argument("--frame", type=int, default=0)
    ap.add_argument("--fps", type=float, default=24.0)
    ap.add_argument("--rays", required=True, help="ray file written by chronolux bench rays --dump-rays")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--variant", default="llvm_ad_rgb")
    a = ap.parse_args()
    os.environ.setdefault("DRJIT_CACHE_DIR", os.path.join(HERE, ".drjit-cache"))

    import peer_mitsuba as pm
    if a.variant.startswith("llvm"):
        pm.pick_libllvm()
    import drjit as dr
    dr.set_thread_count(a.threads)
    r = pm.MitsubaAnim(a.variant, a.scene)
    mi = r.mi
    r.set_time(a.frame / a.fps)
    scene = r.scene

    raw = np.fromfile(a.rays, dtype="<f4").reshape(-1, 6)
    n = raw.shape[0]
    o = mi.Point3f(*[mi.Float(np.ascontiguousarray(raw[:, k])) for k in range(3)])
    d = mi.Vector3f(*[mi.Float(np.ascontiguousarray(raw[:, 3 + k])) for k in range(3)])
    dr.eval(o, d)
    dr.sync_thread()
    ray = mi.Ray3f(o, d)

    def run(kind):
        c0 = time.process_time()
        t0 = time.perf_counter()
        if kind == "ray_intersect_preliminary":
            pi = scene.ray_intersect_preliminary(ray)
            dr.eval(pi.t, pi.prim_index, pi.prim_uv)
            res = pi.t
        elif kind == "ray_intersect":
            si = scene.ray_intersect(ray)
            dr.eval(si.t, si.p, si.n, si.sh_frame.n, si.uv)
            res = si.t
        else:
            res = scene.ray_test(ray)
            dr.eval(res)
        dr.sync_thread()
        return time.perf_counter() - t0, time.process_time() - c0, res

    out = {"peer": "mitsuba", "variant": a.variant, "rays_file": a.rays, "n": n,
           "frame": a.frame, "threads": dr.thread_count(),
           "loadavg1": round(os.getloadavg()[0], 2)}
    for kind in ["ray_intersect_preliminary", "ray_intersect", "ray_test"]:
        times, cpu = [], []
        for k in range(a.reps + 1):
            dt, dc, res = run(kind)
            if k > 0:  # the first call traces and compiles the kernel (or loads it from the cache)
                times.append(dt)
                cpu.append(dc)
        res = np.array(res)
        rec = {"median_s": statistics.median(times), "seconds": times,
               "median_cpu_s": statistics.median(cpu), "cpu_seconds": cpu}
        rec["mrays_per_s"] = n / rec["median_s"] / 1e6
        rec["mrays_per_cpu_s"] = n / rec["median_cpu_s"] / 1e6
        if kind == "ray_test":
            rec["hits"] = int(res.sum())
            rec["hit_fraction"] = rec["hits"] / n
        else:
            hit = np.isfinite(res) & (res < 1e30)
            rec["hits"] = int(hit.sum())
            rec["hit_fraction"] = rec["hits"] / n
            rec["sum_t"] = float(res[hit].astype(np.float64).sum())
        out[kind] = rec
    print(json.dumps(out), flush=True)


if __name__ == "__main__":
    main()
