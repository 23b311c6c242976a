#!/usr/bin/env python3
"""Per scene: at each target FLIP both methods bracket, spacetime-dept's and dept-spatial's
CPU seconds per scored frames (bench quality's interpolated_cpu_s: a run's CPU x scored /
rendered frames, log-log between levels), the ratio, the photons per frame at that FLIP
(effort interpolated log-log the same way) and the flicker of the first level reaching it."""
import json, math, sys

def interp(levels, target, key):
    for k, l in enumerate(levels):
        if l["flip_mean"] <= target:
            if k == 0:
                return None
            a, b = levels[k - 1], levels[k]
            s = math.log(a["flip_mean"] / target) / math.log(a["flip_mean"] / b["flip_mean"])
            return key(a) * (key(b) / key(a)) ** s
    return None

print("| scene | FLIP | st CPU s | ds CPU s | CPU ratio | st k photons | ds k photons | photons ratio | st flicker | ds flicker |")
print("|---|---|---|---|---|---|---|---|---|---|")
for sc in sys.argv[1:]:
    d = json.load(open(f"{sc}.json"))
    st, ds = d["results"]
    for k, t in enumerate(d["targets"]):
        a, b = st["interpolated_cpu_s"][k], ds["interpolated_cpu_s"][k]
        if a is None or b is None:
            continue
        pa = interp(st["levels"], t, lambda l: l["effort"])
        pb = interp(ds["levels"], t, lambda l: l["effort"])
        fa = st["reached"][k]["flicker"]
        fb = ds["reached"][k]["flicker"]
        print(f"| {sc} | {t} | {a:.2f} | {b:.2f} | **{b / a:.2f}×** | {pa:.1f} | {pb:.1f} | {pb / pa:.1f}× | {fa:.4f} | {fb:.4f} |")
