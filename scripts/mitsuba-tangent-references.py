#!/usr/bin/env python3
"""Mitsuba 3 reference images of the tangent-frame scenes of tests/mitsuba_plugins.rs: `bumpmap`
(around diffuse, conductors and anisotropic BSDFs, both nestings with `twosided`), anisotropic
`roughconductor` / `roughdielectric` (oriented by Mitsuba's sh_frame.s, dp/du made orthogonal to
the shading normal) on meshes with and without UVs, rectangles and spheres, and an anisotropic
BSDF under a `normalmap`.

The same room, camera, film, integrator, passes, seeds and EXR layout as
scripts/mitsuba-plugin-references.py (whose functions this script uses: `render`,
`write_reference`, the room and shape helpers), the same log (tests/reference/plugins/
renders.jsonl). It writes its own scenes and textures into tests/scenes/mitsuba-plugins/:

    height32.png    a raw 32 x 32 8-bit grey height field (bumpmap's nested texture)
    quad-nouv.ply   quad.ply without texture coordinates (Mitsuba's dp/du = p1 - p0 per triangle)

Usage (the Mitsuba venv, as the other script):

    /work/mitsuba-venv/bin/python scripts/mitsuba-tangent-references.py            # everything
    ... --scenes-only | --only bumpmap-diffuse,roughconductor-aniso | --spp 16384 --passes 64
"""

import argparse
import importlib.util
import json
import math
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
_spec = importlib.util.spec_from_file_location("plugin_refs", os.path.join(HERE, "mitsuba-plugin-references.py"))
P = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(P)


def height_png(path):
    """height32.png: a raw height field, 32 x 32 8-bit grey in [0.1, 0.9]: ripples along u and
    v and a diagonal term, so that both partial derivatives and their signs matter."""
    from PIL import Image

    y, x = np.mgrid[0:32, 0:32].astype(np.float64)
    u, v = (x + 0.5) / 32.0, (y + 0.5) / 32.0
    h = 0.5 + 0.2 * np.sin(2 * math.pi * 2 * u) + 0.15 * np.cos(2 * math.pi * 3 * v) + 0.05 * np.sin(2 * math.pi * (u + 2 * v))
    Image.fromarray(np.clip(np.round(h * 255.0), 0, 255).astype(np.uint8), "L").save(path)


def quad_nouv_ply(path):
    """quad-nouv.ply: quad.ply's 2 x 2 quad (z = 0, facing +z) without u, v: its two triangles'
    tangents dp/du = p1 - p0 differ (along +x, and along the diagonal)."""
    verts = [(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)]
    head = ["ply", "format ascii 1.0", "comment a quad without texture coordinates (scripts/mitsuba-tangent-references.py)",
            "element vertex 4", "property float x", "property float y", "property float z",
            "element face 2", "property list uchar int vertex_indices", "end_header"]
    body = ["%g %g %g" % v for v in verts] + ["3 0 1 2", "3 0 2 3"]
    with open(path, "w") as f:
        f.write("\n".join(head + body) + "\n")


def height(extra=""):
    return P.bitmap("height", "height32.png", '<boolean name="raw" value="true"/>' + extra)


def bump(inner, scale, tex=None):
    return f'<bsdf type="bumpmap">{tex or height()}<float name="scale" value="{scale}"/>{inner}</bsdf>'


def twosided(inner):
    return f'<bsdf type="twosided">{inner}</bsdf>'


METAL = '<rgb name="eta" value="0.2, 0.92, 1.1"/><rgb name="k" value="3.9, 2.45, 2.2"/>'


def rough(dist, au, av, extra=""):
    return (f'<bsdf type="roughconductor"><string name="distribution" value="{dist}"/>'
            f'<float name="alpha_u" value="{au}"/><float name="alpha_v" value="{av}"/>{METAL}{extra}</bsdf>')


def mesh(kind, file, bsdf, *ops):
    return (f'  <shape type="{kind}"><string name="filename" value="{file}"/>' + P.xf(*ops)
            + f'\n    {bsdf}\n  </shape>')


