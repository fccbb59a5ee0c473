#!/usr/bin/env python3
"""Mitsuba 3's texture coordinates on its analytic and built-in shapes: the tables
`tests/shape_uvs.rs` checks forecast's `rectangle`, `sphere`, `disk`, `cylinder` and `cube` against.

Writes one small scene per case to tests/data/uv/<case>.xml (a shape with a non-trivial
`to_world`, a twosided diffuse BSDF with a checkerboard reflectance, a camera and a point light,
so forecast's loader takes the file as it is) and traces rays at it with Mitsuba (variant
scalar_rgb, `scene.ray_intersect`). Rays come from a fixed seed: origins on a sphere around the
shape's bounding box, aimed at points inside it; a ray is kept when it hits at an incidence of at
most 60 degrees (|cos| >= 0.5) and away from the parametrisation's seams and edges (see KEEP), so
that forecast's tessellation cannot hit another face or miss where Mitsuba hits. Output:
tests/data/uv/<case>.json,

    {"mitsuba": "3.9.1", "variant": "scalar_rgb", "scene": "<case>.xml", "shape": "<plugin>",
     "rows": [{"o": [x, y, z], "d": [x, y, z], "t": t, "p": [..], "n": [..], "uv": [u, v],
               "dp_du": [..], "dp_dv": [..], "reflectance": [r, g, b]}, ...]}

`o` and `d` are the float32 ray Mitsuba traced (d unit to float32 rounding); `t`, `p`, `n`,
`uv`, `dp_du`, `dp_dv` are Mitsuba's `si.t`, `si.p`, `si.n`, `si.uv`, `si.dp_du`, `si.dp_dv`,
and `reflectance` the BSDF's `eval_diffuse_reflectance(si)` (the checkerboard at `si.uv`); every
number is the shortest decimal that reads back as the same float32.

Usage: python scripts/mitsuba-shape-uvs.py
Needs the pip package `mitsuba` (3.9; scripts/bench-vs-mitsuba.sh makes a venv with it) and numpy.
"""
import json
from pathlib import Path

import mitsuba as mi
import numpy as np

mi.set_variant("scalar_rgb")

ROOT = Path(__file__).resolve().parent.parent
DATA = ROOT / "tests" / "data" / "uv"
ROWS = 40

# Rotations are about the coordinate axes: Mitsuba 3.9.1 uses a `rotate` axis as given (a
# non-unit axis gives a matrix that is not a rotation), forecast normalises it.

CHECKER = """<texture name="reflectance" type="checkerboard">
                <rgb name="color0" value="0.8, 0.6, 0.4"/>
                <rgb name="color1" value="0.1, 0.2, 0.3"/>
            </texture>"""

BSDF = f"""<bsdf type="twosided">
        <bsdf type="diffuse">
            {CHECKER}
        </bsdf>
    </bsdf>"""

# the cube's BSDF is also normal-mapped (the map is not compared: it checks that the loader
# takes a normal map on a cube)
NORMAL_MAPPED = f"""<bsdf type="normalmap">
        <texture name="normalmap" type="bitmap">
            <string name="filename" value="../texture/rgb8.png"/>
            <boolean name="raw" value="true"/>
        </texture>
        {BSDF}
    </bsdf>"""

# (case, plugin, the shape's parameters, its BSDF)
CASES = [
    (
        "rectangle",
        "rectangle",
        """<transform name="to_world">
            <scale x="2" y="0.5" z="1"/>
            <rotate x="1" angle="30"/>
            <rotate z="1" angle="-20"/>
            <translate x="0.3" y="-0.2" z="1"/>
        </transform>""",
        BSDF,
    ),
    (
        "sphere",
        "sphere",
        """<point name="center" x="0.1" y="0.2" z="0.3"/>
        <float name="radius" value="0.7"/>
        <transform name="to_world">
            <rotate y="1" angle="40"/>
            <rotate x="1" angle="15"/>
            <scale value="1.5"/>
            <translate x="0.5" y="-0.3" z="0.2"/>
        </transform>""",
        BSDF,
    ),
    (
        "disk",
        "disk",
        """<transform name="to_world">
            <scale x="1.5" y="0.8" z="1"/>
            <rotate x="1" angle="70"/>
            <rotate z="1" angle="25"/>
            <translate x="-0.4" y="0.6" z="0.9"/>
        </transform>""",
        BSDF,
    ),
    (
        # flipped, and a general affine map (shear) given as a matrix
        "disk-flipped",
        "disk",
        """<boolean name="flip_normals" value="true"/>
        <transform name="to_world">
            <matrix value="0.9 0.4 0.1 0.2  -0.3 1.1 0.5 -0.1  0.2 -0.6 0.8 0.7  0 0 0 1"/>
        </transform>""",
        BSDF,
    ),
    (
        "cylinder",
        "cylinder",
        """<point name="p0" x="0.2" y="-0.1" z="0.3"/>
        <point name="p1" x="0.5" y="0.4" z="1.6"/>
        <float name="radius" value="0.6"/>
        <transform name="to_world">
            <rotate z="1" angle="25"/>
            <scale value="1.3"/>
            <translate x="0.1" y="0.2" z="-0.3"/>
        </transform>""",
        BSDF,
    ),
    (
        # a scale along the axis other than across it (Mitsuba allows only that non-uniform
        # scale on a cylinder), flipped normals
        "cylinder-stretched",
        "cylinder",
        """<float name="radius" value="0.5"/>
        <boolean name="flip_normals" value="true"/>
        <transform name="to_world">
            <scale x="0.8" y="0.8" z="2.5"/>
            <rotate x="1" angle="50"/>
            <rotate y="1" angle="-30"/>
            <translate x="-0.2" y="0.1" z="0.4"/>
        </transform>""",
        BSDF,
    ),
    (
        "cube",
        "cube",
        """<transform name="to_world">
            <scale x="1" y="0.5" z="2"/>
            <rotate y="1" angle="35"/>
            <rotate x="1" angle="-15"/>
            <rotate z="1" angle="10"/>
            <translate x="0.2" y="0.1" z="-0.4"/>
        </transform>""",
        NORMAL_MAPPED,
    ),
]


