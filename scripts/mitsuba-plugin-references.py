#!/usr/bin/env python3
"""Per-plugin Mitsuba 3 reference images for tests/mitsuba_plugins.rs.

Writes the small scenes of tests/scenes/mitsuba-plugins/ (XML, and the textures and meshes they
read, all generated here, deterministically) and renders each with Mitsuba 3.9.1's `path`
integrator into tests/reference/plugins/ (ZIP-compressed EXR, row 0 at the top):

    NAME.exr        the mean of all passes: R, G, B (float32) and var.R, var.G, var.B, the
                    per-pixel variance of the mean (the spread of the passes' means / passes;
                    float32 rounded to 8 significant bits, so that it compresses)
    NAME.half0.exr  the mean of the even passes (R, G, B, half floats)
    NAME.half1.exr  the mean of the odd passes  (R, G, B, half floats)
    renders.jsonl   one line per render: spp, passes, seeds, wall time, image mean, noise

Each scene is rendered in PASSES passes of SPP / PASSES samples, pass i with seed
SEED_BASE + i, so the halves are independent and, as for tests/reference/cornell-box-mitsuba-256,
RMSE(half0, half1) / 2 estimates the noise of the full image.

Every scene is the same closed room (the cornell-box walls, x in [-1, 1], y in [0, 2], extended
to z in [-1, 4.5] so that the camera at (0, 1, 3.88) is inside it; vertical fov 36 deg, so every
pixel sees the room's inside), 64 x 64 pixels, a box pixel filter (forecast's pixel estimator:
the plain average over the pixel), the `independent` sampler, `max_depth` 65 (64 surface
vertices with NEE at each: forecast's `--max-depth 64`), a 1.2 x 1.2 ceiling light, walls
one-sided diffuse, and the plugin under test.

Usage (the Mitsuba venv: pip install mitsuba numpy pillow openexr; apt-get install -y
libllvm19 for the llvm variant):

    /work/mitsuba-venv/bin/python scripts/mitsuba-plugin-references.py            # everything
    ... --scenes-only                       # write the scenes and textures, render nothing
    ... --only bitmap-png,checkerboard      # some scenes
    ... --spp 16384 --passes 64 --variant llvm_ad_rgb --threads 2
    ... --repack [--only ...]               # rewrite existing references in this format
"""

import argparse
import json
import math
import os
import sys
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENES = os.path.join(ROOT, "tests", "scenes", "mitsuba-plugins")
REFS = os.path.join(ROOT, "tests", "reference", "plugins")
RES = 64
SEED_BASE = 7000

# ---------------------------------------------------------------- textures and meshes


