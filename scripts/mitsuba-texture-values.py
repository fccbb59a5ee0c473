#!/usr/bin/env python3
"""Mitsuba 3's own texture values: the table `src/texture/tests.rs` (`agrees_with_mitsuba`)
checks forecast's `bitmap` and `checkerboard` against.

Writes the small test images of tests/data/texture/ (with Mitsuba's own writers, from fixed
formulas, so a rerun gives the same texels) and evaluates them, and checkerboards, with Mitsuba
(variant scalar_rgb) at a fixed list of uv points, for each filter_type and wrap_mode, raw
true/false and some to_uv transforms. Output: tests/data/texture/mitsuba-values.csv, one row per
(case, uv point):

    case,texture,filename,filter_type,wrap_mode,raw,m00,m01,m02,m10,m11,m12,
    c0_r,c0_g,c0_b,c1_r,c1_g,c1_b,u,v,r,g,b,eval_1,mean

`m..` are the rows of the case's `to_uv` matrix as Mitsuba holds it; every number is the
shortest decimal that reads back as the same float32; `c0`, `c1` the checkerboard's colours (0 for bitmaps); `r,g,b` = `eval`, `eval_1`
and `mean` as Mitsuba returns them.

Usage: python scripts/mitsuba-texture-values.py
Needs the pip package `mitsuba` (3.9; scripts/bench-vs-mitsuba.sh makes a venv with it) and numpy.
"""
from pathlib import Path

import mitsuba as mi
import numpy as np

mi.set_variant("scalar_rgb")
mi.set_log_level(mi.LogLevel.Error)  # not the [0, 1] range warnings of the float images

ROOT = Path(__file__).resolve().parent.parent
DATA = ROOT / "tests" / "data" / "texture"

# uv points: inside the unit square and outside it (for the wrap modes), none on a texel edge
# of the images' resolutions (3, 4, 5, 8) after the identity to_uv.
POINTS = [
    (0.5, 0.5), (0.1, 0.13), (0.37, 0.81), (0.93, 0.07), (0.02, 0.98), (0.61, 0.29),
    (-0.2, 0.4), (1.3, 0.55), (0.45, -0.35), (0.71, 1.63), (-1.15, -0.61), (2.43, -1.77),
    (-0.03, 0.51), (1.04, 0.99), (0.77, 0.66), (0.26, 0.44),
]


def code8(x, y, c):
    """A spread of 8-bit codes: 0 and 255 appear, and codes in the sRGB curve's linear part."""
    return (x * 73 + y * 151 + c * 37 + 11 * x * y) % 256 if (x + y + c) % 5 else (x * 3 + c) % 11


def make_images():
    DATA.mkdir(parents=True, exist_ok=True)
    rgb8 = np.array([[[code8(x, y, c) for c in range(3)] for x in range(5)] for y in range(4)], dtype=np.uint8)
    rgb8[0, 0] = [255, 0, 128]
    mi.Bitmap(rgb8).write(str(DATA / "rgb8.png"))
    grey8 = np.array([[[(x * 97 + y * 41 + 5) % 256] for x in range(3)] for y in range(2)], dtype=np.uint8)
    mi.Bitmap(grey8, pixel_format=mi.Bitmap.PixelFormat.Y).write(str(DATA / "grey8.png"))
    rgb16 = np.array(
        [[[(x * 9973 + y * 21011 + c * 7919 + 3) % 65536 for c in range(3)] for x in range(4)] for y in range(3)],
        dtype=np.uint16,
    )
    mi.Bitmap(rgb16).write(str(DATA / "rgb16.png"))
    rgbf = np.array(
        [[[((x + 1) * (y + 2) * (c + 1) % 11) / 3.0 for c in range(3)] for x in range(4)] for y in range(3)],
        dtype=np.float32,
    )
    rgbf[1, 2] = [0.0, 0.015625, 5.5]
    mi.Bitmap(rgbf).write(str(DATA / "rgb.exr"))
    greyf = np.array([[[(x * 5 + y * 3 + 1) / 4.0] for x in range(3)] for y in range(2)], dtype=np.float32)
    mi.Bitmap(greyf, pixel_format=mi.Bitmap.PixelFormat.Y).write(str(DATA / "grey.exr"))
    hdr = np.array([[[(x + 2 * y + c + 1) * 0.37 for c in range(3)] for x in range(3)] for y in range(3)], dtype=np.float32)
    mi.Bitmap(hdr).write(str(DATA / "rgb.hdr"))
    # JPEG: flat 8x8 blocks of one colour each (a DC-only block decodes to the same bytes in
    # every conforming decoder), 4 blocks wide and 3 high, written at the best quality
    blocks = [[[40, 200, 90], [250, 10, 30], [128, 128, 128], [5, 60, 220]],
              [[0, 0, 0], [255, 255, 255], [190, 150, 20], [70, 30, 120]],
              [[12, 240, 180], [100, 100, 30], [220, 90, 160], [33, 77, 99]]]
    jpg = np.zeros((24, 32, 3), dtype=np.uint8)
    for by in range(3):
        for bx in range(4):
            jpg[by * 8:(by + 1) * 8, bx * 8:(bx + 1) * 8] = blocks[by][bx]
    mi.Bitmap(jpg).write(str(DATA / "rgb8.jpg"), quality=100)


