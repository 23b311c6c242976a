#!/usr/bin/env python3
"""Per configuration: CPU s (mean of the rounds), mean HDR-FLIP, relMSE, flicker (the same
in every round: the images are identical), from run.sh's JSON files."""
import glob, json, os, re, sys
d = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.abspath(__file__))
rows = {}
for p in sorted(glob.glob(os.path.join(d, "*.json"))):
    m = re.match(r"(cm|demo)-([ab])-(.*)\.json", os.path.basename(p))
    if not m:
        continue
    scene, rnd, cfg = m.groups()
    lv = json.load(open(p))["results"][0]["levels"][0]
    r = rows.setdefault((scene, cfg), {"cpu": [], "flip": set(), "rel": lv["relmse_mean"], "fl": lv["flicker"]})
    r["cpu"].append(lv["cpu_s"])
    r["flip"].add(round(lv["flip_mean"], 5))
for (scene, cfg), r in sorted(rows.items(), key=lambda kv: (kv[0][0], sum(kv[1]["cpu"]) / len(kv[1]["cpu"]))):
    cpu = sum(r["cpu"]) / len(r["cpu"])
    print(f"{scene:5} {cfg:14} cpu {cpu:7.2f} ({' '.join(f'{c:.2f}' for c in r['cpu'])})  "
          f"flip {'/'.join(str(f) for f in sorted(r['flip']))}  relmse {r['rel']:.4f}  flicker {r['fl']:.4f}")
