#!/usr/bin/env python3
"""Table of bench-results/2026-12-07-spt/*.json: per run, photons flagged/re-shot, the
error just after the change, CPU s / photons to clean per order, and the ratios, for the
`visible` measure and the old `area` measure."""
import json, sys, glob, os
d = os.path.dirname(os.path.abspath(__file__))
for f in sorted(glob.glob(os.path.join(d, "*.json"))):
    j = json.load(open(f))
    o = j["orders"]
    print(f"== {os.path.basename(f)}: {j['what']} (Z {j['pool_photons']}, groups {j['groups']})")
    for name in ["priority", "random", "scratch"]:
        r = o[name]
        print(f"  {name:8} invalidated {r['groups_invalidated']:5} groups, pilots {r['pilots_traced']:6}, "
              f"total {r['photons_total']:7} photons {r['cpu_s_total']:.4f} CPU s; whole update "
              f"{r['cpu_s_update']:.4f} CPU s (runs {', '.join(f'{x:.4f}' for x in r['cpu_s_update_runs'])})")
    w = j["whole_update"]
    print(f"  whole update: vs random {w['speedup_vs_random']:.2f}, vs scratch {w['speedup_vs_scratch']:.2f}")
    for m in ["visible", "stale", "view", "area"]:
        mm = j["measures"][m]
        cells = []
        for name in ["priority", "random", "scratch"]:
            r = o[name]
            c, p = r["cpu_s_to_clean"][m], r["photons_to_clean"][m]
            cells.append(f"{name} {c:.4f}s/{p:.0f}" if c is not None else f"{name} —")
        def fmt(x):
            return f"{x:.2f}" if isinstance(x, (int, float)) else "—"
        print(f"  {m:7} steady {mm['steady_state_error']:.4f} after {o['priority']['error_after_change'][m]:.4f} "
              f"thr {mm['threshold']:.4f} | " + "; ".join(cells) +
              f" | vs random {fmt(mm['speedup_vs_random'])} ({fmt(mm['photon_ratio_vs_random'])}) "
              f"vs scratch {fmt(mm['speedup_vs_scratch'])} ({fmt(mm['photon_ratio_vs_scratch'])})")
