#!/usr/bin/env python3
"""`bench suite`: the issue-40 suite of animations, Chronolux side by side with Blender Cycles 5
+ OpenImageDenoise, every figure measured in this one run. Run it with the peers venv's Python
(numpy, OpenEXR, flip-evaluator; bpy for Cycles):

    /work/.venv-peers/bin/python scripts/suite/run.py --bin target/release/chronolux \\
        --out bench-results/DATE-suite [--res 512] [--scenes a,b] [--update-benchmarks BENCHMARKS.md]

What it measures, for each scene of manifest.json (scenes that do not exist yet are made by
make_scenes.py into --work):

1. References, each renderer its own, of the scored frames (--scored) only:
   ours by `chronolux reference --max-spp --target-error --max-depth 8` (one call per frame);
   Cycles' by cycles_suite.py ref (--cycles-ref-spp in passes of --cycles-pass-spp, fixed seeds,
   no denoiser). Their own remaining noise is recorded (relMSE estimates from the halves, and
   the HDR-FLIP of half A against half B).
2. Fidelity: mean HDR-FLIP of our converged reference against Cycles' (Cycles' as the
   reference image) and the ratio of their mean pixel values: how far the two renderers'
   pictures of the same glTF are apart. It is not noise: each renderer is scored against its
   own reference below, so material or light-model differences do not count as error.
3. Ours, the default route, literally: `chronolux render SCENE --frames F --max-depth 8
   --resolution RxR -o DIR` (the default method at the default quality for that pixel count,
   OIDN as the build found it, EXR + PNG + preview written), CPU = user + sys of /usr/bin/time
   over ALL the frames of F (whole windows), times scored / rendered frames (what the scored
   frames cost of a long animation); FLIP and flicker of the scored frames against our
   reference.
4. Ours, `chronolux bench quality` along that same route's photon axis (the technique and its
   settings read from the literal run's run.json; all frames of F rendered, the scored ones
   measured, CPU scaled the same way), so that the CPU to exactly FLIP 0.08 and 0.05 is
   interpolated (log-log) as for the peer.
5. Ours, `path` + OIDN (`bench quality --method path --denoise`, frame by frame: only the
   scored frames rendered), at doubling spp.
6. Cycles + OIDN at doubling spp (cycles_suite.py ttf --denoise): CPU of the scored frames'
   render calls (scene sync, denoiser, EXR writing included), against Cycles' own reference.

Ratios are CPU seconds of the other / ours at equal FLIP (> 1: ours needs less); flicker ratio
is our flicker at that FLIP / Cycles' at that FLIP. "<=" marks a figure already met by the
cheapest level (an upper bound), "n.r." a FLIP not reached by the dearest level.
Writes OUT/suite.json, OUT/table.md, OUT/machine.txt, per-scene logs and JSON (the renders
themselves stay in --work); with --update-benchmarks, replaces the block between
`<!-- suite-table:begin -->` and `<!-- suite-table:end -->` of that file with the table.
A step whose JSON already exists in OUT is not run again (delete it to redo it).

--scale SCENE: also render SCENE at 1920x1080 for --scale-frames frames with the default
route under /usr/bin/time -v: CPU per frame, peak resident memory, bytes written.
"""
import argparse
import datetime
import json
import os
import re
import shutil
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)


def die(msg):
    sys.exit(f"run.py: {msg}")


try:
    import numpy as np
    import flip_evaluator  # noqa: F401
    import OpenEXR  # noqa: F401
except ImportError as e:
    die(f"{e}: run this with the peers venv's Python. Make it once with: python3 -m venv /work/.venv-peers && "
        "/work/.venv-peers/bin/pip install -r ../shared/peers/harness/requirements.txt")
from suite_metrics import flicker, flip, interp, read_beauty  # noqa: E402

TARGETS = (0.08, 0.05)


def log(out, msg):
    line = f"{datetime.datetime.now(datetime.timezone.utc):%H:%M:%S} load {os.getloadavg()[0]:.1f} {msg}"
    print(line, flush=True)
    with open(os.path.join(out, "log.txt"), "a") as f:
        f.write(line + "\n")


