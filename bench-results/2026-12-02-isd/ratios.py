"""Equal-FLIP ratios of the Issue 12 runs (BENCHMARKS.md): CPU seconds interpolated
log-log between the bracketing effort levels of the `bench quality` logs, as `bench
quality` does; all three methods over the same 24 frames. (`pmic()` reads the superseded
4-frame pm-ic renders; unused.)"""
import csv, math, re, sys, os
D = os.path.dirname(os.path.abspath(__file__))
def levels(log, method):
    out = []
    for l in open(os.path.join(D, log)):
        m = re.match(rf"{re.escape(method)} effort (\d+): ([\d.]+) s wall, ([\d.]+) s CPU, FLIP mean ([\d.]+) max ([\d.]+), flicker ([\d.]+)", l)
        if m:
            out.append((int(m[1]), float(m[3]), float(m[4]), float(m[6])))
    return out
def pmic(n):
    rows = list(csv.DictReader(open(os.path.join(D, f"pmic-{n}-frames0-3.csv"))))
    fl = sum(float(r['flip_hdr']) for r in rows) / len(rows)
    fk = [float(r['flicker']) for r in rows if r['flicker']]
    u, s = map(float, open(os.path.join(D, f"pmic-{n}-frames0-3.cpu")).read().split()[-2:])
    return (int(n.split('-')[1]) // 1000, (u + s) / 4 * 24, fl, sum(fk) / len(fk))
def at(c, flip):
    """CPU s and flicker at `flip`, log-log between bracketing levels (None outside)."""
    c = sorted(c, key=lambda x: -x[2])
    for (e0, t0, f0, k0), (e1, t1, f1, k1) in zip(c, c[1:]):
        if f0 >= flip >= f1:
            s = math.log(f0 / flip) / math.log(f0 / f1)
            return t0 * (t1 / t0) ** s, k0 * (k1 / k0) ** s
    return None
scenes = {
    # (ic-static-dynamic logs, pm-ic log, path log, load of the path run)
    'cornell-moving': (['cm2-isd-pmic.log', 'cm2-isd-100.log'], 'cm2-isd-pmic.log', 'cm2-path.log', 'quiet'),
    'demo': (['demo2-isd-pmic.log', 'demo2-isd-100.log'], 'demo2-isd-pmic.log', 'demo-path.log', 'LOADED'),
    'RiggedSimple --stage cornell': (['rig2-isd-pmic.log'], 'rig2-isd-pmic.log', 'rig-path.log', 'LOADED'),
}
for name, (ilogs, plog, pathlog, load) in scenes.items():
    isd = sorted(sum((levels(l, 'ic-static-dynamic') for l in ilogs if os.path.exists(os.path.join(D, l))), []))
    pm = levels(plog, 'pm-ic')
    path = levels(pathlog, 'path')
    print(f"== {name}")
    for lv in isd: print(f"  ic-static-dynamic {lv[0]}k photons: CPU {lv[1]:.2f} s, FLIP {lv[2]:.4f}, flicker {lv[3]:.4f}")
    for lv in pm: print(f"  pm-ic {lv[0]}k photons: CPU {lv[1]:.2f} s, FLIP {lv[2]:.4f}, flicker {lv[3]:.4f}")
    for lv in path: print(f"  path {lv[0]} spp ({load}): CPU {lv[1]:.2f} s, FLIP {lv[2]:.4f}, flicker {lv[3]:.4f}")
    for e, t, f, k in pm:
        r = at(isd, f)
        print(f"  at pm-ic {e}k's FLIP {f:.4f}: " + (f"ic-static-dynamic {r[0]:.2f} CPU s, flicker {r[1]:.4f}; pm-ic {t:.2f} CPU s, flicker {k:.4f}: {t / r[0]:.2f}x less CPU, {k / r[1]:.2f}x lower flicker" if r else "outside ic-static-dynamic's measured range"))
    for f in sorted({x[2] for x in isd} | {0.08}, reverse=True):
        r, q = at(path, f), at(isd, f)
        if r and q:
            print(f"  at FLIP {f:.4f}: path {r[0]:.2f} CPU s (flicker {r[1]:.4f}), ic-static-dynamic {q[0]:.2f} CPU s (flicker {q[1]:.4f}): path/isd CPU {r[0] / q[0]:.2f}x")
        elif q:
            print(f"  at FLIP {f:.4f}: ic-static-dynamic {q[0]:.2f} CPU s; path outside its measured range (best {min(p[2] for p in path):.4f} at {max(p[1] for p in path):.2f} CPU s)")
