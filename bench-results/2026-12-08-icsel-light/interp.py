#!/usr/bin/env python3
# CPU seconds at a target mean FLIP, log-log between the bracketing levels of a report's
# "every effort level" tables (what bench quality's "speed-up CPU interpolated" does);
# "<= x" where the lowest level is already below the target.
import math, re, sys
def levels(md):
    out, cur = {}, None
    for line in open(md):
        m = re.match(r"## (.+): every effort level", line)
        if m:
            cur = m.group(1) + ("'" if m.group(1) in out else ""); out[cur] = []; continue
        if cur and re.match(r"\| \d", line):
            c = [x.strip() for x in line.strip().strip("|").split("|")]
            out[cur].append((float(c[0]), float(c[4]), float(c[5])))
    return out
def at(lv, t):
    lv = sorted(lv)
    if lv[0][2] <= t: return "<= %.2f" % lv[0][1]
    for (e0, c0, f0), (e1, c1, f1) in zip(lv, lv[1:]):
        if f0 > t >= f1:
            w = (math.log(t) - math.log(f0)) / (math.log(f1) - math.log(f0))
            return "%.2f" % math.exp(math.log(c0) + w * (math.log(c1) - math.log(c0)))
    return "not reached"
md, targets = sys.argv[1], [float(x) for x in sys.argv[2].split(",")]
lv = levels(md)
for t in targets:
    print(t, {k: at(v, t) for k, v in lv.items()})