def run(cmd, stdout=None, stderr=None, check=True):
    r = subprocess.run(cmd, stdout=stdout, stderr=stderr, text=True)
    if check and r.returncode != 0:
        tail = ""
        if stderr is not None and hasattr(stderr, "name"):
            stderr.flush()
            tail = open(stderr.name).read()[-2000:]
        die(f"command failed ({r.returncode}): {' '.join(cmd)}\n{tail}")
    return r


def frame_range(s):
    m = re.fullmatch(r"(\d+)\.\.(\d+)", s)
    if not m:
        die(f"--frames {s}: give A..B (half-open)")
    return list(range(int(m.group(1)), int(m.group(2))))


def measure_arg(frames):
    """0,1,2,23,24 -> '0..3,23..25' (bench quality's --measure syntax)."""
    out, i = [], 0
    while i < len(frames):
        j = i
        while j + 1 < len(frames) and frames[j + 1] == frames[j] + 1:
            j += 1
        out.append(str(frames[i]) if i == j else f"{frames[i]}..{frames[j] + 1}")
        i = j + 1
    return ",".join(out)


def cpu_time(path):
    t = dict(re.findall(r"(\w+) ([\d.]+)", open(path).read()))
    return float(t["user_s"]) + float(t["sys_s"]), float(t["wall_s"]), int(float(t.get("maxrss_kb", 0)))


def score(dir_img, name_img, refs, frames):
    imgs = [read_beauty(os.path.join(dir_img, name_img.format(f))) for f in frames]
    flips = [flip(r, i) for r, i in zip(refs, imgs)]
    return float(np.mean(flips)), flicker(imgs, refs, frames)


def ours_reference(a, sc, work, frames):
    d = os.path.join(work, "ref-ours")
    os.makedirs(d, exist_ok=True)
    info = {}
    for f in frames:
        fd = os.path.join(d, f"f{f:04d}")
        if not os.path.exists(os.path.join(fd, f"frame_{f:04d}.exr")):
            with open(os.path.join(work, "ref-ours.log"), "a") as lg:
                run([a.bin, "reference", sc["path"], *sc.get("args", []), "--frames", f"{f}..{f + 1}",
                     "--resolution", f"{a.res}x{a.res}", "--max-depth", "8", "--max-spp", str(a.ours_ref_spp),
                     "--target-error", str(a.ours_ref_error), "--threads", str(a.threads), "-o", fd],
                    stdout=lg, stderr=lg)
        link = os.path.join(d, f"frame_{f:04d}.exr")
        if not os.path.exists(link):
            os.symlink(os.path.join(fd, f"frame_{f:04d}.exr"), link)
        rj = json.load(open(os.path.join(fd, "run.json")))
        info[f] = rj
    return d, info


def halves_flip(d, frames, pattern_a, pattern_b, refs):
    """HDR-FLIP of half A against half B, mean over frames (the reference's own noise, ~2x it)."""
    v = []
    for f in frames:
        pa, pb = os.path.join(d, pattern_a.format(f)), os.path.join(d, pattern_b.format(f))
        if os.path.exists(pa) and os.path.exists(pb):
            v.append(flip(read_beauty(pa), read_beauty(pb)))
    return float(np.mean(v)) if v else None


def flicker_floor(d, frames, pattern_a, pattern_b):
    """What a reference's own noise adds to the flicker figure (harness metrics.py):
    mean over consecutive pairs of mean |((A_t - A_t-1) - (B_t - B_t-1)) / 2| / mean(R_t)."""
    v = []
    for k in range(1, len(frames)):
        if frames[k] != frames[k - 1] + 1:
            continue
        A = [read_beauty(os.path.join(d, pattern_a.format(f))) for f in frames[k - 1:k + 1]]
        B = [read_beauty(os.path.join(d, pattern_b.format(f))) for f in frames[k - 1:k + 1]]
        R = 0.5 * (A[1] + B[1])
        v.append(float(np.mean(np.abs(((A[1] - A[0]) - (B[1] - B[0])) / 2)) / R.mean()))
    return float(np.mean(v)) if v else None


