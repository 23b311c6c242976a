#!/usr/bin/env python3
"""Per spacetime-dept level: the dept-spatial photons, CPU s and flicker at the same mean
FLIP, interpolated linearly in log2(photons) between the bracketing baseline levels (from
the `bench quality --json` output). Usage: equal_flip.py SCENE.json"""
import json, math, sys
d = json.load(open(sys.argv[1]))
d = d[0] if isinstance(d, list) else d
res = d["results"]
runs = {r["method"]: r["levels"] for r in (res if isinstance(res, list) else [res])}
st, bl = runs["spacetime-dept"], runs["dept-spatial"]
print("| spacetime k photons | FLIP | CPU s | flicker | dept-spatial k photons | photons ratio | dept-spatial CPU s | CPU ratio | dept-spatial flicker | flicker ratio |")
print("|---|---|---|---|---|---|---|---|---|---|")
for s in st:
    f = s["flip_mean"]
    for a, b in zip(bl, bl[1:]):
        if a["flip_mean"] >= f >= b["flip_mean"]:
            t = (a["flip_mean"] - f) / (a["flip_mean"] - b["flip_mean"])
            la, lb = math.log2(a["effort"]), math.log2(b["effort"])
            p = 2 ** (la + t * (lb - la))
            cpu = a["cpu_s"] + t * (b["cpu_s"] - a["cpu_s"])
            fl = a["flicker"] + t * (b["flicker"] - a["flicker"])
            print(f"| {s['effort']} | {f:.4f} | {s['cpu_s']:.2f} | {s['flicker']:.4f} | {p:.1f} | {p / s['effort']:.1f}× | {cpu:.2f} | **{cpu / s['cpu_s']:.2f}×** | {fl:.4f} | {fl / s['flicker']:.2f}× |")
            break
    else:
        print(f"| {s['effort']} | {f:.4f} | {s['cpu_s']:.2f} | {s['flicker']:.4f} | outside the baseline's range | | | | | |")
