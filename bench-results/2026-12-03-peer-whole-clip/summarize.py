#!/usr/bin/env python3
"""Summary of run.sh: CPU s per 12 frames (the scored frames) at HDR-FLIP 0.08, and flicker there.
Ours: CPU of the run x 12 / frames rendered (48 for a temporal method, 12 for a frame-by-frame
one); peers: CPU of their 12 frames. Interpolated log-log between the levels straddling 0.08.
Usage: summarize.py [FOLDER [CFG,CFG,...]]"""
import json, math, os, sys
D = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.abspath(__file__))
T = 0.08

def interp(levels, key):
    for a, b in zip(levels, levels[1:]):
        if a["flip"] >= T >= b["flip"]:
            la, lb = math.log(a["flip"]), math.log(b["flip"])
            w = (math.log(T) - la) / (lb - la)
            return math.exp(math.log(a[key]) + w * (math.log(b[key]) - math.log(a[key])))
    return None

def ours(name):
    p = os.path.join(D, name + ".json")
    if not os.path.exists(p) or os.path.getsize(p) == 0:
        return None
    d = json.load(open(p))
    scale = len(d["measured"]) / len(d["frames"]) if d["method"] != "path" else 1.0
    lv = [{"flip": l["flip_mean"], "cpu_s": l["cpu_s"] * scale, "flicker": l["flicker"]} for l in d["results"][0]["levels"]]
    return lv

rows = []
for peer in ["mitsuba", "cycles"]:
    lv = json.loads(open(os.path.join(D, peer + ".json")).read().strip().splitlines()[-1])["levels"]
    rows.append((peer, lv))
# Our configurations (the name after ours-a-/ours-b-), comma-separated: argv[2].
CFGS = sys.argv[2].split(",") if len(sys.argv) > 2 else ["path", "il2-k8", "il8-k8", "il16-k8", "st"]
for cfg in CFGS:
    for r in "ab":
        lv = ours(f"ours-{r}-{cfg}")
        if lv:
            rows.append((f"ours-{r}-{cfg}", lv))
peer_cpu = {}
print(f"| run | levels (FLIP @ CPU s per 12 frames) | CPU s per 12 frames at {T} | flicker there | Mitsuba / ours | Cycles+OIDN / ours |")
print("|---|---|---|---|---|---|")
for name, lv in rows:
    c, f = interp(lv, "cpu_s"), interp(lv, "flicker")
    if name in ("mitsuba", "cycles"):
        peer_cpu[name] = c
    levels = ", ".join(f"{l['flip']:.4f} @ {l['cpu_s']:.1f}" for l in lv)
    rm = f"{peer_cpu['mitsuba'] / c:.2f}x" if c and "mitsuba" in peer_cpu and name.startswith("ours") else ""
    rc = f"{peer_cpu['cycles'] / c:.2f}x" if c and "cycles" in peer_cpu and name.startswith("ours") else ""
    cs = f"{c:.1f}" if c else "not bracketed"
    fs = f"{f:.4f}" if f else ""
    print(f"| {name} | {levels} | {cs} | {fs} | {rm} | {rc} |")
