#!/usr/bin/env python3
"""Render ONE frame of an animated glTF with Mitsuba 3, using the peer harness's
scene construction (harness/peer_mitsuba.py + gltf_scene.py), and print one JSON line.

  .venv/bin/python mitsuba_frame.py --scene /work/shared/peers/cornell-moving.glb \
      --frame 0 --spp 16 --res 256 --max-depth 8 --threads 2 --out out.exr

Timing fields (wall seconds):
  seconds        the timed mi.render() call only (incl. film develop + copy to numpy);
                 by default it follows a 1-spp warm-up render of the same kernel, so it
                 excludes tracing->LLVM compilation (Dr.Jit keys kernels on the IR, and
                 spp and seed are opaque: one kernel serves every spp/seed/frame).
  seconds_total  process start (incl. Python imports) -> end of the timed render
                 (excludes the EXR write)
  load_s         glTF read + PLY write + mi.load_dict + traverse
  update_s       moving the animated meshes to frame/24 s (vertex update + BVH rebuild)
  warmup_s       the warm-up render (first render in process: IR tracing + compile or
                 kernel-cache load); with --warmup 0 this is 0 and `seconds` includes it
  cpu_s          process CPU seconds (all threads) during the timed render
"""
import time

T_START = time.perf_counter()

import argparse  # noqa: E402
import json  # noqa: E402
import os  # noqa: E402
import resource  # noqa: E402
import sys  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "harness"))


def cpu_s():
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene", default="/work/shared/peers/cornell-moving.glb")
    ap.add_argument("--frame", type=int, default=0)
    ap.add_argument("--fps", type=float, default=24.0)
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--res", type=int, default=256)
    ap.add_argument("--max-depth", type=int, default=8, help="Mitsuba convention: 1 = emitters seen directly")
    ap.add_argument("--threads", type=int, default=2, help="dr.set_thread_count (counts the main thread)")
    ap.add_argument("--variant", default="llvm_ad_rgb")
    ap.add_argument("--seed", type=int, default=None, help="default frame+1 (the harness's 'animated' seed mode)")
    ap.add_argument("--warmup", type=int, default=1, help="warm-up renders (1 spp) before the timed one")
    ap.add_argument("--out", default=None, help="EXR path (float32 RGB)")
    a = ap.parse_args()

    # Keep Dr.Jit's on-disk kernel cache beside this script unless told otherwise.
    os.environ.setdefault("DRJIT_CACHE_DIR", os.path.join(HERE, ".drjit-cache"))

    import peer_mitsuba as pm  # harness: scene dict, per-frame update, render
    from exr_io import write_exr

    pm.RES = a.res              # read by MitsubaAnim._build_dict at construction
    pm.MAX_DEPTH = a.max_depth
    if a.variant.startswith("llvm"):
        pm.pick_libllvm()       # must run before drjit/mitsuba initialise LLVM (needs LLVM >= 16)
    import drjit as dr
    dr.set_thread_count(a.threads)

    t0 = time.perf_counter()
    r = pm.MitsubaAnim(a.variant, a.scene)
    t1 = time.perf_counter()
    r.set_time(a.frame / a.fps)
    t2 = time.perf_counter()
    seed = a.frame + 1 if a.seed is None else a.seed
    for k in range(a.warmup):
        r.render(1, 999_999 + k)
    t3 = time.perf_counter()
    c0 = cpu_s()
    img = r.render(a.spp, seed)
    t4 = time.perf_counter()
    c1 = cpu_s()
    if a.out:
        write_exr(a.out, img)
    print(json.dumps({
        "frame": a.frame, "spp": a.spp, "seconds": round(t4 - t3, 4), "seconds_total": round(t4 - T_START, 4),
        "load_s": round(t1 - t0, 4), "update_s": round(t2 - t1, 4), "warmup_s": round(t3 - t2, 4),
        "cpu_s": round(c1 - c0, 4), "threads": dr.thread_count(), "seed": seed, "res": a.res,
        "max_depth": a.max_depth, "variant": a.variant, "mean": float(img.mean()),
        "loadavg1": round(os.getloadavg()[0], 2), "out": a.out}), flush=True)


if __name__ == "__main__":
    main()
