"""Per spacetime-dept level: stbpt's CPU s, relMSE and flicker at its FLIP (log-log between
stbpt's bracketing levels; '–' outside them)."""
import json, math, os
d = os.path.dirname(os.path.abspath(__file__))
def lv(p): return [(l["effort"], l["cpu_s"], l["flip_mean"], l["flicker"], l["relmse_mean"])
                   for l in json.load(open(p))["results"][0]["levels"]]
def at(v, flip, i):
    s = sorted(v, key=lambda l: -l[2])
    for a, b in zip(s, s[1:]):
        if a[2] >= flip >= b[2]:
            t = (math.log(flip) - math.log(a[2])) / (math.log(b[2]) - math.log(a[2]))
            return math.exp(math.log(a[i]) + t * (math.log(b[i]) - math.log(a[i])))
f = lambda x, p=2: "–" if x is None else f"{x:.{p}f}"
for sc in ["rigged", "dolly", "demo", "cm"]:
    if not os.path.exists(f"{d}/{sc}-st.json"):
        continue
    st, sb = lv(f"{d}/{sc}-st.json"), lv(f"{d}/{sc}-stbpt.json")
    print(f"\n{sc}: stbpt levels " + ", ".join(f"{e} spp {c:.2f} s FLIP {fl:.4f} relMSE {r:.4f} flicker {k:.3f}" for e, c, fl, k, r in sb))
    print("| spacetime-dept k photons | FLIP | CPU s | relMSE | flicker | stbpt CPU s | **stbpt / spacetime-dept CPU** | stbpt relMSE | stbpt flicker |")
    print("|---|---|---|---|---|---|---|---|---|")
    for e, c, fl, k, r in st:
        bc, br, bk = at(sb, fl, 1), at(sb, fl, 4), at(sb, fl, 3)
        print(f"| {e} | {fl:.4f} | {c:.2f} | {r:.4f} | {k:.3f} | {f(bc)} | **{f(bc and bc/c)}×** | {f(br,4)} | {f(bk,3)} |")