def scenes():
    s = {}
    sc, rot, tr, panel, sphere = P.sc, P.rot, P.tr, P.panel, P.sphere
    s["bumpmap-diffuse"] = P.scene(
        "`bumpmap` around `diffuse`: the back wall (a raw grey height field, scale 0.5); a panel "
        "with an sRGB colour texture as heights (luminance, mirror wrapping, a rotated to_uv) "
        "around `twosided`; two panels turned away from the camera, twosided(bumpmap(diffuse)) "
        "(left: Mitsuba's twosided mirrors the frame before the bump map sees it) and "
        "bumpmap(twosided(diffuse)) (right)",
        P.room(back=bump(P.diffuse("0.75, 0.72, 0.7"), 0.5))
        + "\n" + panel(
            bump(twosided(P.diffuse("0.3, 0.6, 0.8")), 0.15,
                 P.bitmap("height", "tex16.png", '<string name="wrap_mode" value="mirror"/>'
                          '<transform name="to_uv"><rotate z="1" angle="30"/><scale x="1.5" y="1.5"/></transform>')),
            sc(0.3, 0.3), rot("x", -40), rot("y", 10), tr(0.0, 0.55, 0.3))
        + "\n" + panel(twosided(bump(P.diffuse("0.8, 0.7, 0.3"), 0.3)),
                       sc(0.35, 0.45), rot("y", 155), rot("x", 15), tr(-0.5, 1.2, 0.0))
        + "\n" + panel(bump(twosided(P.diffuse("0.8, 0.7, 0.3")), 0.3),
                       sc(0.35, 0.45), rot("y", 205), rot("x", 15), tr(0.5, 1.2, 0.0)),
    )
    s["bumpmap-conductor"] = P.scene(
        "`bumpmap` around a smooth `conductor` (explicit eta, k) on a tilted panel, and around an "
        "isotropic `roughconductor` (GGX, alpha 0.2) on a sphere (dp/du, dp/dv of Mitsuba's sphere)",
        P.room()
        + "\n" + panel(bump(f'<bsdf type="conductor">{METAL}</bsdf>', 0.2),
                       sc(0.5, 0.5), rot("x", -35), rot("y", -25), tr(-0.35, 0.8, -0.3))
        + "\n" + sphere(bump('<bsdf type="roughconductor"><string name="distribution" value="ggx"/>'
                             f'<float name="alpha" value="0.2"/>{METAL}</bsdf>', 0.25),
                        c=(0.45, 0.4, 0.1), r=0.4, spin=40),
    )
    s["roughconductor-aniso"] = P.scene(
        "anisotropic `roughconductor` oriented by Mitsuba's tangent: a PLY quad with sheared u, v "
        "(GGX, alpha_u 0.04, alpha_v 0.4), the same quad without u, v (dp/du = p1 - p0 per "
        "triangle), a rectangle seen from behind through `twosided`, and a sphere (Beckmann, "
        "alpha_u 0.4, alpha_v 0.05: dp/du along its parallels)",
        P.room()
        + "\n" + mesh("ply", "quad.ply", rough("ggx", 0.04, 0.4),
                      sc(0.35), rot("x", -30), rot("y", 20), tr(-0.55, 0.5, 0.0))
        + "\n" + mesh("ply", "quad-nouv.ply", rough("ggx", 0.04, 0.4),
                      sc(0.35), rot("x", -30), rot("y", -20), tr(-0.1, 1.35, -0.3))
        + "\n" + panel(twosided(rough("ggx", 0.4, 0.04)),
                       sc(0.3, 0.35), rot("y", 200), rot("x", -20), tr(0.6, 1.3, 0.0))
        + "\n" + sphere(rough("beckmann", 0.4, 0.05), c=(0.35, 0.4, -0.1), r=0.4, spin=30),
    )
    s["roughdielectric-aniso"] = P.scene(
        "anisotropic `roughdielectric` (GGX, int_ior 1.5) in front of the textured back wall: a "
        "sphere (alpha_u 0.03, alpha_v 0.3) and a pane turned about its normal, seen partly from "
        "behind (alpha_u 0.4, alpha_v 0.02)",
        P.room(back=f'<bsdf type="diffuse">{P.bitmap("reflectance", "tex16.png")}</bsdf>')
        + "\n" + sphere('<bsdf type="roughdielectric"><string name="distribution" value="ggx"/>'
                        '<float name="alpha_u" value="0.03"/><float name="alpha_v" value="0.3"/>'
                        '<float name="int_ior" value="1.5"/><float name="ext_ior" value="1"/></bsdf>',
                        c=(-0.3, 0.45, 0.0), r=0.45, spin=60)
        + "\n" + panel('<bsdf type="roughdielectric"><string name="distribution" value="ggx"/>'
                       '<float name="alpha_u" value="0.4"/><float name="alpha_v" value="0.02"/>'
                       '<float name="int_ior" value="1.33"/><float name="ext_ior" value="1"/></bsdf>',
                       sc(0.35, 0.55), rot("z", 35), rot("y", 200), tr(0.5, 0.7, 0.1)),
    )
    s["aniso-maps"] = P.scene(
        "an anisotropic `roughconductor` (GGX, alpha_u 0.04, alpha_v 0.4) under a `normalmap` "
        "(a panel: the map's frame keeps dp/du's direction) and under a `bumpmap` (a panel and a "
        "sphere: Mitsuba's bump frame)",
        P.room()
        + "\n" + panel(f'<bsdf type="normalmap">{P.NORMALMAP}{rough("ggx", 0.04, 0.4)}</bsdf>',
                       sc(0.4, 0.4), rot("x", -35), rot("y", 25), tr(-0.5, 0.65, -0.1))
        + "\n" + panel(bump(rough("ggx", 0.04, 0.4), 0.15),
                       sc(0.4, 0.4), rot("x", -35), rot("y", -25), tr(0.05, 1.35, -0.4))
        + "\n" + sphere(bump(rough("ggx", 0.4, 0.04), 0.2), c=(0.45, 0.4, 0.0), r=0.4, spin=20),
    )
    return s


