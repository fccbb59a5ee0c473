#!/usr/bin/env python3
"""Per-pixel variance of one sample inside a region, from the seeds of scripts/frame-variance.sh.

    scripts/pixel-variance.py PREFIX SEEDS SPP X,Y,W,H [NAME:X,Y,W,H ...]

PREFIX is frame-variance's image prefix (out/frames/SCENE-METHOD; images PREFIX-s1.exr ..
PREFIX-sSEEDS.exr). Prints the region's variance of one sample (half the squared difference of
consecutive seeds times SPP, mean over RGB: the figure frame-variance.sh prints for --crop), the
share of it held by its noisiest 1% / 5% / 10% of pixels (how heavy-tailed it is), a map of the
region (left: mean, right: variance, log scale from the median), and the share of each named
sub-rectangle (coordinates relative to the region). Needs `pip install numpy OpenEXR`; not used
by the tests.
"""
import sys

import numpy as np
import OpenEXR


def load(path, x, y, w, h):
    with OpenEXR.File(path) as f:
        ch = f.channels()
        if "RGB" in ch:
            rgb = ch["RGB"].pixels
        else:
            rgb = np.stack([ch[c].pixels for c in "RGB"], -1)
        return np.asarray(rgb, dtype=np.float64)[y:y + h, x:x + w, :3]


def main(argv):
    if len(argv) < 5:
        sys.exit(__doc__)
    prefix, seeds, spp = argv[1], int(argv[2]), int(argv[3])
    x, y, w, h = map(int, argv[4].split(","))
    a = np.stack([load(f"{prefix}-s{s}.exr", x, y, w, h) for s in range(1, seeds + 1)])
    var = (((a[1:] - a[:-1]) ** 2).mean(-1) * spp / 2).mean(0)
    mean = a.mean(0).mean(-1)
    total = var.sum()
    top = np.sort(var.ravel())[::-1]
    shares = [top[: max(1, len(top) * p // 100)].sum() / total for p in (1, 5, 10)]
    print(f"variance per sample {var.mean():.4g}; noisiest 1% / 5% / 10% of pixels hold "
          + " / ".join(f"{s:.2f}" for s in shares))
    ramp = " .:-=+*#%@"
    median = max(np.median(var), 1e-30)
    for r in range(h):
        left = "".join(ramp[min(9, int(v / mean.max() * 9.99))] for v in mean[r])
        right = "".join(ramp[min(9, int(np.log2(max(v / median, 1.0)) * 1.5))] for v in var[r])
        print(left, "|", right)
    for arg in argv[5:]:
        name, rect = arg.split(":")
        sx, sy, sw, sh = map(int, rect.split(","))
        print(f"{name}: {var[sy:sy + sh, sx:sx + sw].sum() / total:.2f} of the variance")


if __name__ == "__main__":
    main(sys.argv)
