#!/usr/bin/env python3
"""relMSE and HDR-FLIP of TEST.exr against REF.exr, exactly as harness/metrics.py computes them.

  .venv/bin/python relmse.py TEST.exr REF.exr [--no-flip] [--json]

relMSE   = mean over pixels and channels of (I - R)^2 / (R^2 + 0.01)
HDR-FLIP = mean of flip-evaluator's HDR mode on the linear images (negatives clamped to 0,
           inputsRGB=False, exposure range chosen by FLIP from the reference); ~1-3 s at 256^2.
"""
import argparse
import json
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "harness"))
from exr_io import read_exr  # noqa: E402

EPS = 1e-2


def rel_mse(img, ref):
    return float(np.mean((img - ref) ** 2 / (ref ** 2 + EPS)))


def hdr_flip(ref, test):
    import flip_evaluator as fl
    ref = np.ascontiguousarray(np.maximum(ref, 0), dtype=np.float32)
    test = np.ascontiguousarray(np.maximum(test, 0), dtype=np.float32)
    return float(fl.evaluate(ref, test, "HDR", inputsRGB=False, applyMagma=False, computeMeanError=True)[1])


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("test")
    ap.add_argument("ref")
    ap.add_argument("--no-flip", action="store_true")
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args()
    I = read_exr(a.test).astype(np.float64)
    R = read_exr(a.ref).astype(np.float64)
    if I.shape != R.shape:
        sys.exit(f"shape mismatch: {I.shape} vs {R.shape}")
    res = {"relmse": rel_mse(I, R), "mean_test": float(I.mean()), "mean_ref": float(R.mean())}
    if not a.no_flip:
        res["hdr_flip"] = hdr_flip(R, I)
    if a.json:
        print(json.dumps(res))
    else:
        print(f"relMSE   {res['relmse']:.6f}")
        if "hdr_flip" in res:
            print(f"HDR-FLIP {res['hdr_flip']:.4f}")
        print(f"mean     test {res['mean_test']:.5f}  ref {res['mean_ref']:.5f}")


if __name__ == "__main__":
    main()
