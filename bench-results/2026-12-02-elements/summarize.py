"""Per spacetime-dept level: dept-spatial's and path's CPU seconds (and dept-spatial's
photons) at the same mean FLIP, interpolated log-log between their bracketing levels."""
import json, math, sys, os

def levels(path):
    d = json.load(open(path))
    return [(l["effort"], l["cpu_s"], l["flip_mean"], l["flicker"]) for l in d["results"][0]["levels"]]

def at(lv, flip, idx):
    """Value idx of lv interpolated (log-log) at FLIP `flip`; None outside the range."""
    s = sorted(lv, key=lambda l: -l[2])
    for a, b in zip(s, s[1:]):
        if a[2] >= flip >= b[2]:
            t = (math.log(flip) - math.log(a[2])) / (math.log(b[2]) - math.log(a[2])) if a[2] != b[2] else 0
            return math.exp(math.log(a[idx]) + t * (math.log(b[idx]) - math.log(a[idx])))
    return None

d = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(__file__) or "."
for sc in ["rigged", "dolly", "demo", "cm"]:
    if not os.path.exists(f"{d}/{sc}-path.json"):
        continue
    pa = levels(f"{d}/{sc}-path.json")
    for el in ["0", "100"]:
        st, ds = levels(f"{d}/{sc}-st-e{el}.json"), levels(f"{d}/{sc}-ds-e{el}.json")
        print(f"\n{sc}, elements={el} ({'auto' if el == '0' else 'fixed'})")
        print("| st k photons | FLIP | CPU s | flicker | ds k photons | photons ratio | ds CPU s | CPU ratio vs ds | ds flicker | path CPU s | CPU ratio vs path | path flicker |")
        print("|---|---|---|---|---|---|---|---|---|---|---|---|")
        for e, c, f, fl in st:
            dk, dc, dfl = at(ds, f, 0), at(ds, f, 1), at(ds, f, 3)
            pc, pfl = at(pa, f, 1), at(pa, f, 3)
            fmt = lambda x, p=2: "–" if x is None else f"{x:.{p}f}"
            print(f"| {e} | {f:.4f} | {c:.2f} | {fl:.4f} | {fmt(dk,1)} | {fmt(dk and dk/e,1)}{'×' if dk else ''} | {fmt(dc)} | **{fmt(dc and dc/c)}{'×' if dc else ''}** | {fmt(dfl,4)} | {fmt(pc)} | **{fmt(pc and pc/c)}{'×' if pc else ''}** | {fmt(pfl,4)} |")

# spacetime-dept at 16 spp against dept-spatial (run-spp16.sh: both in one bench run)
for sc in ["dolly", "demo"]:
    p = f"{d}/{sc}-st16.json"
    if not os.path.exists(p):
        continue
    r = json.load(open(p))["results"]
    lv = lambda k: [(l["effort"], l["cpu_s"], l["flip_mean"], l["flicker"]) for l in r[k]["levels"]]
    st, ds = lv(0), lv(1)
    print(f"\n{sc}, spacetime-dept at 16 spp (auto elements) against dept-spatial")
    print("| st k photons | FLIP | CPU s | flicker | ds k photons | photons ratio | ds CPU s | CPU ratio | ds flicker |")
    print("|---|---|---|---|---|---|---|---|---|")
    for e, c, f, fl in st:
        dk, dc, dfl = at(ds, f, 0), at(ds, f, 1), at(ds, f, 3)
        if dk is None:
            print(f"| {e} | {f:.4f} | {c:.2f} | {fl:.4f} | outside the baseline's range | | | | |")
            continue
        print(f"| {e} | {f:.4f} | {c:.2f} | {fl:.4f} | {dk:.1f} | {dk/e:.1f}× | {dc:.2f} | **{dc/c:.2f}×** | {dfl:.4f} |")
