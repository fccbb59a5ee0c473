#!/usr/bin/env python3
"""Image means of a Mitsuba 3 scene: Mitsuba 3 `path` (K independent seeds) against forecast
`pt` (its per-pixel variance channel), each with its standard error, and their ratio.

Usage: scripts/mean-vs-mitsuba.py SCENE.xml WIDTH HEIGHT [--mi-spp N] [--mi-runs K]
       [--spp N] [--method pt] [--forecast BIN] [--out DIR]
Needs the pip package `mitsuba` (scripts/bench-vs-mitsuba.sh makes a venv with it) and numpy.
Mitsuba renders in `scalar_rgb` (no LLVM needed) from inside the scene's folder, as the
folder's README says; `<default>`s `width`, `height`, `spp` are passed as parameters.
"""
import argparse, json, os, subprocess, sys
import numpy as np
import mitsuba as mi

ap = argparse.ArgumentParser()
ap.add_argument("scene"); ap.add_argument("width", type=int); ap.add_argument("height", type=int)
ap.add_argument("--mi-spp", type=int, default=256); ap.add_argument("--mi-runs", type=int, default=4)
ap.add_argument("--spp", type=int, default=1024); ap.add_argument("--method", default="pt")
ap.add_argument("--forecast", default="target/release/forecast"); ap.add_argument("--out", default="out/mean-vs-mitsuba")
ap.add_argument("--variant", default="scalar_rgb")
a = ap.parse_args()
mi.set_variant(a.variant)
os.makedirs(a.out, exist_ok=True)
name = os.path.splitext(os.path.basename(os.path.dirname(os.path.abspath(a.scene))))[0]
fc = os.path.abspath(a.forecast)
out = os.path.abspath(a.out)

# Mitsuba's per-run means, kept beside the outputs (a rerun reuses them)
cache = os.path.join(out, f"{name}-mitsuba-{a.width}x{a.height}-{a.mi_spp}x{a.mi_runs}.json")
if os.path.exists(cache):
    means = json.load(open(cache))
else:
    means = []
    cwd = os.getcwd()
    os.chdir(os.path.dirname(os.path.abspath(a.scene)))
    scene = mi.load_file(os.path.basename(a.scene), width=a.width, height=a.height, spp=a.mi_spp)
    for k in range(a.mi_runs):
        img = np.array(mi.render(scene, spp=a.mi_spp, seed=1000 + k))[..., :3]
        means.append(img.reshape(-1, 3).mean(0).tolist())
    os.chdir(cwd)
    json.dump(means, open(cache, "w"))
means = np.array(means)
mi_mean = means.mean(0)
mi_se = means.std(0, ddof=1) / np.sqrt(len(means)) if len(means) > 1 else np.full(3, np.nan)

prefix = os.path.join(out, f"{name}-{a.method}-{a.width}x{a.height}-{a.spp}")
subprocess.run([fc, "render", a.scene, "--method", a.method, "--spp", str(a.spp), "--resolution",
                f"{a.width}x{a.height}", "--seed", "1", "--out", prefix, "--quiet"], check=True)
exr = mi.Bitmap(prefix + ".exr")
chans = dict(exr.split())  # forecast's EXR: RGB, and the variance of the mean as var.R/G/B
fc_img, var = np.array(chans["<root>"])[..., :3], np.array(chans["var"])[..., :3]
n = fc_img.shape[0] * fc_img.shape[1]
fc_mean = fc_img.reshape(-1, 3).mean(0)
fc_se = np.sqrt(var.reshape(-1, 3).sum(0)) / n
ratio = fc_mean / mi_mean
ratio_se = ratio * np.sqrt((fc_se / fc_mean) ** 2 + (mi_se / mi_mean) ** 2)
row = {"scene": name, "resolution": [a.width, a.height], "method": a.method,
       "mitsuba": {"spp": a.mi_spp, "runs": a.mi_runs, "mean": mi_mean.tolist(), "se": mi_se.tolist()},
       "forecast": {"spp": a.spp, "mean": fc_mean.tolist(), "se": fc_se.tolist()},
       "ratio": ratio.tolist(), "ratio_se": ratio_se.tolist(),
       "z": ((fc_mean - mi_mean) / np.sqrt(fc_se ** 2 + mi_se ** 2)).tolist()}
print(json.dumps(row))
