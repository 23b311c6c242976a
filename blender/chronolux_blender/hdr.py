"""Writing Radiance HDR (RGBE) files, flat scanlines: the constant map of a uniform world."""

import math


def _rgbe(c):
    v = max(c)
    if not (v > 1e-32) or not math.isfinite(v):
        return bytes(4)
    m, e = math.frexp(v)  # v = m·2^e, m in [0.5, 1)
    scale = 256.0 / 2.0 ** e
    return bytes(
        [max(0, min(255, int(round(max(x, 0.0) * scale - 0.5)))) for x in c[:3]] + [max(0, min(255, e + 128))]
    )


def write(path, width, height, pixels):
    """``pixels``: width·height (r, g, b) tuples of linear radiance, top row first."""
    with open(path, "wb") as f:
        f.write(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y %d +X %d\n" % (height, width))
        for p in pixels:
            f.write(_rgbe(p))
