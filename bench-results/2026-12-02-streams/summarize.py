#!/usr/bin/env python3
"""streams.sh's results: per configuration and level, CPU s (mean of rounds a, b), FLIP,
relMSE and flicker before and after, and the ratios after / before."""
import glob, json, os, re, sys
D = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.abspath(__file__))
rows = {}
for p in sorted(glob.glob(os.path.join(D, "*.json"))):
    m = re.match(r"(\w+)-([ab])-(before|after)(?:-(k\d))?\.json", os.path.basename(p))
    scene, rnd, which, k = m.groups()
    for l in json.load(open(p))["results"][0]["levels"]:
        r = rows.setdefault((scene, k or "k4", l["effort"]), {}).setdefault(which, {"cpu": []})
        r["cpu"].append(l["cpu_s"])
        r.update(flip=l["flip_mean"], rel=l["relmse_mean"], fl=l["flicker"])
for key, v in sorted(rows.items()):
    b, a = v["before"], v["after"]
    cb, ca = sum(b["cpu"]) / len(b["cpu"]), sum(a["cpu"]) / len(a["cpu"])
    print(f"{key[0]:6} {key[1]} spp {key[2]}: CPU {cb:6.2f} -> {ca:6.2f} ({ca / cb:.2f}x)  "
          f"FLIP {b['flip']:.4f} -> {a['flip']:.4f} ({a['flip'] / b['flip'] - 1:+.1%})  "
          f"relMSE {b['rel']:.4f} -> {a['rel']:.4f} ({a['rel'] / b['rel'] - 1:+.0%})  "
          f"flicker {b['fl']:.4f} -> {a['fl']:.4f}")
