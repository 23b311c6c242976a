#!/usr/bin/env python3
"""seeds.sh's results: per spp, mean over seeds 1-4 of FLIP, relMSE and flicker before and
after the sample-stream change, and the per-seed relMSE ratios after / before."""
import json, os, sys
D = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.abspath(__file__))
lv = lambda s, w: {l["effort"]: l for l in json.load(open(os.path.join(D, f"seed{s}-{w}.json")))["results"][0]["levels"]}
seeds = [1, 2, 3, 4]
for e in (1, 2, 4):
    b = [lv(s, "before")[e] for s in seeds]; a = [lv(s, "after")[e] for s in seeds]
    m = lambda xs, k: sum(x[k] for x in xs) / len(xs)
    print(f"spp {e}: FLIP {m(b, 'flip_mean'):.4f} -> {m(a, 'flip_mean'):.4f}, "
          f"relMSE {m(b, 'relmse_mean'):.4f} -> {m(a, 'relmse_mean'):.4f}, "
          f"flicker {m(b, 'flicker'):.4f} -> {m(a, 'flicker'):.4f}; relMSE ratio per seed "
          + " ".join(f"{y['relmse_mean'] / x['relmse_mean']:.2f}" for x, y in zip(b, a)))
