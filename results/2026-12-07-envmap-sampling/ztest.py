"""ztest.py A.exr B.exr: per-pixel z-test of two independent forecast renders (RGB + var.R/G/B,
the variance of each pixel's mean), as tests/common's assert_agrees: max |z| over every pixel and
channel against the Šidák threshold at family-wise α = 1e-3, and the global z of the image means
(threshold at α = 1e-3). The EXR holds each mean rounded to float32, so each image's variance gets
that rounding's, ulp²/12 (it matters only where a pixel is constant up to rounding: a uniform patch
of an envmap seen directly). Run with a Python that has Mitsuba 3 (it reads the EXRs)."""
import math, sys
import numpy as np
import mitsuba as mi
mi.set_variant('scalar_rgb')
from statistics import NormalDist

def read(p):
    b = mi.Bitmap(p)
    names = [f.name for f in b.struct_()]
    a = np.array(b, copy=False).reshape(-1, len(names))
    return a[:, [names.index(c) for c in 'RGB']], a[:, [names.index('var.' + c) for c in 'RGB']]

def thr(alpha, n):
    a = 1 - (1 - alpha) ** (1 / n)
    return NormalDist().inv_cdf(1 - a / 2)

(ma, va), (mb, vb) = read(sys.argv[1]), read(sys.argv[2])
v = va.astype(np.float64) + vb + (np.spacing(ma).astype(np.float64) ** 2 + np.spacing(mb).astype(np.float64) ** 2) / 12
n = ma.size
pos = v > 0
assert (ma[~pos] == mb[~pos]).all(), 'zero-variance pixels differ'
z = abs(ma[pos] - mb[pos]) / v[pos] ** 0.5
zg = (ma.sum() - mb.sum()) / v.sum() ** 0.5
t, t1 = thr(1e-3, n), thr(1e-3, 1)
# the power: B scaled by 1.03 (a 3% error) must be rejected by the global z
zc = (ma.sum() - 1.03 * mb.sum()) / (va.astype(np.float64).sum() + 1.03**2 * vb.astype(np.float64).sum()) ** 0.5
print(f'max|z| {z.max():.2f} (threshold {t:.2f} over {n}); global z {zg:.2f} (threshold {t1:.2f}); '
      f'means {ma.mean():.5f} {mb.mean():.5f}: {"AGREE" if z.max() < t and abs(zg) < t1 else "DISAGREE"}; '
      f'3% control: global z {zc:.2f} ({"detected" if abs(zc) >= t1 else "NOT detected"})')
