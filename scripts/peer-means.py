#!/usr/bin/env python3
"""A peer's image means against Mitsuba 3's, per region (docs/peers.md; run with Mitsuba's venv).

    peer-means.py 'REF_RUNS_GLOB' 'NAME=Y0:Y1,X0:X1 ...' PEER.exr ...

REF_RUNS_GLOB: Mitsuba's runs as .npy images (scripts/mean-vs-mitsuba.py mitsuba … writes them,
one per run); their mean is the reference, their spread over √K its standard error. A region is
rows Y0:Y1 and columns X0:X1 in pixels; `all` (the frame) is always added. Prints, per peer image
and region, the ratio peer / Mitsuba per channel, and ± Mitsuba's relative standard error (the
largest over the channels); the peer's own noise is not in it: render it with several seeds and
compare their ratios.
"""
import glob
import sys

import numpy as np
import mitsuba as mi

mi.set_variant("scalar_rgb")


def main(argv):
    runs = np.stack([np.load(f) for f in sorted(glob.glob(argv[0]))])
    regs = [("all", (slice(None), slice(None)))]
    for spec in argv[1].split():
        name, box = spec.split("=")
        ys, xs = box.split(",")
        y0, y1 = (int(v) for v in ys.split(":"))
        x0, x1 = (int(v) for v in xs.split(":"))
        regs.append((name, (slice(y0, y1), slice(x0, x1))))
    ref = runs.mean(0)
    for f in argv[2:]:
        a = np.array(mi.Bitmap(f), dtype=np.float64)[..., :3]
        out = []
        for name, (ys, xs) in regs:
            m0 = ref[ys, xs].reshape(-1, 3).mean(0)
            se = runs[:, ys, xs].reshape(len(runs), -1, 3).mean(1).std(0, ddof=1) / np.sqrt(len(runs))
            r = a[ys, xs].reshape(-1, 3).mean(0) / m0
            out.append(f"{name} " + "/".join(f"{x:.3f}" for x in r) + f" (±{(se / m0).max():.3f})")
        print(f"{f}: " + " | ".join(out))


if __name__ == "__main__":
    main(sys.argv[1:])
