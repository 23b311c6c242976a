import json, math, sys
def curve(res):
    return [(l['effort'], l['cpu_s'], l['flip_mean'], l['relmse_mean'], l['flicker']) for l in res['levels']]
def interp(c, target, key):  # key index: 2 flip, 3 relmse; returns cpu time, log-log
    for k,(e,t,f,r,fl) in enumerate(c):
        v = c[k][key]
        if v <= target:
            if k == 0: return None if v < target else t
            e0, e1 = c[k-1][key], v
            t0 = c[k-1][1]
            s = math.log(e0/target)/math.log(e0/e1)
            return t0*(t/t0)**s
    return None
def interp_flicker(c, time):  # flicker at equal CPU time, log-log on time
    for k in range(1,len(c)):
        t0,t1 = c[k-1][1], c[k][1]
        if t0 <= time <= t1:
            s = math.log(time/t0)/math.log(t1/t0)
            f0,f1=c[k-1][4],c[k][4]
            return f0*(f1/f0)**s
    return None
for p in sys.argv[1:]:
    r = json.load(open(p))
    a, b = curve(r['results'][0]), curve(r['results'][1])
    print(f"== {p}: {r['method']} vs {r['baseline']}, window {r.get('window')}, frames {r['frames'][0]}..{r['frames'][-1]}")
    for name, key in [('FLIP', 2), ('relMSE', 3)]:
        vals = sorted({round(x[key], 4) for x in a + b}, reverse=True)
        lo = max(min(x[key] for x in a), min(x[key] for x in b)); hi = min(a[0][key], b[0][key])
        # targets: geometric grid within the common range
        ts = [hi * (lo/hi)**(i/4) for i in range(5)] if hi > lo else []
        for t in ts:
            ta, tb = interp(a, t, key), interp(b, t, key)
            if ta and tb: print(f"  {name} {t:.4f}: {r['method']} {ta:.2f} CPU s, {r['baseline']} {tb:.2f} CPU s, speed-up {tb/ta:.2f}x")
        # below the common range: stbpt 1-spp vs baseline
        t = a[0][key]; tb = interp(b, t, key)
        if tb: print(f"  {name} {t:.4f} (method's first level): {a[0][1]:.2f} vs {tb:.2f} CPU s: {tb/a[0][1]:.2f}x")
        t = a[-1][key]; tb = interp(b, t, key)
        if tb: print(f"  {name} {t:.4f} (method's last level): {a[-1][1]:.2f} vs {tb:.2f} CPU s: {tb/a[-1][1]:.2f}x")
        else: print(f"  {name} {t:.4f} (method's last level, {a[-1][1]:.2f} CPU s): baseline not reached at {b[-1][0]} ({b[-1][1]:.2f} CPU s, {name} {b[-1][key]:.4f}) -> > {b[-1][1]/a[-1][1]:.2f}x")
    for (e,t,f,rr,fl) in a:
        fb = interp_flicker(b, t)
        if fb: print(f"  flicker at {t:.2f} CPU s: {r['method']} {fl:.4f}, {r['baseline']} {fb:.4f} ({fb/fl:.2f}x lower)")
