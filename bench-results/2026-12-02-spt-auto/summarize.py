"""Per spt level: dept-spatial's and spacetime-dept's CPU (and photons) at its FLIP,
interpolated log-log between their bracketing levels."""
import json, math, os
d = os.path.dirname(os.path.abspath(__file__))
def lv(r): return [(l["effort"], l["cpu_s"], l["flip_mean"], l["flicker"]) for l in r["levels"]]
def at(v, flip, i):
    s = sorted(v, key=lambda l: -l[2])
    for a, b in zip(s, s[1:]):
        if a[2] >= flip >= b[2]:
            t = (math.log(flip) - math.log(a[2])) / (math.log(b[2]) - math.log(a[2]))
            return math.exp(math.log(a[i]) + t * (math.log(b[i]) - math.log(a[i])))
r = json.load(open(f"{d}/spt-dept.json"))["results"]
spt, ds = lv(r[0]), lv(r[1])
st = lv(json.load(open(f"{d}/st.json"))["results"][0])
print("| spt k photons (pool) | FLIP | CPU s | flicker | dept-spatial k/frame, CPU s | spt vs dept-spatial | spacetime-dept CPU s | spt vs spacetime-dept |")
print("|---|---|---|---|---|---|---|---|")
f = lambda x, p=2: "–" if x is None else f"{x:.{p}f}"
for e, c, fl_, fk in spt:
    dk, dc, sc = at(ds, fl_, 0), at(ds, fl_, 1), at(st, fl_, 1)
    print(f"| {e} | {fl_:.4f} | {c:.2f} | {fk:.3f} | {f(dk,1)}, {f(dc)} | **{f(dc and dc/c)}×** | {f(sc)} | {f(sc and sc/c)}× |")
