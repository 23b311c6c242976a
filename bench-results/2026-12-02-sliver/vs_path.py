"""CPU s of path at each spacetime-dept level's FLIP (log-log between path's bracketing
levels), from the `bench quality` logs: python3 vs_path.py vp-rigged vp-dolly"""
import math, re, sys

def levels(path):
    out = []
    for line in open(path):
        m = re.search(r"effort (\d+): .* ([\d.]+) s CPU, FLIP mean ([\d.]+) .* flicker ([\d.]+)", line)
        if m:
            out.append((int(m[1]), float(m[2]), float(m[3]), float(m[4])))
    return out

for name in sys.argv[1:]:
    st, pt = levels(f"{name}-st.log"), levels(f"{name}-path.log")
    print(f"{name}: k photons | FLIP | CPU s | flicker | path CPU s | CPU ratio | path flicker")
    for k, cpu, flip, fl in st:
        for (e0, c0, f0, l0), (e1, c1, f1, l1) in zip(pt, pt[1:]):
            if f1 <= flip <= f0:
                t = math.log(flip / f0) / math.log(f1 / f0)
                c = math.exp(math.log(c0) + t * math.log(c1 / c0))
                l = math.exp(math.log(l0) + t * math.log(l1 / l0))
                print(f"| {k} | {flip:.4f} | {cpu:.2f} | {fl:.4f} | {c:.2f} | **{c / cpu:.2f}×** | {l:.4f} |")
                break
        else:
            print(f"| {k} | {flip:.4f} | {cpu:.2f} | {fl:.4f} | outside path's range | | |")
