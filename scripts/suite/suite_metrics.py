"""The suite's error measures, with the peers harness's definitions
(../shared/peers/harness/metrics.py and mitsuba_time_to_flip.py, copied here so that nothing
imports Mitsuba):

- FLIP: mean over the scored frames of flip-evaluator's mean HDR-FLIP of the frame against
  the reference (exposures chosen by FLIP from the reference), negative values clamped to 0;
- flicker: mean over consecutive scored pairs (t-1, t) of
  mean |(I_t - I_{t-1}) - (R_t - R_{t-1})| / mean(R_t);
- interp: CPU seconds (or flicker) at a target FLIP, log-log between the two levels that
  straddle it; a target already met by the cheapest level gives that level's figure marked
  as an upper bound ("<="), one never met gives None.
"""
import math

import numpy as np


def read_beauty(path):
    """R, G, B of an EXR as float64: the top-level channels exactly when present (Chronolux's
    frames also carry layers), else the first `*.R` etc."""
    import OpenEXR
    with OpenEXR.File(path, separate_channels=True) as f:
        ch = f.channels()

        def pick(c):
            if c in ch:
                return ch[c].pixels.astype(np.float64)
            for n in ch:
                if n.endswith("." + c):
                    return ch[n].pixels.astype(np.float64)
            raise KeyError(f"{path}: no channel {c} in {list(ch)}")

        return np.stack([pick("R"), pick("G"), pick("B")], axis=-1)


def flip(ref, img):
    import flip_evaluator as fl
    r = np.ascontiguousarray(np.maximum(ref, 0), dtype=np.float32)
    t = np.ascontiguousarray(np.maximum(img, 0), dtype=np.float32)
    return float(fl.evaluate(r, t, "HDR", inputsRGB=False, applyMagma=False, computeMeanError=True)[1])


def flicker(imgs, refs, frames):
    v = []
    for k in range(1, len(frames)):
        if frames[k] != frames[k - 1] + 1:
            continue
        d = (imgs[k] - imgs[k - 1]) - (refs[k] - refs[k - 1])
        v.append(float(np.mean(np.abs(d)) / np.mean(refs[k])))
    return float(np.mean(v)) if v else None


def interp(levels, target, key="cpu_s"):
    """levels: dicts with "flip" and key, in increasing effort. Returns (value, bound) with
    bound "=" (interpolated), "<=" (the first level already meets it) or (None, "not reached")."""
    levels = [lv for lv in levels if lv.get(key) is not None and lv.get("flip") is not None]
    if not levels:
        return None, "not reached"
    if levels[0]["flip"] <= target:
        return levels[0][key], "<="
    for a, b in zip(levels, levels[1:]):
        if a["flip"] >= target >= b["flip"]:
            la, lb = math.log(a["flip"]), math.log(b["flip"])
            w = 0.0 if la == lb else (math.log(target) - la) / (lb - la)
            return math.exp(math.log(a[key]) + w * (math.log(b[key]) - math.log(a[key]))), "="
    return None, "not reached"
