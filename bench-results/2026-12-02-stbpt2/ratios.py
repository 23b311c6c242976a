"""Ratios of issue 17 (stbpt): CPU seconds to equal mean FLIP (log-log interpolation
between effort levels, within the range both curves cover) and flicker at that FLIP
(interpolated the same way), for stbpt against bdpt and path.
Usage: python3 ratios.py NAME...  (reads NAME-stbpt.json [stbpt vs bdpt], NAME-bdpt-hi.json [bdpt's
levels 32 and 64], NAME-path.json and NAME-stbpt-before.json when present)."""
import json, math, sys

def curve(res):
    return [(l['effort'], l['cpu_s'], l['flip_mean'], l['flicker']) for l in res['levels']]

def at_flip(c, target):
    """(CPU s, flicker) where the curve reaches FLIP `target`, log-log between levels."""
    if c and abs(c[0][2] - target) < 5e-4:
        return c[0][1], c[0][3]
    for k in range(1, len(c)):
        f0, f1 = c[k - 1][2], c[k][2]
        if f1 <= target <= f0 and f0 > f1:
            s = math.log(f0 / target) / math.log(f0 / f1)
            t = c[k - 1][1] * (c[k][1] / c[k - 1][1]) ** s
            fl = c[k - 1][3] * (c[k][3] / c[k - 1][3]) ** s
            return t, fl
    return None

def load(p):
    try:
        return json.load(open(p))
    except (FileNotFoundError, json.JSONDecodeError):
        return None

for name in sys.argv[1:]:
    sb = load(f'{name}-stbpt.json')
    pa = load(f'{name}-path.json')
    be = load(f'{name}-stbpt-before.json')
    curves = {}
    if sb:
        curves['stbpt'] = curve(sb['results'][0])
        curves['bdpt'] = curve(sb['results'][1])
    hi = load(f'{name}-bdpt-hi.json')
    if hi and 'bdpt' in curves:
        curves['bdpt'] = sorted(curves['bdpt'] + curve(hi['results'][0]))
    if pa:
        curves['path'] = curve(pa['results'][0])
    if be:
        curves['stbpt-before'] = curve(be['results'][0])
    print(f'== {name}')
    for m, c in curves.items():
        print(f'  {m:13s} ' + '  '.join(f'{e}:{t:.1f}s/{f:.3f}/fl{fl:.3f}' for e, t, f, fl in c))
    for m, base in [('stbpt', 'bdpt'), ('stbpt', 'path'), ('stbpt', 'stbpt-before'),
                    ('stbpt-before', 'path'), ('bdpt', 'path')]:
        if m not in curves or base not in curves:
            continue
        targets = sorted({round(f, 3) for _, _, f, _ in curves[m]}, reverse=True)
        for t in targets:
            a, b = at_flip(curves[m], t), at_flip(curves[base], t)
            if a and b:
                print(f'  {m} vs {base}, FLIP {t:.3f}: {a[0]:.2f} vs {b[0]:.2f} CPU s -> '
                      f'{b[0]/a[0]:.2f}x less CPU; flicker {a[1]:.4f} vs {b[1]:.4f} '
                      f'({b[1]/a[1]:.2f}x lower)')