def machine(out):
    lines = [f"date {datetime.datetime.now(datetime.timezone.utc).isoformat()}"]
    try:
        lines.append("commit " + subprocess.run(["git", "rev-parse", "HEAD"], capture_output=True, text=True).stdout.strip())
        lines.append("uptime " + subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip())
        ls = subprocess.run(["lscpu"], capture_output=True, text=True).stdout
        lines += [l for l in ls.splitlines() if re.match(r"(Model name|CPU\(s\))", l)]
    except FileNotFoundError:
        pass
    flags = sorted(set(re.findall(r"\bavx512\w*", open("/proc/cpuinfo").read())))
    lines.append("avx512: " + (" ".join(flags) if flags else "none"))
    model = next((l.split(":", 1)[1].strip() for l in lines if l.startswith("Model name")), "unknown CPU")
    open(os.path.join(out, "machine.txt"), "w").write("\n".join(lines) + "\n")
    return model, flags


def scene_run(a, sc, out, work):
    name = sc["name"]
    so, sw = os.path.join(out, name), os.path.join(work, name)
    os.makedirs(so, exist_ok=True)
    os.makedirs(sw, exist_ok=True)
    frames = frame_range(a.frames)
    scored = [int(x) for x in a.scored.split(",")]
    res = {"name": name, "scene": sc["file"], "what": sc["what"], "res": a.res, "frames": a.frames, "scored": scored}
    R = f"{a.res}x{a.res}"
    py = sys.executable
    cyc = os.path.join(HERE, "cycles_suite.py")
    do_cycles = sc.get("cycles", True) and not a.no_cycles

    # 1. references
    log(out, f"{name}: our reference")
    dref, refinfo = ours_reference(a, sc, sw, scored)
    refs = [read_beauty(os.path.join(dref, f"frame_{f:04d}.exr")) for f in scored]
    res["ref_ours"] = {"max_spp": a.ours_ref_spp, "target_error": a.ours_ref_error,
                       "frames": {f: ri.get("frames") for f, ri in refinfo.items()}}
    res["ref_ours"]["halves_flip"] = halves_flip(dref, scored, "f{0:04d}/frame_{0:04d}_A.exr",
                                                 "f{0:04d}/frame_{0:04d}_B.exr", refs)
    res["ref_ours"]["flicker_floor"] = flicker_floor(dref, scored, "f{0:04d}/frame_{0:04d}_A.exr",
                                                     "f{0:04d}/frame_{0:04d}_B.exr")
    if do_cycles:
        cref = os.path.join(sw, "ref-cycles")
        if not os.path.exists(os.path.join(cref, "ref.json")):
            log(out, f"{name}: Cycles reference")
            with open(os.path.join(so, "cycles-ref.err"), "w") as e:
                run([py, cyc, "ref", sc["path"], "--res", str(a.res), "--frames", a.scored, "--spp",
                     str(a.cycles_ref_spp), "--pass-spp", str(a.cycles_pass_spp), "--out", cref], stdout=e, stderr=e)
        shutil.copy(os.path.join(cref, "ref.json"), os.path.join(so, "cycles-ref.json"))
        crefs = [read_beauty(os.path.join(cref, f"frame_{f:04d}.exr")) for f in scored]
        res["ref_cycles"] = json.load(open(os.path.join(cref, "ref.json")))
        res["ref_cycles"]["halves_flip"] = halves_flip(cref, scored, "frame_{:04d}_A.exr", "frame_{:04d}_B.exr", crefs)
        res["ref_cycles"]["flicker_floor"] = flicker_floor(cref, scored, "frame_{:04d}_A.exr", "frame_{:04d}_B.exr")
        res["fidelity_flip"] = float(np.mean([flip(c, o) for c, o in zip(crefs, refs)]))
        res["fidelity_mean_ratio"] = float(np.mean([o.mean() / c.mean() for c, o in zip(crefs, refs)]))

    # 3. ours, literally
    lit = os.path.join(so, "literal.json")
    if not os.path.exists(lit):
        log(out, f"{name}: ours, the literal render")
        d = os.path.join(sw, "render")
        shutil.rmtree(d, ignore_errors=True)
        tf = os.path.join(so, "literal.time")
        with open(os.path.join(so, "literal.log"), "w") as lg:
            run(["/usr/bin/time", "-f", "wall_s %e user_s %U sys_s %S maxrss_kb %M", "-o", tf, a.bin, "render",
                 sc["path"], *sc.get("args", []), *ours_set(a), "--frames", a.frames, "--max-depth", "8",
                 "--resolution", R, "-o", d], stdout=lg, stderr=lg)
        shutil.copy(os.path.join(d, "run.json"), os.path.join(so, "literal.run.json"))
        cpu, wall, rss = cpu_time(tf)
        fl, fk = score(d, "frame_{:04d}.exr", refs, scored)
        json.dump({"cpu_s_all": cpu, "wall_s": wall, "maxrss_kb": rss, "frames_rendered": len(frames),
                   "cpu_s_scored": cpu * len(scored) / len(frames), "flip": fl, "flicker": fk}, open(lit, "w"), indent=1)
    res["literal"] = json.load(open(lit))
    # frames the default route rendered as `path` (its path probe found nothing to reuse)
    res["literal"]["frames_as_path"] = open(os.path.join(so, "literal.log")).read().count("rendered as path")
    rj = json.load(open(os.path.join(so, "literal.run.json")))
    res["route"] = route = route_of(rj)

    # 4. and 5. bench quality: the route along its effort axis, and path + OIDN
    def quality(tag, method_args, start, stop):
        p = os.path.join(so, f"{tag}.json")
        if not os.path.exists(p):
            log(out, f"{name}: bench quality {tag}")
            with open(p + ".tmp", "w") as o, open(os.path.join(so, f"{tag}.err"), "w") as e:
                run([a.bin, "bench", "quality", sc["path"], *sc.get("args", []), "--frames", a.frames,
                     "--measure", measure_arg(scored), "--reference", dref, "--max-depth", "8", "--resolution", R,
                     "--threads", str(a.threads), "--denoise", "--target-flip", ",".join(map(str, TARGETS)),
                     *method_args, "--start-effort", str(start), "--max-effort", str(stop), "--json"], stdout=o, stderr=e)
            os.replace(p + ".tmp", p)
        q = json.load(open(p))
        m = q["results"][0]
        # a level's cpu_s is its whole run's: charged per scored frame as bench quality does
        levels = [{"effort": lv["effort"], "cpu_s": lv["cpu_s"] * lv["frames_scored"] / lv["frames_rendered"],
                   "cpu_s_run": lv["cpu_s"], "frames_rendered": lv["frames_rendered"], "flip": lv["flip_mean"],
                   "flicker": lv.get("flicker")} for lv in m["levels"]]
        return {"levels": levels, "bench_interpolated_cpu_s": m.get("interpolated_cpu_s"),
                **{str(t): at(levels, t) for t in TARGETS}}

    res["ours_route"] = quality("route", route["args"] + ours_set(a), route["start"], route["stop"])
    res["path_oidn"] = quality("path", ["--method", "path"], 1, a.path_max_spp)

    # 6. Cycles + OIDN
    if do_cycles:
        p = os.path.join(so, "cycles.json")
        if not os.path.exists(p):
            log(out, f"{name}: Cycles + OIDN at doubling spp")
            with open(p + ".tmp", "w") as o, open(os.path.join(so, "cycles.err"), "w") as e:
                run([py, cyc, "ttf", sc["path"], "--res", str(a.res), "--frames", a.scored, "--levels", a.cycles_levels,
                     "--refs", os.path.join(sw, "ref-cycles"), "--denoise",
                     "--targets", ",".join(map(str, TARGETS))], stdout=o, stderr=e)
            os.replace(p + ".tmp", p)
        c = json.loads(open(p).read().strip().splitlines()[-1])
        res["cycles_oidn"] = {"levels": c["levels"], **{str(t): at(c["levels"], t) for t in TARGETS}}
    json.dump(res, open(os.path.join(so, "result.json"), "w"), indent=1)
    return res


