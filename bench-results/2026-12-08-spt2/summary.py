#!/usr/bin/env python3
"""Table of the A/B(/C) run: per change and binary, the CPU ratios of `bench update`
(`visible` measure: CPU s to no visible difference; whole update: change to empty queue,
median of 5) and the median whole update's phases in CPU ms. Usage: summary.py [DIR]"""
import glob, json, os, re, sys
d = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.abspath(__file__))
rows = {}
for f in sorted(glob.glob(os.path.join(d, "*_r[0-9].json"))):
    m = re.match(r"([a-z]+)_([A-Z]\d?)_r(\d)\.json", os.path.basename(f))
    if not m:
        continue
    change, v, r = m.groups()
    try:
        j = json.load(open(f))
    except ValueError:
        continue  # still being written
    o = j["orders"]
    u = o["priority"]["update_stats"]
    p = u["phases"]
    vis = j["measures"]["visible"]
    fmt = lambda x: "—" if x is None else "%.2f" % x
    rows.setdefault((change, v), []).append(
        "| %s | %s | %s | %s | %s | %s | %s / %s | %.1f / %.1f | %s | %s | %s |"
        % (
            change, v, r, fmt(vis["speedup_vs_scratch"]), fmt(j["whole_update"]["speedup_vs_scratch"]),
            fmt(vis["speedup_vs_random"]), fmt(vis.get("speedup_vs_random_pool")),
            fmt(j["whole_update"].get("speedup_vs_random_pool")),
            1e3 * o["priority"]["cpu_s_update"], 1e3 * o["scratch"]["cpu_s_update"],
            "%dk / %dk" % (u["photons_flagged"] / 1e3, u["scan_candidates"] / 1e3),
            "restart" if u["restarted"] else "",
            " / ".join("%.1f" % (1e3 * p[k]) for k in ["coverage", "scan", "keys", "trace", "apply"]),
        )
    )
print("| change | bin | round | vs scratch (visible) | whole update vs scratch | vs random (visible) | vs random_pool: visible / whole update | whole update ms: priority / scratch | flagged / candidates | | phases ms: coverage / scan / keys / trace / apply |")
print("|---|---|---|---|---|---|---|---|---|---|---|")
order = {"nudge": 0, "jump": 1, "occluder": 2, "light": 3}
for k in sorted(rows, key=lambda k: (order.get(k[0], 9), k[1])):
    for line in rows[k]:
        print(line)
