#!/usr/bin/env python3
"""fast.sh's runs (and any other bench-quality JSON named here): CPU s per 12 scored frames
at HDR-FLIP 0.08 (log-log between the straddling levels, as ../2026-12-03-peer-whole-clip/
summarize.py), flicker there. Usage: summarize.py [DIR] NAME..."""
import json, math, os, sys
D = sys.argv[1]
T = 0.08
def interp(lv, key):
    for a, b in zip(lv, lv[1:]):
        if a["flip"] >= T >= b["flip"]:
            w = (math.log(T) - math.log(a["flip"])) / (math.log(b["flip"]) - math.log(a["flip"]))
            return math.exp(math.log(a[key]) + w * (math.log(b[key]) - math.log(a[key])))
print("| run | levels (FLIP @ CPU s per 12 frames) | CPU s at 0.08 | flicker there |")
print("|---|---|---|---|")
for name in sys.argv[2:]:
    d = json.load(open(os.path.join(D, name + ".json")))
    scale = len(d["measured"]) / len(d["frames"]) if d["method"] != "path" else 1.0
    lv = [{"flip": l["flip_mean"], "cpu_s": l["cpu_s"] * scale, "flicker": l["flicker"]} for l in d["results"][0]["levels"]]
    c, f = interp(lv, "cpu_s"), interp(lv, "flicker")
    print(f"| {name} | " + ", ".join(f"{l['flip']:.4f} @ {l['cpu_s']:.1f}" for l in lv)
          + f" | {c:.1f} | {f:.4f} |" if c else " | not bracketed | |")
