#!/usr/bin/env python3
"""The table of scripts/equal-time-vs-mitsuba.sh: per renderer and crop, from the renders
OUT/RENDERER-SEED.exr (seeds 1..SEEDS) and, where given, a reference image. Run with a Python
that has Mitsuba 3 (its Bitmap reads every EXR here: forecast's, Mitsuba's, LuxCore's, Blender's).

    et_metrics.py OUT SEEDS "RENDERER ..." "NAME=X,Y,W,H ..." [REFERENCE.exr]

A crop is X,Y,W,H in pixels, or in fractions of the frame when any of the four has a decimal
point (0.25,0.5,0.1,0.1), so that one named crop serves every resolution; `whole` is the frame.

Columns (each a mean over seeds where it is per render):
  noise   RMSE of one render from the seed-to-seed differences: sqrt(mean over seed pairs of
          MSE(a, b) / 2) — for an unbiased renderer its RMSE against the true image
  ref     RMSE against the reference (holds the reference's own noise and any bias)
  relmse  MSE against the reference / (the reference's crop mean)²  ("-" without a reference)
  relvar  noise² / (the crop mean)²: the relative variance, needing no reference
  mean    the crop's mean (pixels and channels): a renderer that cannot see part of a crop shows
          a low noise there but a lower mean
  spp, wall_s, cpu_s  from OUT/renders.tsv
  mean/ref  the crop mean over the reference's (with a reference)
Then, per crop, each renderer's relmse (relvar without a reference) over the best of the others
(`vs best other`): below 1 is ahead. With a reference, a renderer whose crop mean is more than
BLIND (3%) away from the reference's is marked `blind` and is not a "best other" (Mitsuba's
ptracer on glass seen directly, a peer that cannot render part of a crop, a render with no
sample). Writes OUT/table.txt and OUT/table.json.
"""
import json
import os
import sys

import numpy as np
import mitsuba as mi

mi.set_variant("scalar_rgb")
BLIND = 0.03


def read(path):
    b = mi.Bitmap(path)
    parts = dict(b.split())
    img = np.array(parts["<root>"] if "<root>" in parts else b, dtype=np.float64)
    return img[..., :3]


def crop_box(spec, w, h):
    if spec == "whole":
        return 0, 0, w, h
    v = spec.split(",")
    if len(v) != 4:
        raise SystemExit(f"et_metrics: a crop is X,Y,W,H, got {spec}")
    if any("." in x for x in v):
        f = [float(x) for x in v]
        x, y = int(round(f[0] * w)), int(round(f[1] * h))
        return x, y, max(1, int(round(f[2] * w))), max(1, int(round(f[3] * h)))
    return tuple(int(x) for x in v)


def main(argv):
    if len(argv) not in (4, 5):
        raise SystemExit(__doc__.split("\n\n")[1])
    out, seeds, renderers, crops = argv[0], int(argv[1]), argv[2].split(), argv[3].split()
    ref = read(argv[4]) if len(argv) == 5 and argv[4] else None
    crops = [("whole", "whole")] + [tuple(c.split("=", 1)) for c in crops if not c.startswith("whole=")]
    log = {}
    tsv = os.path.join(out, "renders.tsv")
    if os.path.exists(tsv):
        for line in open(tsv).read().splitlines()[1:]:
            r, s, spp, wall, cpu = line.split("\t")[:5]
            log.setdefault(r, []).append((float(spp), float(wall), float(cpu)))
    rows, table = [], {}
    for r in renderers:
        imgs = [read(os.path.join(out, f"{r}-{s}.exr")) for s in range(1, seeds + 1)
                if os.path.exists(os.path.join(out, f"{r}-{s}.exr"))]
        if not imgs:
            print(f"et_metrics: no render of {r}", file=sys.stderr)
            continue
        h, w = imgs[0].shape[:2]
        for name, spec in crops:
            x, y, cw, ch = crop_box(spec, w, h)
            cs = [i[y:y + ch, x:x + cw] for i in imgs]
            mean = float(np.mean([c.mean() for c in cs]))
            pairs = [np.mean((cs[a] - cs[b]) ** 2) for a in range(len(cs)) for b in range(a + 1, len(cs))]
            noise = float(np.sqrt(np.mean(pairs) / 2)) if pairs else float("nan")
            e = {"renderer": r, "crop": name, "box": [x, y, cw, ch], "noise": noise, "mean": mean,
                 "relvar": noise ** 2 / mean ** 2 if mean > 0 else float("nan"), "seeds": len(cs)}
            if ref is not None:
                rc = ref[y:y + ch, x:x + cw]
                mse = float(np.mean([np.mean((c - rc) ** 2) for c in cs]))
                e["ref"], e["relmse"], e["ref_mean"] = float(np.sqrt(mse)), mse / float(rc.mean()) ** 2, float(rc.mean())
                e["mean_ratio"] = mean / float(rc.mean())
                e["blind"] = bool(abs(e["mean_ratio"] - 1) > BLIND)
            if r in log:
                e["spp"], e["wall_s"], e["cpu_s"] = [float(np.mean([t[k] for t in log[r]])) for k in range(3)]
            rows.append(e)
            table.setdefault(name, {})[r] = e
    key = "relmse" if ref is not None else "relvar"
    lines = [f"{'renderer':<22} {'crop':<14} {'noise':>10} {'ref':>10} {'relmse':>10} {'relvar':>10} {'mean':>10} {'mean/ref':>8} {'spp':>8} {'wall_s':>7} {'cpu_s':>7}"]
    for e in rows:
        f = lambda k, p=".3e": format(e[k], p) if k in e else "-"
        lines.append(f"{e['renderer']:<22} {e['crop']:<14} {f('noise'):>10} {f('ref'):>10} {f('relmse'):>10} {f('relvar'):>10} "
                     f"{f('mean'):>10} {f('mean_ratio', '.3f'):>8} {f('spp', '.0f'):>8} {f('wall_s', '.1f'):>7} {f('cpu_s', '.1f'):>7}")
    lines.append("")
    lines.append(f"{key} over the best other renderer's (below 1: ahead of every other):")
    for name, per in table.items():
        parts = []
        for r, e in per.items():
            others = [o[key] for q, o in per.items() if q != r and np.isfinite(o[key]) and not o.get("blind")]
            if others and np.isfinite(e[key]) and min(others) > 0:
                best = min(others)
                parts.append(f"{r} {e[key] / best:.2f}x" + (" (blind)" if e.get("blind") else ""))
        lines.append(f"  {name:<14} " + ", ".join(parts))
    text = "\n".join(lines)
    print(text)
    open(os.path.join(out, "table.txt"), "a").write(text + "\n")
    json.dump({"key": key, "rows": rows}, open(os.path.join(out, "table.json"), "w"), indent=1)


if __name__ == "__main__":
    main(sys.argv[1:])