T = mi.ScalarTransform3f
AFFINE = T().translate([0.25, -0.1]) @ T().rotate(30) @ T().scale([2, 3])
FLIP_SHIFT = T().translate([0.3, 0.2]) @ T().scale([-1.5, 0.75])


def cases():
    images = ["rgb8.png", "grey8.png", "rgb16.png", "rgb.exr", "grey.exr", "rgb.hdr", "rgb8.jpg"]
    out = []
    for name in images:
        for f in ["bilinear", "nearest"]:
            for w in ["repeat", "mirror", "clamp"]:
                out.append(dict(texture="bitmap", filename=name, filter_type=f, wrap_mode=w, raw=False, to_uv=T()))
    for name, f, w in [("rgb8.png", "bilinear", "repeat"), ("rgb8.png", "nearest", "mirror"),
                       ("grey8.png", "bilinear", "clamp"), ("rgb16.png", "nearest", "clamp"),
                       ("rgb16.png", "bilinear", "mirror"), ("rgb8.jpg", "bilinear", "mirror"),
                       ("rgb.exr", "bilinear", "repeat")]:
        out.append(dict(texture="bitmap", filename=name, filter_type=f, wrap_mode=w, raw=True, to_uv=T()))
    for name, f, w, m in [("rgb8.png", "bilinear", "repeat", AFFINE), ("rgb8.png", "nearest", "clamp", AFFINE),
                          ("rgb.exr", "nearest", "mirror", FLIP_SHIFT), ("rgb.exr", "bilinear", "clamp", FLIP_SHIFT)]:
        out.append(dict(texture="bitmap", filename=name, filter_type=f, wrap_mode=w, raw=False, to_uv=m))
    grey = lambda v: [v, v, v]
    for c0, c1, m in [(grey(0.4), grey(0.2), T()),
                      ([0.9, 0.1, 0.2], [0.05, 0.6, 0.3], T().scale([4, 4])),
                      ([0.3, 0.7, 0.5], [1.0, 0.25, 0.0], AFFINE)]:
        out.append(dict(texture="checkerboard", c0=c0, c1=c1, to_uv=m))
    for i, c in enumerate(out):
        c["case"] = i
    return out


def plugin(case):
    if case["texture"] == "bitmap":
        return {"type": "bitmap", "filename": str(DATA / case["filename"]), "filter_type": case["filter_type"],
                "wrap_mode": case["wrap_mode"], "raw": case["raw"], "to_uv": case["to_uv"]}
    colour = lambda c: c[0] if c[0] == c[1] == c[2] else {"type": "rgb", "value": c}
    # Mitsuba's defaults are the floats 0.4 and 0.2: a grey is given as a float
    return {"type": "checkerboard", "color0": colour(case["c0"]), "color1": colour(case["c1"]),
            "to_uv": case["to_uv"]}


def f(x):
    """The shortest decimal that reads back as the same float32."""
    return str(np.float32(x))


def main():
    make_images()
    lines = ["case,texture,filename,filter_type,wrap_mode,raw,m00,m01,m02,m10,m11,m12,"
             "c0_r,c0_g,c0_b,c1_r,c1_g,c1_b,u,v,r,g,b,eval_1,mean"]
    for case in cases():
        tex = mi.load_dict(plugin(case))
        m = np.array(case["to_uv"].matrix, dtype=np.float32)
        if not np.array_equal(m[2], [0, 0, 1]):
            raise SystemExit(f"case {case['case']}: to_uv is not affine")
        mat = [f(m[i, j]) for i in range(2) for j in range(3)]
        c0 = [f(np.float32(v)) for v in case.get("c0", [0, 0, 0])]
        c1 = [f(np.float32(v)) for v in case.get("c1", [0, 0, 0])]
        head = [str(case["case"]), case["texture"], case.get("filename", ""), case.get("filter_type", ""),
                case.get("wrap_mode", ""), str(case.get("raw", False)).lower()]
        mean = tex.mean()
        for u, v in POINTS:
            si = mi.SurfaceInteraction3f()
            si.uv = mi.Point2f(u, v)
            rgb = tex.eval(si)
            y = tex.eval_1(si)
            vals = [f(np.float32(u)), f(np.float32(v)), f(rgb[0]), f(rgb[1]), f(rgb[2]), f(y), f(mean)]
            lines.append(",".join(head + mat + c0 + c1 + vals))
    (DATA / "mitsuba-values.csv").write_text("\n".join(lines) + "\n")
    print(f"wrote {len(lines) - 1} rows to {DATA / 'mitsuba-values.csv'}")


if __name__ == "__main__":
    main()
