#!/usr/bin/env python3
"""Mitsuba 3's own texture gradients: the table `src/texture/tests.rs` (`grad_agrees_with_mitsuba`)
checks forecast's `Bitmap::eval_1_grad` against (what `bumpmap` tilts the normal by).

Reads the committed images of tests/data/texture/ (written by scripts/mitsuba-texture-values.py)
and evaluates Mitsuba's bitmap `eval_1_grad` (variant scalar_rgb) at fixed uv points, for each
image, filter_type, wrap_mode, raw both ways, and to_uv transforms that scale, rotate, shear,
mirror and translate (on square and non-square images). Output: tests/data/texture/mitsuba-grad.csv,
one row per (case, uv point):

    case,filename,filter_type,wrap_mode,raw,m00,m01,m02,m10,m11,m12,u,v,du,dv,eval_1

`m..` are the rows of the case's `to_uv` matrix as Mitsuba holds it, `du, dv` Mitsuba's gradient
and `eval_1` its value there; every number is the shortest decimal that reads back as the same
float32. Points within 2e-3 texel of a bilinear cell's edge (a texel centre, where the gradient
jumps) are left out, so the table does not depend on which cell a rounding picks.

Usage: /work/mitsuba-venv/bin/python scripts/mitsuba-texture-grad.py
"""
from pathlib import Path

import mitsuba as mi
import numpy as np

mi.set_variant("scalar_rgb")
mi.set_log_level(mi.LogLevel.Error)

ROOT = Path(__file__).resolve().parent.parent
DATA = ROOT / "tests" / "data" / "texture"

POINTS = [
    (0.5, 0.45), (0.1, 0.13), (0.37, 0.81), (0.93, 0.07), (0.02, 0.98), (0.61, 0.29),
    (-0.2, 0.4), (1.3, 0.55), (0.45, -0.35), (0.71, 1.63), (-1.15, -0.61), (2.43, -1.77),
    (-0.03, 0.51), (1.04, 0.99), (0.77, 0.66), (0.26, 0.44), (0.013, 0.021), (0.987, 0.991),
]

T = mi.ScalarTransform3f
AFFINE = T().translate([0.25, -0.1]) @ T().rotate(30) @ T().scale([2, 3])
FLIP_SHIFT = T().translate([0.3, 0.2]) @ T().scale([-1.5, 0.75])
SHEAR = mi.ScalarTransform3f(mi.ScalarMatrix3f([[1.0, 0.6, 0.05], [-0.3, 1.4, 0.0], [0.0, 0.0, 1.0]]))


def cases():
    images = ["rgb8.png", "grey8.png", "rgb16.png", "rgb.exr", "grey.exr", "rgb.hdr", "rgb8.jpg"]
    out = []
    for name in images:
        for w in ["repeat", "mirror", "clamp"]:
            out.append(dict(filename=name, filter_type="bilinear", wrap_mode=w, raw=False, to_uv=T()))
        out.append(dict(filename=name, filter_type="nearest", wrap_mode="repeat", raw=False, to_uv=T()))
    for name, w in [("rgb8.png", "repeat"), ("grey8.png", "mirror"), ("rgb16.png", "clamp"), ("rgb8.jpg", "mirror")]:
        out.append(dict(filename=name, filter_type="bilinear", wrap_mode=w, raw=True, to_uv=T()))
    for name, w, m in [("rgb8.png", "repeat", AFFINE), ("rgb8.png", "mirror", SHEAR), ("grey8.png", "clamp", AFFINE),
                       ("rgb.exr", "clamp", FLIP_SHIFT), ("rgb.exr", "repeat", SHEAR), ("grey.exr", "mirror", FLIP_SHIFT),
                       ("rgb.hdr", "repeat", AFFINE)]:
        out.append(dict(filename=name, filter_type="bilinear", wrap_mode=w, raw=False, to_uv=m))
    for i, c in enumerate(out):
        c["case"] = i
    return out


def f(x):
    """The shortest decimal that reads back as the same float32."""
    return str(np.float32(x))


def near_cell_edge(tex, m, u, v):
    """True when the point lies within 2e-3 texel of a bilinear cell edge (texel centres)."""
    res = np.array(tex.resolution(), dtype=np.float64)
    p = m[:2, :2].astype(np.float64) @ np.array([u, v]) + m[:2, 2]
    q = p * res - 0.5
    frac = q - np.floor(q)
    return bool(np.any(np.minimum(frac, 1.0 - frac) < 2e-3))


def main():
    lines = ["case,filename,filter_type,wrap_mode,raw,m00,m01,m02,m10,m11,m12,u,v,du,dv,eval_1"]
    for case in cases():
        tex = mi.load_dict({"type": "bitmap", "filename": str(DATA / case["filename"]),
                            "filter_type": case["filter_type"], "wrap_mode": case["wrap_mode"],
                            "raw": case["raw"], "to_uv": case["to_uv"]})
        m = np.array(case["to_uv"].matrix, dtype=np.float32)
        if not np.array_equal(m[2], [0, 0, 1]):
            raise SystemExit(f"case {case['case']}: to_uv is not affine")
        mat = [f(m[i, j]) for i in range(2) for j in range(3)]
        head = [str(case["case"]), case["filename"], case["filter_type"], case["wrap_mode"], str(case["raw"]).lower()]
        for u, v in POINTS:
            if near_cell_edge(tex, m, u, v):
                continue
            si = mi.SurfaceInteraction3f()
            si.uv = mi.Point2f(u, v)
            g = tex.eval_1_grad(si)
            y = tex.eval_1(si)
            lines.append(",".join(head + mat + [f(np.float32(u)), f(np.float32(v)), f(g[0]), f(g[1]), f(y)]))
    (DATA / "mitsuba-grad.csv").write_text("\n".join(lines) + "\n")
    print(f"wrote {len(lines) - 1} rows to {DATA / 'mitsuba-grad.csv'}")


if __name__ == "__main__":
    main()
