#!/usr/bin/env python3
"""Merge quality_side_by_side.py runs (e.g. one from spp 1 and one from spp 3) into a finer
time-to-FLIP comparison.

  python3 quality_merge.py OUT/quality_pow2.json OUT/quality_start3.json [--md OUT.md]

For each renderer the levels of all runs are pooled and sorted by spp. Per target it reports
  first level   the cheapest pooled level whose mean FLIP <= target (the bench-quality rule
                on the finer grid spp 1, 2, 3, 4, 6, 8, 12, ...)
  interpolated  wall and CPU seconds at exactly the target, interpolated linearly in
                log(seconds) vs log(FLIP) between the two pooled levels straddling it
                (seconds are per-level measurements, so load noise carries into these)
Pool wall seconds only over runs that saw the same load; CPU seconds pool more safely.
Given one run, it interpolates within that run alone.
"""
import argparse
import json
import math


def interp(levels, target, key):
    pts = sorted(levels, key=lambda l: l["effort"])
    for a, b in zip(pts, pts[1:]):
        if a["flip_mean"] > target >= b["flip_mean"]:
            x0, x1 = math.log(a["flip_mean"]), math.log(b["flip_mean"])
            y0, y1 = math.log(a[key]), math.log(b[key])
            w = (math.log(target) - x0) / (x1 - x0)
            return math.exp(y0 + w * (y1 - y0))
    return None


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("runs", nargs="+")
    ap.add_argument("--md", default=None)
    a = ap.parse_args()
    docs = [json.load(open(p)) for p in a.runs]
    targets = [r["target"] for r in docs[0]["targets"]]
    pooled = {w: sorted((l for d in docs for l in d[w]), key=lambda l: l["effort"]) for w in ("ours", "mitsuba")}

    def f(x, d=2):
        return "-" if x is None else f"{x:.{d}f}"

    md = ("| target HDR-FLIP | ours first level: spp / wall s / CPU s | Mitsuba first level: spp / wall s / CPU s "
          "| wall ratio ours/Mitsuba | CPU ratio | interpolated wall ours / Mitsuba (ratio) "
          "| interpolated CPU ours / Mitsuba (**ratio**) |\n|---:|---|---|---:|---:|---|---|\n")
    out = []
    for t in targets:
        fl = {w: next((l for l in pooled[w] if l["flip_mean"] <= t), None) for w in pooled}
        iw = {w: interp(pooled[w], t, "wall_s") for w in pooled}
        ic = {w: interp(pooled[w], t, "cpu_s") for w in pooled}
        o, m = fl["ours"], fl["mitsuba"]
        row = {"target": t, "first": fl, "interp_wall": iw, "interp_cpu": ic}
        out.append(row)
        rw = o["wall_s"] / m["wall_s"] if o and m else None
        rc = o["cpu_s"] / m["cpu_s"] if o and m else None
        riw = iw["ours"] / iw["mitsuba"] if iw["ours"] and iw["mitsuba"] else None
        ric = ic["ours"] / ic["mitsuba"] if ic["ours"] and ic["mitsuba"] else None
        md += (f"| {t} | {o['effort'] if o else '-'} / {f(o and o['wall_s'])} / {f(o and o['cpu_s'])} "
               f"| {m['effort'] if m else '-'} / {f(m and m['wall_s'])} / {f(m and m['cpu_s'])} "
               f"| {f(rw)} | {f(rc)} | {f(iw['ours'], 1)} / {f(iw['mitsuba'], 1)} ({f(riw)}) "
               f"| {f(ic['ours'], 1)} / {f(ic['mitsuba'], 1)} (**{f(ric)}**) |\n")
    md += ("\nPooled levels (spp: wall s, CPU s, FLIP mean, flicker):\n\n| spp | ours | Mitsuba |\n|---:|---|---|\n")
    for e in sorted({l["effort"] for w in pooled for l in pooled[w]}):
        cell = []
        for w in ("ours", "mitsuba"):
            l = next((l for l in pooled[w] if l["effort"] == e), None)
            cell.append("-" if l is None else
                        f"{l['wall_s']:.2f} s, {l['cpu_s']:.2f} CPU-s, FLIP {l['flip_mean']:.4f}, flicker {l['flicker']:.4f}")
        md += f"| {e} | {cell[0]} | {cell[1]} |\n"
    print(md)
    if a.md:
        with open(a.md, "w") as fh:
            fh.write(md)


if __name__ == "__main__":
    main()
