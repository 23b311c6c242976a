#!/usr/bin/env python3
"""Issue 17 goal 3, seventh run (the sixth run's summary script unchanged; the fourth run's script with spacetime-dept + OIDN in place of stbpt without interleaving): CPU s to HDR-FLIP 0.08 (log-log between levels) and flicker
there, for Mitsuba 3, Cycles + OIDN, our path + OIDN, stbpt + OIDN without interleaving
(1 spp, K 2 -> 4) and with it (one pixel in 8, K = 8, 3 -> 4 spp; one pixel in 2, 1 spp,
K 4 -> 8); ours: mean CPU of runs
a and b (same images). Usage: python3 summarize17d.py [RESULTS_DIR]"""
import json, os, sys
HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "2026-12-02-peer-issue17c"))
from summarize17c import interp, last_json  # the third run's interpolation, unchanged
D = sys.argv[1] if len(sys.argv) > 1 else HERE
def ours(name):
    by = {}
    for r in "ab":
        for l in json.load(open(os.path.join(D, f"ours-{r}-{name}.json")))["results"][0]["levels"]:
            by.setdefault(l["effort"], []).append(l)
    return [{"effort": e, "cpu_s": sum(x["cpu_s"] for x in v) / len(v), "cpu_runs": [x["cpu_s"] for x in v],
             "flip": v[0]["flip_mean"], "flicker": v[0]["flicker"]} for e, v in sorted(by.items())]
rows = {"Mitsuba 3": last_json("mitsuba.json", D), "Cycles + OIDN": last_json("cycles.json", D),
        "ours path + OIDN": ours("path"),
        "ours spacetime-dept + OIDN, 4 spp, 256k -> 512k": ours("st256") + ours("st512"),
        "ours stbpt + OIDN, interleave 8, K 8, 3 -> 4 spp": ours("il8-e3") + ours("il8-e4"),
        "ours stbpt + OIDN, interleave 2, 1 spp, K 4 -> 8": ours("il2-k4") + ours("il2-k8")}
res = {}
for k, lv in rows.items():
    res[k] = (interp(lv, 0.08, "cpu_s"), interp(lv, 0.08, "flicker"))
    if res[k][0] is None and not any(l["flip"] <= 0.08 for l in lv):
        print(f"{k}: levels {[(round(l['cpu_s'], 2), round(l['flip'], 4), round(l['flicker'], 4)) for l in lv]}; 0.08 not reached")
        continue
    if res[k][0] is None:
        # Not bracketed (every level below 0.08): the cheapest level below is an upper bound.
        first = min((l for l in lv if l["flip"] <= 0.08), key=lambda l: l["cpu_s"])
        res[k] = (first["cpu_s"], first["flicker"])
        print(f"{k}: 0.08 not bracketed; the cheapest level below it (an upper bound):")
    print(f"{k}: levels {[(round(l['cpu_s'], 2), round(l['flip'], 4), round(l['flicker'], 4)) for l in lv]}; "
          f"CPU s at 0.08 {res[k][0]:.2f}, flicker {res[k][1]:.4f}")
for best in ("ours spacetime-dept + OIDN, 4 spp, 256k -> 512k", "ours stbpt + OIDN, interleave 8, K 8, 3 -> 4 spp",
             "ours stbpt + OIDN, interleave 2, 1 spp, K 4 -> 8"):
    for k in ("Mitsuba 3", "Cycles + OIDN", "ours path + OIDN"):
        if k != best and res.get(best, (None,))[0] is not None:
            print(f"{k} / {best}: {res[k][0] / res[best][0]:.2f}x CPU, flicker {res[k][1] / res[best][1]:.2f}x")
