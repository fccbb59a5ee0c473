#!/usr/bin/env python3
"""Per-pixel z-test of two renders (independent seeds) from their EXR means and `var.*` layers
(variance of the pixel mean): z = (a − b)/sqrt(var_a + var_b), over every pixel and channel with
a positive variance. Prints the count, mean z, the rms of z (≈ 1 when the two agree) and the
share of |z| > 3 (0.27% for a normal), then the same for the image mean.

    ztest.py A.exr B.exr     (needs pip install numpy OpenEXR)
"""
import sys

import numpy as np
import OpenEXR
import Imath


def load(path):
    f = OpenEXR.InputFile(path)
    dw = f.header()["dataWindow"]
    w, h = dw.max.x - dw.min.x + 1, dw.max.y - dw.min.y + 1
    pt = Imath.PixelType(Imath.PixelType.FLOAT)
    get = lambda c: np.frombuffer(f.channel(c, pt), dtype=np.float32).reshape(h, w).astype(np.float64)
    return np.stack([get(c) for c in "RGB"]), np.stack([get("var." + c) for c in "RGB"])


(a, va), (b, vb) = load(sys.argv[1]), load(sys.argv[2])
ok = (va + vb) > 0
z = (a - b)[ok] / np.sqrt((va + vb)[ok])
print(f"pixels×channels {z.size}, mean z {z.mean():+.4f}, rms z {np.sqrt((z * z).mean()):.4f}, "
      f"|z|>3 {100 * (np.abs(z) > 3).mean():.3f}%")
# the image mean's variance: channels of a pixel fully correlated (an upper bound) and
# independent (a lower bound); the renders keep no covariance
n = a.shape[1] * a.shape[2]
v_hi = (np.sqrt(va).sum(axis=0) ** 2 + np.sqrt(vb).sum(axis=0) ** 2).sum() / (3 * n) ** 2
v_lo = (va.sum() + vb.sum()) / (3 * n) ** 2
d = a.mean() - b.mean()
print(f"image mean {a.mean():.6f} vs {b.mean():.6f}: z {d / np.sqrt(v_hi):+.3f} (correlated channels) "
      f"to {d / np.sqrt(v_lo):+.3f} (independent)")