def srgb_png(path):
    """tex16.png: 16 x 16 8-bit sRGB, asymmetric in u and v (a flip or a transpose shows):
    red ramps with x, green with y, blue 4 x 4 blocks, a white L in the top-left corner."""
    from PIL import Image

    a = np.zeros((16, 16, 3), np.uint8)
    for y in range(16):
        for x in range(16):
            a[y, x] = (30 + 14 * x, 40 + 12 * y, 200 if ((x // 4) + (y // 4)) % 2 == 0 else 40)
    a[1:7, 1] = 250  # the L: a vertical bar ...
    a[6, 1:5] = 250  # ... and its foot
    Image.fromarray(a, "RGB").save(path)


def linear_exr(path, mi):
    """tex8.exr: 8 x 8 linear float RGB in [0.05, 0.9], asymmetric."""
    y, x = np.mgrid[0:8, 0:8].astype(np.float32)
    r = 0.05 + 0.85 * x / 7.0
    g = 0.05 + 0.85 * (1.0 - y / 7.0) ** 2
    b = 0.05 + 0.4 * (1.0 + np.sin(1.3 * x + 0.7 * y)) * 0.5
    mi.Bitmap(np.stack([r, g, b], axis=-1).astype(np.float32)).write(path)


def normal_png(path):
    """normals32.png: a raw tangent-space normal map, 32 x 32 8-bit: bumps tilting the normal up
    to ~60 degrees, so that some perturbed normals face away from grazing views (the flip of
    invalid normals) and some light directions fall below the shading horizon."""
    from PIL import Image

    y, x = np.mgrid[0:32, 0:32].astype(np.float64)
    u, v = (x + 0.5) / 32.0, (y + 0.5) / 32.0
    sx = 1.6 * np.sin(2 * math.pi * 2 * u) * np.cos(2 * math.pi * v)
    sy = 1.2 * np.cos(2 * math.pi * 3 * v) + 0.4 * np.sin(2 * math.pi * u)
    n = np.stack([sx, sy, np.ones_like(sx)], axis=-1)
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    rgb = np.clip(np.round((n + 1.0) * 0.5 * 255.0), 0, 255).astype(np.uint8)
    Image.fromarray(rgb, "RGB").save(path)


def box_obj(path):
    """box.obj: a unit cube [-1, 1]^3, each face its own 4 vertices with `vt` (v up in OBJ's
    convention, which Mitsuba flips by default) covering the whole texture, oriented per face."""
    faces = [  # (normal axis, sign): corners counter-clockwise seen from outside
        [(-1, -1, 1), (1, -1, 1), (1, 1, 1), (-1, 1, 1)],  # +z
        [(1, -1, -1), (-1, -1, -1), (-1, 1, -1), (1, 1, -1)],  # -z
        [(1, -1, 1), (1, -1, -1), (1, 1, -1), (1, 1, 1)],  # +x
        [(-1, -1, -1), (-1, -1, 1), (-1, 1, 1), (-1, 1, -1)],  # -x
        [(-1, 1, 1), (1, 1, 1), (1, 1, -1), (-1, 1, -1)],  # +y
        [(-1, -1, -1), (1, -1, -1), (1, -1, 1), (-1, -1, 1)],  # -y
    ]
    uv = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
    lines = ["# a unit cube with per-face texture coordinates (scripts/mitsuba-plugin-references.py)"]
    for f in faces:
        for p in f:
            lines.append("v %g %g %g" % p)
    for _ in faces:
        for t in uv:
            lines.append("vt %g %g" % t)
    for k in range(len(faces)):
        a = 4 * k + 1
        lines.append("f %d/%d %d/%d %d/%d" % (a, a, a + 1, a + 1, a + 2, a + 2))
        lines.append("f %d/%d %d/%d %d/%d" % (a, a, a + 2, a + 2, a + 3, a + 3))
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


def quad_ply(path):
    """quad.ply: ASCII PLY, a 2 x 2 quad in z = 0 facing +z with per-vertex u, v (not flipped by
    Mitsuba), the texture repeated 2 x 1.5 times and sheared, so that any remapping shows."""
    verts = [(-1, -1, 0, 0.0, 0.0), (1, -1, 0, 2.0, 0.25), (1, 1, 0, 2.0, 1.75), (-1, 1, 0, 0.0, 1.5)]
    head = [
        "ply",
        "format ascii 1.0",
        "comment a textured quad (scripts/mitsuba-plugin-references.py)",
        "element vertex 4",
        "property float x",
        "property float y",
        "property float z",
        "property float u",
        "property float v",
        "element face 2",
        "property list uchar int vertex_indices",
        "end_header",
    ]
    body = ["%g %g %g %g %g" % v for v in verts] + ["3 0 1 2", "3 0 2 3"]
    with open(path, "w") as f:
        f.write("\n".join(head + body) + "\n")


# ---------------------------------------------------------------- scenes


def xf(*ops):
    return '<transform name="to_world">' + "".join(ops) + "</transform>"


def rot(axis, angle):
    x, y, z = {"x": (1, 0, 0), "y": (0, 1, 0), "z": (0, 0, 1)}[axis]
    return f'<rotate x="{x}" y="{y}" z="{z}" angle="{angle}"/>'


def tr(x, y, z):
    return f'<translate x="{x}" y="{y}" z="{z}"/>'


def sc(x, y=None, z=None):
    if y is None:
        return f'<scale value="{x}"/>'
    return f'<scale x="{x}" y="{y}" z="{z if z is not None else 1}"/>'


def diffuse(rgb):
    return f'<bsdf type="diffuse"><rgb name="reflectance" value="{rgb}"/></bsdf>'


WHITE, RED, GREEN = "0.725, 0.71, 0.68", "0.63, 0.065, 0.05", "0.14, 0.45, 0.091"

# the room's surfaces: name -> transform of Mitsuba's rectangle ([-1, 1]^2 at z = 0, normal +z).
# Closed: x in [-1, 1], y in [0, 2], z in [-1, 4.5], the camera inside at z = 3.88, so that every
# path stays in the room (a mirror or a glass shows a lit wall, never the void).
WALLS = {
    "floor": xf(sc(1, 2.75), rot("x", -90), tr(0, 0, 1.75)),  # y = 0, normal +y
    "ceiling": xf(sc(1, 2.75), rot("x", 90), tr(0, 2, 1.75)),  # y = 2, normal -y
    "back": xf(tr(0, 1, -1)),  # z = -1, normal +z
    "front": xf(rot("y", 180), tr(0, 1, 4.5)),  # z = 4.5 (behind the camera), normal -z
    "left": xf(sc(2.75, 1), rot("y", 90), tr(-1, 1, 1.75)),  # x = -1, normal +x
    "right": xf(sc(2.75, 1), rot("y", -90), tr(1, 1, 1.75)),  # x = +1, normal -x
}


def room(**bsdfs):
    """The five walls (one-sided diffuse unless `bsdfs` gives a wall's BSDF XML) and the light."""
    default = {"floor": WHITE, "ceiling": WHITE, "back": WHITE, "front": WHITE, "left": RED, "right": GREEN}
    out = []
    for w, t in WALLS.items():
        b = bsdfs.get(w) or diffuse(default[w])
        out.append(f'  <shape type="rectangle">{t}\n    {b}\n  </shape>')
    out.append(
        '  <shape type="rectangle">'
        + xf(sc(0.6, 0.6), rot("x", 90), tr(0, 1.98, 0))
        + '\n    <bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf>'
        + '\n    <emitter type="area"><rgb name="radiance" value="5, 4.6, 3.8"/></emitter>\n  </shape>'
    )
    return "\n".join(out)


def scene(title, body, top=""):
    return f"""<?xml version="1.0" encoding="utf-8"?>
<!-- {title}
     Generated by scripts/mitsuba-plugin-references.py; reference: tests/reference/plugins/.
     The closed room of every scene in this folder, a 1.2 x 1.2 ceiling light, 64 x 64. -->
<scene version="3.0.0">
  <default name="spp" value="64"/>
  <integrator type="path"><integer name="max_depth" value="65"/></integrator>
  <sensor type="perspective">
    <float name="fov" value="36"/>
    <string name="fov_axis" value="y"/>
    <transform name="to_world"><lookat origin="0, 1, 3.88" target="0, 1, 0" up="0, 1, 0"/></transform>
    <sampler type="independent"><integer name="sample_count" value="$spp"/></sampler>
    <film type="hdrfilm">
      <integer name="width" value="{RES}"/><integer name="height" value="{RES}"/>
      <rfilter type="box"/>
    </film>
  </sensor>
{top}{body}
</scene>
"""


def bitmap(name, file, extra=""):
    return f'<texture name="{name}" type="bitmap"><string name="filename" value="{file}"/>{extra}</texture>'


def sphere(bsdf, c=(0, 0.5, 0), r=0.5, spin=0):
    """A sphere whose pole (uv's v = 0) points up (+y), turned by `spin` degrees about y."""
    t = xf(sc(r), rot("x", -90), rot("y", spin), tr(*c))
    return f'  <shape type="sphere">{t}\n    {bsdf}\n  </shape>'


def panel(bsdf, *ops):
    return f'  <shape type="rectangle">{xf(*ops)}\n    {bsdf}\n  </shape>'


NORMALMAP = '<texture name="normalmap" type="bitmap"><string name="filename" value="normals32.png"/><boolean name="raw" value="true"/></texture>'


def scenes():
    s = {}
    tex = lambda extra="": bitmap("reflectance", "tex16.png", extra)  # noqa: E731
    s["bitmap-png"] = scene(
        "diffuse with a `bitmap` reflectance: an 8-bit sRGB PNG, bilinear (back wall), nearest with "
        "mirror wrapping and a 3x to_uv scale (floor), clamp with a shifted to_uv (left wall)",
        room(
            back=f'<bsdf type="diffuse">{tex()}</bsdf>',
            floor='<bsdf type="diffuse">'
            + tex('<string name="filter_type" value="nearest"/><string name="wrap_mode" value="mirror"/>'
                  '<transform name="to_uv"><scale x="3" y="3"/></transform>')
            + "</bsdf>",
            left='<bsdf type="diffuse">'
            + tex('<string name="wrap_mode" value="clamp"/>'
                  '<transform name="to_uv"><translate x="-0.3" y="0.2"/><scale x="1.5" y="1.5"/></transform>')
            + "</bsdf>",
        ),
    )
    s["bitmap-exr"] = scene(
        "diffuse with a `bitmap` reflectance read from a linear float EXR (back wall and floor, repeated 2x)",
        room(
            back=f'<bsdf type="diffuse">{bitmap("reflectance", "tex8.exr")}</bsdf>',
            floor='<bsdf type="diffuse">'
            + bitmap("reflectance", "tex8.exr", '<transform name="to_uv"><scale x="2" y="2"/></transform>')
            + "</bsdf>",
        ),
    )
    s["checkerboard"] = scene(
        "diffuse with `checkerboard` reflectances: given colours and a 4x to_uv scale (floor), "
        "the default colours rotated (back wall)",
        room(
            floor='<bsdf type="diffuse"><texture name="reflectance" type="checkerboard">'
            '<rgb name="color0" value="0.8, 0.75, 0.7"/><rgb name="color1" value="0.1, 0.3, 0.6"/>'
            '<transform name="to_uv"><scale x="4" y="4"/></transform></texture></bsdf>',
            back='<bsdf type="diffuse"><texture name="reflectance" type="checkerboard">'
            '<transform name="to_uv"><rotate z="1" angle="30"/><scale x="5" y="3"/></transform></texture></bsdf>',
        ),
    )
    s["texture-ref"] = scene(
        "a top-level `<texture id>` named by `<ref>` from two BSDFs: the back wall and a diffuse "
        "sphere (Mitsuba's sphere uv)",
        room(back='<bsdf type="diffuse"><ref name="reflectance" id="shared"/></bsdf>')
        + "\n"
        + sphere('<bsdf type="diffuse"><ref name="reflectance" id="shared"/></bsdf>', c=(0, 0.55, 0), r=0.55, spin=30),
        top='  <texture type="bitmap" id="shared"><string name="filename" value="tex16.png"/></texture>\n',
    )
    s["normalmap-diffuse"] = scene(
        "`normalmap` around `diffuse` on rectangles: the back wall, and a panel tilted toward the light",
        room(back=f'<bsdf type="normalmap">{NORMALMAP}{diffuse("0.75, 0.72, 0.7")}</bsdf>')
        + "\n"
        + panel(
            f'<bsdf type="normalmap">{NORMALMAP}<bsdf type="twosided">{diffuse("0.3, 0.6, 0.8")}</bsdf></bsdf>',
            sc(0.45, 0.45), rot("x", -50), rot("y", 25), tr(0.2, 0.7, 0.1),
        ),
    )
    s["normalmap-conductor"] = scene(
        "`normalmap` around a smooth `conductor` (explicit eta, k) on a tilted rectangle, "
        "reflecting the room and the light",
        room()
        + "\n"
        + panel(
            f'<bsdf type="normalmap">{NORMALMAP}<bsdf type="conductor">'
            '<rgb name="eta" value="0.2, 0.92, 1.1"/><rgb name="k" value="3.9, 2.45, 2.2"/></bsdf></bsdf>',
            sc(0.7, 0.7), rot("x", -35), rot("y", -20), tr(0, 0.8, -0.2),
        ),
    )
    s["normalmap-dielectric"] = scene(
        "`normalmap` around a smooth `dielectric` (int_ior 1.5) on a sphere (the map in the "
        "sphere's uv, its tangent frame from dp/du)",
        room() + "\n" + sphere(
            f'<bsdf type="normalmap">{NORMALMAP}<bsdf type="dielectric"><float name="int_ior" value="1.5"/>'
            '<float name="ext_ior" value="1"/></bsdf></bsdf>',
            c=(0, 0.6, 0), r=0.6, spin=20,
        ),
    )
    s["plastic"] = scene(
        "smooth `plastic` (linear): a sphere, and the floor with a textured diffuse_reflectance",
        room(floor='<bsdf type="plastic">'
             + bitmap("diffuse_reflectance", "tex16.png", '<transform name="to_uv"><scale x="2" y="2"/></transform>')
             + '<float name="int_ior" value="1.5"/></bsdf>')
        + "\n" + sphere('<bsdf type="plastic"><rgb name="diffuse_reflectance" value="0.2, 0.4, 0.8"/>'
                        '<float name="int_ior" value="1.6"/></bsdf>', c=(-0.3, 0.5, -0.1), r=0.5),
    )
    s["plastic-nonlinear"] = scene(
        "smooth `plastic` with `nonlinear` true (a sphere, and a panel) and a tinted specular_reflectance",
        room()
        + "\n" + sphere('<bsdf type="plastic"><rgb name="diffuse_reflectance" value="0.8, 0.3, 0.1"/>'
                        '<boolean name="nonlinear" value="true"/></bsdf>', c=(0.3, 0.5, -0.1), r=0.5)
        + "\n" + panel('<bsdf type="plastic"><rgb name="diffuse_reflectance" value="0.1, 0.7, 0.4"/>'
                       '<rgb name="specular_reflectance" value="0.9, 0.6, 0.5"/>'
                       '<boolean name="nonlinear" value="true"/><float name="int_ior" value="1.33"/></bsdf>',
                       sc(0.4, 0.4), rot("y", 35), tr(-0.5, 0.6, 0.1)),
    )
    s["thindielectric"] = scene(
        "`thindielectric` panes in front of the textured back wall: clear (int_ior 1.5), and one "
        "with a tinted specular_transmittance seen partly from its back",
        room(back=f'<bsdf type="diffuse">{tex()}</bsdf>')
        + "\n" + panel('<bsdf type="thindielectric"><float name="int_ior" value="1.5"/></bsdf>',
                       sc(0.45, 0.7), rot("y", 30), tr(-0.4, 0.75, 0.2))
        + "\n" + panel('<bsdf type="thindielectric"><float name="int_ior" value="1.7"/>'
                       '<rgb name="specular_transmittance" value="0.9, 0.5, 0.3"/></bsdf>',
                       sc(0.4, 0.6), rot("y", 200), tr(0.45, 0.7, 0.0)),
    )
    s["onesided"] = scene(
        "one-sided `diffuse` panels: one facing the camera, one showing it its back (black), and a "
        "`twosided` one also turned away (lit on both sides)",
        room()
        + "\n" + panel(diffuse("0.8, 0.8, 0.8"), sc(0.3, 0.5), rot("y", 25), tr(-0.55, 0.6, 0.1))
        + "\n" + panel(diffuse("0.8, 0.8, 0.8"), sc(0.3, 0.5), rot("y", 160), tr(0.0, 0.6, -0.1))
        + "\n" + panel(f'<bsdf type="twosided">{diffuse("0.8, 0.8, 0.8")}</bsdf>',
                       sc(0.3, 0.5), rot("y", 200), tr(0.55, 0.6, 0.1)),
    )
    s["obj-uv"] = scene(
        "an OBJ cube with per-face `vt` (flip_tex_coords default, true) and a bitmap reflectance, "
        "turned to show three faces",
        room()
        + "\n" + f'  <shape type="obj"><string name="filename" value="box.obj"/>'
        '<boolean name="face_normals" value="true"/>'
        + xf(sc(0.4), rot("y", 35), rot("x", 20), tr(0, 0.65, 0))
        + f'\n    <bsdf type="diffuse">{tex()}</bsdf>\n  </shape>',
    )
    s["ply-uv"] = scene(
        "a PLY quad with per-vertex u, v (not flipped) and a bitmap reflectance, tilted",
        room()
        + "\n" + f'  <shape type="ply"><string name="filename" value="quad.ply"/>'
        + xf(sc(0.6), rot("x", -25), rot("y", 15), tr(0, 0.8, 0))
        + f'\n    <bsdf type="twosided"><bsdf type="diffuse">{tex()}</bsdf></bsdf>\n  </shape>',
    )
    # the rough BSDFs (GGX and Beckmann, a couple of alphas each)
    metal = '<rgb name="eta" value="0.2, 0.92, 1.1"/><rgb name="k" value="3.9, 2.45, 2.2"/>'
    for dist, a_sphere, a_panel in [("ggx", 0.15, 0.4), ("beckmann", 0.3, 0.08)]:
        d = f'<string name="distribution" value="{dist}"/>'
        s[f"roughconductor-{dist}"] = scene(
            f"`roughconductor` ({dist}): a sphere at alpha {a_sphere}, a tilted panel at alpha {a_panel}",
            room()
            + "\n" + sphere(f'<bsdf type="roughconductor">{d}<float name="alpha" value="{a_sphere}"/>{metal}</bsdf>',
                            c=(0.35, 0.45, -0.1), r=0.45)
            + "\n" + panel(f'<bsdf type="roughconductor">{d}<float name="alpha" value="{a_panel}"/>'
                           '<rgb name="specular_reflectance" value="0.9, 0.9, 0.8"/></bsdf>',
                           sc(0.35, 0.5), rot("y", 40), tr(-0.5, 0.7, 0.0)),
        )
        s[f"roughdielectric-{dist}"] = scene(
            f"`roughdielectric` ({dist}, int_ior 1.5): a sphere at alpha {a_sphere}, and at alpha "
            f"{a_panel} a pane seen partly from behind",
            room(back=f'<bsdf type="diffuse">{tex()}</bsdf>')
            + "\n" + sphere(f'<bsdf type="roughdielectric">{d}<float name="alpha" value="{a_sphere}"/>'
                            '<float name="int_ior" value="1.5"/><float name="ext_ior" value="1"/></bsdf>',
                            c=(-0.3, 0.45, 0.0), r=0.45)
            + "\n" + panel(f'<bsdf type="roughdielectric">{d}<float name="alpha" value="{a_panel}"/>'
                           '<float name="int_ior" value="1.33"/><float name="ext_ior" value="1"/></bsdf>',
                           sc(0.35, 0.55), rot("y", 200), tr(0.5, 0.7, 0.1)),
        )
        s[f"roughplastic-{dist}"] = scene(
            f"`roughplastic` ({dist}): a sphere at alpha {a_sphere}, the floor at alpha {a_panel} "
            "with a textured diffuse_reflectance",
            room(floor=f'<bsdf type="roughplastic">{d}<float name="alpha" value="{a_panel}"/>'
                 + bitmap("diffuse_reflectance", "tex16.png", '<transform name="to_uv"><scale x="2" y="2"/></transform>')
                 + "</bsdf>")
            + "\n" + sphere(f'<bsdf type="roughplastic">{d}<float name="alpha" value="{a_sphere}"/>'
                            '<rgb name="diffuse_reflectance" value="0.2, 0.4, 0.8"/>'
                            '<float name="int_ior" value="1.6"/></bsdf>', c=(0.2, 0.5, -0.1), r=0.5),
        )
    return s


def write_scenes(mi):
    os.makedirs(SCENES, exist_ok=True)
    srgb_png(os.path.join(SCENES, "tex16.png"))
    linear_exr(os.path.join(SCENES, "tex8.exr"), mi)
    normal_png(os.path.join(SCENES, "normals32.png"))
    box_obj(os.path.join(SCENES, "box.obj"))
    quad_ply(os.path.join(SCENES, "quad.ply"))
    s = scenes()
    for name, text in s.items():
        with open(os.path.join(SCENES, name + ".xml"), "w") as f:
            f.write(text)
    return sorted(s)


# ---------------------------------------------------------------- rendering


def round_mantissa(x, bits):
    """float32 `x` (non-negative) rounded to `bits` explicit mantissa bits: its low bits zero, so
    that the variance channels compress (relative error <= 2^-(bits+1))."""
    drop = 23 - bits
    u = np.ascontiguousarray(x, dtype=np.float32).view(np.uint32)
    u = (u + np.uint32(1 << (drop - 1))) & np.uint32(~((1 << drop) - 1) & 0xFFFFFFFF)
    return u.view(np.float32)


def write_exr(path, channels):
    import OpenEXR  # pip install openexr

    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    with OpenEXR.File(header, {k: np.ascontiguousarray(v) for k, v in channels.items()}) as f:
        f.write(path)


def write_reference(name, mean, var, h0, h1):
    """NAME.exr: R, G, B float32 and var.R/G/B float32 rounded to 8 significant bits (relative
    0.4%: 0.2% of a z statistic); NAME.half{0,1}.exr: R, G, B as half floats (relative 5e-4: their use, (h0 - h1)^2 / 4,
    is the reference's noise, ~0.3% of a pixel). ZIP-compressed: 19 scenes in ~2 MB."""
    os.makedirs(REFS, exist_ok=True)
    mean, var = mean.astype(np.float32), round_mantissa(var.astype(np.float32), 7)
    ch = {c: mean[..., i] for i, c in enumerate("RGB")}
    ch.update({"var." + c: var[..., i] for i, c in enumerate("RGB")})
    write_exr(os.path.join(REFS, name + ".exr"), ch)
    for k, h in enumerate([h0, h1]):
        h = h.astype(np.float32).astype(np.float16)
        write_exr(os.path.join(REFS, f"{name}.half{k}.exr"), {c: h[..., i] for i, c in enumerate("RGB")})


def repack(name):
    """Rewrites a scene's references in write_reference's format from the EXRs on disk."""
    import OpenEXR

    def read(path, names):
        with OpenEXR.File(path, separate_channels=True) as f:
            ch = f.channels()
            return np.stack([ch[n].pixels.astype(np.float32) for n in names], axis=-1)

    full = read(os.path.join(REFS, name + ".exr"), ["R", "G", "B", "var.R", "var.G", "var.B"])
    h0, h1 = (read(os.path.join(REFS, f"{name}.half{k}.exr"), ["R", "G", "B"]) for k in (0, 1))
    write_reference(name, full[..., :3], full[..., 3:], h0, h1)


def render(mi, dr, name, spp, passes):
    scene = mi.load_file(os.path.join(SCENES, name + ".xml"))
    per = spp // passes
    acc = np.zeros((RES, RES, 3))
    acc2 = np.zeros((RES, RES, 3))
    halves = [np.zeros((RES, RES, 3)), np.zeros((RES, RES, 3))]
    t0 = time.time()
    for i in range(passes):
        img = np.array(mi.render(scene, spp=per, seed=SEED_BASE + i), dtype=np.float64)[..., :3]
        acc += img
        acc2 += img * img
        halves[i % 2] += img
    wall = time.time() - t0
    mean = acc / passes
    # the spread of the passes' means: the variance of one pass, / passes for the mean's
    var = np.maximum(acc2 / passes - mean * mean, 0.0) * passes / (passes - 1) / passes
    h0, h1 = halves[0] / ((passes + 1) // 2), halves[1] / (passes // 2)
    write_reference(name, mean, var, h0, h1)
    rmse_halves = float(np.sqrt(np.mean((h0 - h1) ** 2)))
    return {
        "scene": name,
        "spp": per * passes,
        "passes": passes,
        "seeds": [SEED_BASE, SEED_BASE + passes - 1],
        "wall_s": round(wall, 1),
        "mean": [float(x) for x in mean.mean(axis=(0, 1))],
        "noise_rmse": rmse_halves / 2,
        "rel_sd_of_image_mean": float(np.sqrt(var.sum()) / mean.sum()),
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--spp", type=int, default=16384)
    ap.add_argument("--passes", type=int, default=64)
    ap.add_argument("--variant", default="llvm_ad_rgb")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--only", default="")
    ap.add_argument("--scenes-only", action="store_true")
    ap.add_argument("--repack", action="store_true", help="rewrite the existing references' EXRs, render nothing")
    a = ap.parse_args()
    if a.repack:
        for n in a.only.split(",") if a.only else sorted(scenes()):
            repack(n)
        return
    import mitsuba as mi
    import drjit as dr

    mi.set_variant(a.variant)
    if a.variant.startswith("llvm"):
        dr.set_thread_count(a.threads)  # 1 hung 3.9.1's llvm variant (docs/mitsuba.md)
    names = write_scenes(mi)
    if a.scenes_only:
        print("scenes:", ", ".join(names))
        return
    if a.only:
        names = [n for n in a.only.split(",") if n]
    log = os.path.join(REFS, "renders.jsonl")
    for n in names:
        r = render(mi, dr, n, a.spp, a.passes)
        r.update(variant=a.variant, mitsuba=mi.__version__)
        print(json.dumps(r), flush=True)
        os.makedirs(REFS, exist_ok=True)
        with open(log, "a") as f:
            f.write(json.dumps(r) + "\n")


if __name__ == "__main__":
    sys.exit(main())
