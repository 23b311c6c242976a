#!/usr/bin/env python3
"""Per scene (FILE.json of a `bench quality --baseline` run): at each target FLIP both methods
bracket, the method's and the baseline's CPU seconds per scored frames (bench quality's
interpolated_cpu_s: a run's CPU x scored / rendered frames, log-log between levels), the
ratio, the effort at that FLIP (thousands of photons per frame, or samples per pixel;
interpolated log-log the same way) and the flicker of the first level reaching it.
Usage: summarize.py NAME... (reads NAME.json)."""
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

first = True
for sc in sys.argv[1:]:
    d = json.load(open(f"{sc}.json"))
    st, ds = d["results"]
    if first:
        m, b = st["method"], ds["method"]
        print(f"| scene | FLIP | {m} CPU s | {b} CPU s | CPU ratio | {m} effort | {b} effort | effort ratio | {m} flicker | {b} flicker |")
        print("|---|---|---|---|---|---|---|---|---|---|")
        first = False
    for k, t in enumerate(d["targets"]):
        a, b = st["interpolated_cpu_s"][k], ds["interpolated_cpu_s"][k]
        if a is None or b is None:
            continue
        pa = interp(st["levels"], t, lambda l: l["effort"])
        pb = interp(ds["levels"], t, lambda l: l["effort"])
        fa = st["reached"][k]["flicker"]
        fb = ds["reached"][k]["flicker"]
        print(f"| {sc} | {t} | {a:.2f} | {b:.2f} | **{b / a:.2f}×** | {pa:.1f} | {pb:.1f} | {pb / pa:.1f}× | {fa:.4f} | {fb:.4f} |")
