#!/usr/bin/env python3
"""Mean HDR-FLIP and flicker of a `chronolux render` output folder against Mitsuba's
references, with the peers' harness definitions (../shared/peers/harness/metrics.py):
FLIP = mean over the scored frames of flip-evaluator's mean HDR-FLIP; flicker = mean over
consecutive scored pairs (t-1, t) of mean |(I_t - I_{t-1}) - (R_t - R_{t-1})| / mean(R_t).
Usage: score.py OUTPUT_DIR REFS_DIR   (REFS_DIR holds mitsuba_fNN.exr)
Reads the beauty channels R, G, B exactly (our frames also carry a noisy layer)."""
import os
import sys

import numpy as np
import OpenEXR
import flip_evaluator as fl

FRAMES = [0, 1, 2, 3, 4, 5, 6, 7, 12, 24, 36, 47]


def read(path, exact):
    with OpenEXR.File(path, separate_channels=True) as f:
        ch = f.channels()
        def pick(c):
            if c in ch:
                return ch[c].pixels.astype(np.float32)
            if exact:
                raise KeyError(f"{path}: no channel {c}")
            for n in ch:
                if n.endswith("." + c):
                    return ch[n].pixels.astype(np.float32)
            raise KeyError(f"{path}: no channel {c} in {list(ch)}")
        return np.stack([pick("R"), pick("G"), pick("B")], axis=-1)


out, refs = sys.argv[1], sys.argv[2]
img, ref, flips = {}, {}, []
for f in FRAMES:
    img[f] = read(os.path.join(out, f"frame_{f:04d}.exr"), True).astype(np.float64)
    ref[f] = read(os.path.join(refs, f"mitsuba_f{f:02d}.exr"), False).astype(np.float64)
    r = np.ascontiguousarray(np.maximum(ref[f], 0), dtype=np.float32)
    t = np.ascontiguousarray(np.maximum(img[f], 0), dtype=np.float32)
    flips.append(float(fl.evaluate(r, t, "HDR", inputsRGB=False, applyMagma=False, computeMeanError=True)[1]))
fl_pairs = [
    float(np.mean(np.abs((img[b] - img[a]) - (ref[b] - ref[a]))) / float(np.mean(ref[b])))
    for a, b in zip(FRAMES, FRAMES[1:]) if b == a + 1
]
print(f"flip_mean {np.mean(flips):.4f} flicker {np.mean(fl_pairs):.4f} frames {len(flips)} pairs {len(fl_pairs)}")
