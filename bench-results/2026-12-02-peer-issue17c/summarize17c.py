"""Issue 17 goal 3, third run: CPU s to HDR-FLIP 0.08 (log-log between levels) and flicker
there, for Mitsuba 3, Cycles + OIDN, our path + OIDN and stbpt + OIDN (1 spp, K 2 -> 4,
mean of our runs a and b). Usage: python3 summarize17c.py RESULTS_DIR"""
import json, math, re, sys, os
D = sys.argv[1] if __name__ == "__main__" else None
def interp(lv, t, key):
    """The CPU s (or flicker: `key`) at FLIP `t`, log-log between the levels around it."""
    for a, b in zip(lv, lv[1:]):
        if a["flip"] >= t >= b["flip"]:
            w = math.log(t / a["flip"]) / math.log(b["flip"] / a["flip"])
            return math.exp(math.log(a[key]) + w * math.log(b[key] / a[key]))
def last_json(p, d=None):
    """The levels of a peer harness's output (its last JSON line)."""
    return json.loads([l for l in open(os.path.join(d or D, p)) if l.startswith("{")][-1])["levels"]
def ours(name):
    out = {}
    for r in "ab":
        for line in open(os.path.join(D, f"ours-{r}-{name}.err")):
            m = re.search(r"effort (\d+): .* ([\d.]+) s CPU, FLIP mean ([\d.]+) .* flicker ([\d.]+)", line)
            if m:
                out.setdefault(int(m[1]), []).append((float(m[2]), float(m[3]), float(m[4])))
    return [{"effort": e, "cpu_s": sum(x[0] for x in v) / len(v), "flip": v[0][1], "flicker": v[0][2]}
            for e, v in sorted(out.items())]
def main():
    rows = {"Mitsuba 3": last_json("mitsuba.json"), "Cycles + OIDN": last_json("cycles.json"),
            "ours path + OIDN": ours("path"), "ours stbpt + OIDN, 1 spp, K 2 -> 4": [ours("w2")[0], ours("w4")[0]]}
    res = {}
    for k, lv in rows.items():
        res[k] = (interp(lv, 0.08, "cpu_s"), interp(lv, 0.08, "flicker"))
        print(f"{k}: levels {[(round(l['cpu_s'], 2), round(l['flip'], 4)) for l in lv]}; "
              f"CPU s at 0.08 {res[k][0]:.2f}, flicker {res[k][1]:.4f}")
    print("K = 8:", ours("w8"))
    best = res["ours stbpt + OIDN, 1 spp, K 2 -> 4"][0]
    for k in ("Mitsuba 3", "Cycles + OIDN", "ours path + OIDN"):
        print(f"{k} / stbpt: {res[k][0] / best:.2f}x")

if __name__ == "__main__":
    main()
