#!/usr/bin/env python3
"""Mitsuba 3 reference of the film's crop window for tests/mitsuba_film.rs: the 16 x 12 window at
(19, 13) of tests/scenes/film/crop.xml's 40 x 30 film, rendered PASSES times with SPP samples per
pixel (seed SEED_BASE + i) by Mitsuba's `path`; per pixel and channel the mean of the renders and
its standard error (their spread / sqrt(PASSES)). Writes tests/reference/film-crop.json (rows
top to bottom, RGB per pixel).

Usage (the Mitsuba venv):
    /work/mitsuba-venv/bin/python scripts/mitsuba-crop-reference.py [--spp 1024] [--passes 32]
"""

import argparse
import json
import os
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENE = os.path.join(ROOT, "tests", "scenes", "film", "crop.xml")
OUT = os.path.join(ROOT, "tests", "reference", "film-crop.json")
SEED_BASE = 50000


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--spp", type=int, default=1024)
    ap.add_argument("--passes", type=int, default=32)
    ap.add_argument("--variant", default="llvm_ad_rgb")
    a = ap.parse_args()
    import mitsuba as mi

    mi.set_variant(a.variant)
    scene = mi.load_file(SCENE, spp=a.spp)
    t0 = time.time()
    imgs = np.array([np.array(mi.render(scene, seed=SEED_BASE + i, spp=a.spp))[:, :, :3].astype(np.float64)
                     for i in range(a.passes)])
    h, w = imgs.shape[1:3]
    mean, se = imgs.mean(axis=0), imgs.std(axis=0, ddof=1) / np.sqrt(a.passes)
    r = lambda x: [float("%.7g" % v) for v in x.reshape(-1)]
    out = {"scene": "tests/scenes/film/crop.xml", "mitsuba": mi.__version__, "variant": a.variant,
           "integrator": "path", "film": [40, 30], "crop_offset": [19, 13], "size": [w, h],
           "spp_per_pass": a.spp, "passes": a.passes, "seeds": [SEED_BASE, SEED_BASE + a.passes - 1],
           "seconds": round(time.time() - t0, 1), "mean": r(mean), "se": r(se)}
    print(w, h, mean.mean(axis=(0, 1)))
    with open(OUT, "w") as f:
        json.dump(out, f)
        f.write("\n")


if __name__ == "__main__":
    main()
