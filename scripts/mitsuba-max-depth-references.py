#!/usr/bin/env python3
"""Mitsuba 3 image means of tests/scenes/max-depth/room.xml at several `max_depth`s, for
tests/mitsuba_max_depth.rs (Mitsuba's `max_depth` counts path segments: forecast reads d as
d - 1 surface vertices).

For each depth d: PASSES independent renders of SPP samples per pixel (seed SEED_BASE + 1000 d + i)
with Mitsuba's `path`; the image mean per channel is the mean of the passes' image means, its
standard error their spread / sqrt(PASSES). Writes tests/reference/max-depth.json.

Usage (the Mitsuba venv):
    /work/mitsuba-venv/bin/python scripts/mitsuba-max-depth-references.py [--spp 1024] [--passes 32]
        [--depths 1,2,3,5] [--variant llvm_ad_rgb]
"""

import argparse
import json
import os
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENE = os.path.join(ROOT, "tests", "scenes", "max-depth", "room.xml")
OUT = os.path.join(ROOT, "tests", "reference", "max-depth.json")
SEED_BASE = 90000


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--spp", type=int, default=1024)
    ap.add_argument("--passes", type=int, default=32)
    ap.add_argument("--depths", default="1,2,3,5")
    ap.add_argument("--variant", default="llvm_ad_rgb")
    a = ap.parse_args()
    import mitsuba as mi

    mi.set_variant(a.variant)
    out = {"scene": "tests/scenes/max-depth/room.xml", "mitsuba": mi.__version__, "variant": a.variant,
           "integrator": "path", "spp_per_pass": a.spp, "passes": a.passes, "depths": {}}
    for d in [int(x) for x in a.depths.split(",")]:
        scene = mi.load_file(SCENE, max_depth=d, spp=a.spp)
        t0 = time.time()
        means = []
        for i in range(a.passes):
            seed = SEED_BASE + 1000 * d + i
            img = np.array(mi.render(scene, seed=seed, spp=a.spp))[:, :, :3].astype(np.float64)
            means.append(img.mean(axis=(0, 1)))
        m = np.array(means)
        mean, se = m.mean(axis=0), m.std(axis=0, ddof=1) / np.sqrt(a.passes)
        out["depths"][str(d)] = {"mean": mean.tolist(), "se": se.tolist(),
                                 "seeds": [SEED_BASE + 1000 * d, SEED_BASE + 1000 * d + a.passes - 1],
                                 "seconds": round(time.time() - t0, 1)}
        print(d, mean, se, flush=True)
    with open(OUT, "w") as f:
        json.dump(out, f, indent=1)
        f.write("\n")


if __name__ == "__main__":
    main()