def scene_xml(plugin, params, bsdf):
    return f"""<scene version="3.0.0">
    <!-- written by scripts/mitsuba-shape-uvs.py; tests/shape_uvs.rs loads it -->
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <transform name="to_world">
            <lookat origin="0, -12, 3" target="0, 0, 0" up="0, 0, 1"/>
        </transform>
    </sensor>
    <emitter type="point">
        <point name="position" x="3" y="-4" z="5"/>
        <rgb name="intensity" value="10"/>
    </emitter>
    <shape type="{plugin}">
        {params}
        {bsdf}
    </shape>
</scene>
"""


def away(x, lo, hi):
    return lo <= x <= hi


# which hits are kept, by plugin: uv away from the seams (u = 0 ≡ 1 on the sphere and the
# cylinder, v = 0 ≡ 1 on the disk), the poles, the disk's centre and rim (forecast's polygon is
# inscribed), the cylinder's open ends and the faces' edges; and away from the checkerboard's
# edges at 0.5 (the reflectance is compared too)
KEEP = {
    "rectangle": lambda u, v: away(u, 0.01, 0.99) and away(v, 0.01, 0.99),
    "cube": lambda u, v: away(u, 0.01, 0.99) and away(v, 0.01, 0.99),
    "sphere": lambda u, v: away(u, 0.02, 0.98) and away(v, 0.05, 0.95),
    "disk": lambda u, v: away(u, 0.05, 0.95) and away(v, 0.02, 0.98),
    "cylinder": lambda u, v: away(u, 0.02, 0.98) and away(v, 0.02, 0.98),
}


def f(x):
    """The shortest decimal that reads back as the same float32, as a JSON number."""
    return float(str(np.float32(x)))


def vec(v, n=3):
    return [f(v[i]) for i in range(n)]


def trace(case, plugin, scene, seed):
    rng = np.random.default_rng(seed)
    bbox = scene.bbox()
    lo, hi = np.array(bbox.min, dtype=np.float64), np.array(bbox.max, dtype=np.float64)
    c, ext = 0.5 * (lo + hi), hi - lo
    radius = 2.0 * np.linalg.norm(ext)
    rows, tries = [], 0
    while len(rows) < ROWS:
        tries += 1
        assert tries < 200 * ROWS, f"{case}: too few rays kept ({len(rows)} of {tries})"
        w = rng.normal(size=3)
        o = c + radius * w / np.linalg.norm(w)
        target = lo + rng.random(3) * ext
        d = target - o
        d /= np.linalg.norm(d)
        o32, d32 = o.astype(np.float32), d.astype(np.float32)
        ray = mi.Ray3f(mi.Point3f(*o32), mi.Vector3f(*d32))
        si = scene.ray_intersect(ray)
        if not si.is_valid():
            continue
        u, v = float(si.uv[0]), float(si.uv[1])
        cos = abs(float(np.dot(np.array(si.n), d32)))
        checker_edge = min(abs(u - 0.5), abs(v - 0.5)) < 0.01
        if cos < 0.5 or checker_edge or not KEEP[plugin](u, v):
            continue
        refl = si.bsdf().eval_diffuse_reflectance(si)
        rows.append(
            {
                "o": vec(o32),
                "d": vec(d32),
                "t": f(si.t),
                "p": vec(si.p),
                "n": vec(si.n),
                "uv": vec(si.uv, 2),
                "dp_du": vec(si.dp_du),
                "dp_dv": vec(si.dp_dv),
                "reflectance": vec(refl),
            }
        )
    return rows, tries


def main():
    DATA.mkdir(parents=True, exist_ok=True)
    for k, (case, plugin, params, bsdf) in enumerate(CASES):
        xml = DATA / f"{case}.xml"
        xml.write_text(scene_xml(plugin, params, bsdf))
        scene = mi.load_file(str(xml))
        rows, tries = trace(case, plugin, scene, 61_000 + k)
        out = {
            "mitsuba": mi.__version__,
            "variant": mi.variant(),
            "scene": xml.name,
            "shape": plugin,
            "rows": rows,
        }
        path = DATA / f"{case}.json"
        # one row a line
        head = json.dumps({k: v for k, v in out.items() if k != "rows"})[:-1]
        body = ",\n  ".join(json.dumps(r) for r in rows)
        path.write_text(f'{head}, "rows": [\n  {body}\n]}}\n')
        print(f"{path.relative_to(ROOT)}: {len(rows)} rays kept of {tries}")


if __name__ == "__main__":
    main()