def write_scenes(mi):
    os.makedirs(P.SCENES, exist_ok=True)
    height_png(os.path.join(P.SCENES, "height32.png"))
    quad_nouv_ply(os.path.join(P.SCENES, "quad-nouv.ply"))
    for needed in ["tex16.png", "normals32.png", "quad.ply"]:
        if not os.path.exists(os.path.join(P.SCENES, needed)):
            raise SystemExit(f"{needed} missing: run scripts/mitsuba-plugin-references.py --scenes-only first")
    s = scenes()
    for name, text in s.items():
        with open(os.path.join(P.SCENES, name + ".xml"), "w") as f:
            f.write(text)
    return sorted(s)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--spp", type=int, default=16384)
    ap.add_argument("--passes", type=int, default=64)
    ap.add_argument("--variant", default="llvm_ad_rgb")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--only", default="")
    ap.add_argument("--scenes-only", action="store_true")
    a = ap.parse_args()
    import mitsuba as mi
    import drjit as dr

    mi.set_variant(a.variant)
    if a.variant.startswith("llvm"):
        dr.set_thread_count(a.threads)
    names = write_scenes(mi)
    if a.scenes_only:
        print("scenes:", ", ".join(names))
        return
    if a.only:
        names = [n for n in a.only.split(",") if n]
    log = os.path.join(P.REFS, "renders.jsonl")
    for n in names:
        r = P.render(mi, dr, n, a.spp, a.passes)
        r.update(variant=a.variant, mitsuba=mi.__version__)
        print(json.dumps(r), flush=True)
        with open(log, "a") as f:
            f.write(json.dumps(r) + "\n")


if __name__ == "__main__":
    sys.exit(main())