def ours_set(a):
    """--set KEY=VALUE arguments for our default route (--ours-set), e.g. an A/B of one setting."""
    return [x for kv in a.ours_set for x in ("--set", kv)]


def at(levels, t):
    cpu, bound = interp(levels, t)
    fk, _ = interp(levels, t, "flicker")
    return {"cpu_s": cpu, "bound": bound, "flicker": fk}


def route_of(rj):
    """The technique and settings `render` took (its run.json `settings`), as bench quality
    arguments: the same method, spp and OIDN quality, with the photon axis (effort = thousands
    of photons per frame) from 1/8 to 4x the count the command chose."""
    st = rj.get("settings") or die("run.json has no settings")
    method, tech = st.get("method"), st.get("technique") or {}
    if not method:
        die("run.json names no method")
    args = ["--method", method]
    if "spp" in tech:
        args += ["--set", f"spp={tech['spp']}"]
    if st.get("denoise_quality"):
        args += ["--denoise-quality", str(st["denoise_quality"]).lower()]
    photons = tech.get("photons")
    k = max(1, int(photons) // 1000) if photons else None
    return {"method": method, "spp": tech.get("spp"), "photons": photons, "quality": st.get("quality"),
            "denoise_quality": st.get("denoise_quality"), "args": args,
            "start": max(1, k // 8) if k else 1, "stop": k * 4 if k else 64}


def fmt(x, bound="="):
    if x is None:
        return "n.r."
    return ("≤ " if bound == "<=" else "") + (f"{x:.2f}" if x < 100 else f"{x:.0f}")


def ratio(other, ours):
    if not other or not ours or other["cpu_s"] is None or ours["cpu_s"] is None:
        return "—"
    r = other["cpu_s"] / ours["cpu_s"]
    # an upper bound on ours makes the ratio a lower bound, and one on theirs an upper bound
    if ours["bound"] == "<=" and other["bound"] == "<=":
        return f"~{r:.1f}× (both ≤)"
    return ("≥ " if ours["bound"] == "<=" else "≤ " if other["bound"] == "<=" else "") + f"{r:.1f}×"


def table(results, a, model, flags):
    L = [f"Chronolux vs Cycles 5 + OIDN, each against its own reference; {a.res}², frames {a.frames} rendered, "
         f"{len(a.scored.split(','))} scored ({a.scored}); CPU s of the scored frames; {model}, "
         f"AVX-512: {'yes' if flags else 'no'}." + (f" **{a.label}**" if a.label else ""), "",
         "| scene | fidelity FLIP (ref vs ref) | ours literal: CPU s (FLIP, flicker) | ours to 0.08 / 0.05 | "
         "path+OIDN to 0.08 / 0.05 | Cycles+OIDN to 0.08 / 0.05 | **CPU ratio Cycles/ours at 0.08 / 0.05** | "
         "flicker ratio ours/Cycles at 0.08 | path/ours at 0.08 |",
         "|---|---|---|---|---|---|---|---|---|"]
    for r in results:
        o, p, c = r["ours_route"], r["path_oidn"], r.get("cycles_oidn")
        lit = r["literal"]
        cf = r.get("fidelity_flip")
        fid = f"{cf:.3f} (mean ×{r['fidelity_mean_ratio']:.3f})" if cf is not None else "—"
        fr = "—"
        if c and c["0.08"]["flicker"] and o["0.08"]["flicker"]:
            fr = f"{o['0.08']['flicker'] / c['0.08']['flicker']:.2f}"
        asp = f"; {lit['frames_as_path']}/{lit['frames_rendered']} frames as `path`" if lit.get("frames_as_path") else ""
        L.append(f"| {r['name']} ({r['what']}) | {fid} | {lit['cpu_s_scored']:.2f} ({lit['flip']:.3f}, {lit['flicker']:.4f}{asp}) | "
                 f"{fmt(o['0.08']['cpu_s'], o['0.08']['bound'])} / {fmt(o['0.05']['cpu_s'], o['0.05']['bound'])} | "
                 f"{fmt(p['0.08']['cpu_s'], p['0.08']['bound'])} / {fmt(p['0.05']['cpu_s'], p['0.05']['bound'])} | "
                 + (f"{fmt(c['0.08']['cpu_s'], c['0.08']['bound'])} / {fmt(c['0.05']['cpu_s'], c['0.05']['bound'])} | "
                    f"**{ratio(c['0.08'], o['0.08'])} / {ratio(c['0.05'], o['0.05'])}** | {fr} | " if c else "— | — | — | ")
                 + f"{ratio(p['0.08'], o['0.08'])} |")
    L += ["", "References' own noise (HDR-FLIP of half A vs half B, about 1.4x the full reference's; flicker floor "
          "= what the reference's noise adds to the flicker figure):", "",
          "| scene | ours: spp, halves FLIP, flicker floor | Cycles: spp, halves FLIP, flicker floor |", "|---|---|---|"]
    for r in results:
        ro, rc = r["ref_ours"], r.get("ref_cycles")
        spp = sorted({(fr[0] or {}).get("stats", {}).get("spp") for fr in ro["frames"].values() if fr} - {None})
        g = lambda x: "—" if x is None else f"{x:.3f}"  # noqa: E731
        L.append(f"| {r['name']} | {'/'.join(map(str, spp))}, {g(ro.get('halves_flip'))}, {g(ro.get('flicker_floor'))} | "
                 + (f"{rc['spp']}, {g(rc.get('halves_flip'))}, {g(rc.get('flicker_floor'))} |" if rc else "— |"))
    return "\n".join(L) + "\n"


def scale_run(a, scenes, out, work):
    sc = scenes[a.scale]
    if os.path.exists(os.path.join(out, "scale-1080p.json")):
        return json.load(open(os.path.join(out, "scale-1080p.json")))
    d = os.path.join(work, "scale-1080p")
    shutil.rmtree(d, ignore_errors=True)
    tf = os.path.join(out, "scale-1080p.time")
    log(out, f"scale: {a.scale} at 1920x1080, frames {a.scale_frames}")
    with open(os.path.join(out, "scale-1080p.log"), "w") as lg:
        run(["/usr/bin/time", "-v", "-o", tf, a.bin, "render", sc["path"], *sc.get("args", []), *ours_set(a),
             "--frames", a.scale_frames, "--max-depth", "8", "--resolution", "1920x1080", "-o", d], stdout=lg, stderr=lg)
    t = open(tf).read()
    g = lambda k: float(re.search(re.escape(k) + r":\s*([\d.]+)", t).group(1))  # noqa: E731
    n = len(frame_range(a.scale_frames))
    disk = sum(os.path.getsize(os.path.join(r, f)) for r, _, fs in os.walk(d) for f in fs)
    s = {"scene": a.scale, "frames": n, "cpu_s_per_frame": (g("User time (seconds)") + g("System time (seconds)")) / n,
         "peak_rss_mib": g("Maximum resident set size (kbytes)") / 1024, "disk_bytes": disk,
         "disk_per_frame_mib": disk / n / 2 ** 20}
    json.dump(s, open(os.path.join(out, "scale-1080p.json"), "w"), indent=1)
    return s


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bin", required=True, help="the chronolux binary (the default build, OIDN fetched by build.rs)")
    ap.add_argument("--out", required=True, help="results folder (JSON, logs, table)")
    ap.add_argument("--work", default="/tmp/chronolux-suite", help="renders, references, generated scenes")
    ap.add_argument("--shared", default=os.path.join(HERE, "..", "..", "..", "shared"))
    ap.add_argument("--scenes", help="comma-separated names from manifest.json (default: all)")
    ap.add_argument("--res", type=int, default=512)
    ap.add_argument("--frames", default="0..48")
    ap.add_argument("--scored", default="0,1,2,3,4,5,6,7,12,24,36,47")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--ours-ref-spp", type=int, default=8192)
    ap.add_argument("--ours-ref-error", type=float, default=1e-4)
    ap.add_argument("--cycles-ref-spp", type=int, default=4096)
    ap.add_argument("--cycles-pass-spp", type=int, default=256)
    ap.add_argument("--cycles-levels", default="1,2,4,8,16,32,64")
    ap.add_argument("--path-max-spp", type=int, default=256)
    ap.add_argument("--no-cycles", action="store_true")
    ap.add_argument("--ours-set", action="append", default=[], metavar="KEY=VALUE",
                    help="a setting of our default route's technique, passed as --set to its render and bench quality "
                         "(repeatable; for an A/B of one setting in one run)")
    ap.add_argument("--label", default="", help="e.g. 'reduced: ...', printed with the table")
    ap.add_argument("--scale", help="a scene name for the 1920x1080 scale run")
    ap.add_argument("--scale-frames", default="0..4")
    ap.add_argument("--update-benchmarks", help="BENCHMARKS.md whose suite-table block is replaced")
    a = ap.parse_args()
    if not os.access(a.bin, os.X_OK):
        die(f"--bin {a.bin}: not an executable (cargo build --release makes target/release/chronolux)")
    if not os.path.exists("/usr/bin/time"):
        die("/usr/bin/time is missing (apt-get install -y time)")
    os.makedirs(a.out, exist_ok=True)
    os.makedirs(a.work, exist_ok=True)
    gen = os.path.join(a.work, "scenes")
    manifest = json.load(open(os.path.join(HERE, "manifest.json")))
    if not all(os.path.exists(os.path.join(gen, s["file"].split("/")[-1])) for s in manifest["scenes"] if "{gen}" in s["file"]):
        run([sys.executable, os.path.join(HERE, "make_scenes.py"), gen, "--shared", a.shared])
    scenes = {}
    for s in manifest["scenes"]:
        s = dict(s, path=s["file"].replace("{gen}", gen).replace("{shared}", a.shared))
        if not s["path"].startswith("builtin:") and not os.path.exists(s["path"]):
            die(f"scene {s['name']}: {s['path']} not found")
        scenes[s["name"]] = s
    names = a.scenes.split(",") if a.scenes else [s["name"] for s in manifest["scenes"]]
    for n in names:
        if n not in scenes:
            die(f"--scenes: no scene {n} in manifest.json ({', '.join(scenes)})")
    model, flags = machine(a.out)
    log(a.out, f"start: scenes {names}, {a.res}², frames {a.frames}, scored {a.scored}, {model}")
    results = [scene_run(a, scenes[n], a.out, a.work) for n in names]
    scale = scale_run(a, scenes, a.out, a.work) if a.scale else None
    md = table(results, a, model, flags)
    if scale:
        md += (f"\nScale: `{scale['scene']}` at 1920×1080, {scale['frames']} frames, default route: "
               f"{scale['cpu_s_per_frame']:.1f} CPU s per frame, peak RSS {scale['peak_rss_mib']:.0f} MiB, "
               f"{scale['disk_per_frame_mib']:.1f} MiB written per frame.\n")
    json.dump({"args": vars(a), "cpu": model, "avx512": flags, "scenes": results, "scale": scale},
              open(os.path.join(a.out, "suite.json"), "w"), indent=1)
    open(os.path.join(a.out, "table.md"), "w").write(md)
    print(md)
    if a.update_benchmarks:
        b = open(a.update_benchmarks).read()
        i, j = b.find("<!-- suite-table:begin -->"), b.find("<!-- suite-table:end -->")
        if i < 0 or j < i:
            die(f"{a.update_benchmarks}: no <!-- suite-table:begin --> ... <!-- suite-table:end --> block")
        b = b[:i] + "<!-- suite-table:begin -->\n" + md + b[j:]
        open(a.update_benchmarks, "w").write(b)
    log(a.out, "end")


if __name__ == "__main__":
    main()
