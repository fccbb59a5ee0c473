#!/usr/bin/env python3
"""Mitsuba 3 on meshes without texture coordinates: the table `tests/bad_scenes.rs`
(`a_textured_or_normal_mapped_mesh_without_uvs_shades_as_mitsuba`) checks forecast against.

A mesh without UVs (an OBJ without `vt`, a PLY without u/v) takes Mitsuba's barycentric
parametrisation: uv = (b1, b2) of the hit, dp/du = p1 - p0 of its triangle. Writes to
tests/data/no-uv/: `tent.obj` and `tent.ply` (the same four triangles, no UVs), `normal.png`
(an 8 x 8 tangent-space normal map of gentle tilts) and one scene per case (a bitmap-textured
diffuse BSDF, alone or under a `normalmap`, a camera and a point light, so that forecast's loader
takes the file as it is); then traces rays at each scene with Mitsuba (variant scalar_rgb,
`scene.ray_intersect`) and writes `<case>.json`:

    {"mitsuba": "3.9.1", "variant": "scalar_rgb", "scene": "<case>.xml",
     "rows": [{"o": [..], "d": [..], "t": t, "uv": [u, v], "dp_du": [..], "n": [..],
               "reflectance": [r, g, b], "wi": [[..], ..], "eval": [[r, g, b], ..]}, ...]}

`o`, `d`: the float32 ray; `t`, `uv`, `dp_du`, `n`: Mitsuba's `si.t`, `si.uv`, `si.dp_du` and
`si.sh_frame.n` (the untilted shading normal); `reflectance`: the bitmap at `si.uv` (the
texture evaluated directly); `eval[k]`: `bsdf.eval(ctx, si, si.to_local(wi[k]))` for the unit
world directions `wi[k]` (the cosine included, the normal map's tilt and shadowing term too).
Rays come from a fixed seed, aimed at points of each triangle away from its edges (barycentrics
in [0.08, 0.84]), and kept when they hit at an incidence of at most 60 degrees.

Usage: python scripts/mitsuba-no-uv-values.py
Needs the pip packages `mitsuba` (3.9), numpy and Pillow.
"""
import json
from pathlib import Path

import drjit as dr
import mitsuba as mi
import numpy as np
from PIL import Image

mi.set_variant("scalar_rgb")

ROOT = Path(__file__).resolve().parent.parent
DATA = ROOT / "tests" / "data" / "no-uv"
ROWS = 32

# a tent: four triangles of different orientations around an apex, facing +z
P = [(0.0, 0.0, 0.5), (-1.0, -1.0, 0.0), (1.2, -0.9, 0.1), (1.0, 1.1, -0.1), (-0.9, 1.0, 0.0)]
F = [(1, 2, 0), (2, 3, 0), (3, 4, 0), (4, 1, 0)]
WI = [(0.3, 0.2, 1.0), (-0.5, 0.4, 0.8), (0.6, -0.5, 0.45)]


def write_meshes():
    obj = "# four triangles, no vt (scripts/mitsuba-no-uv-values.py)\n"
    obj += "".join(f"v {x} {y} {z}\n" for x, y, z in P)
    obj += "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in F)
    (DATA / "tent.obj").write_text(obj)
    ply = (f"ply\nformat ascii 1.0\ncomment no u, v (scripts/mitsuba-no-uv-values.py)\nelement vertex {len(P)}\n"
           "property float x\nproperty float y\nproperty float z\n"
           f"element face {len(F)}\nproperty list uchar int vertex_indices\nend_header\n")
    ply += "".join(f"{x} {y} {z}\n" for x, y, z in P)
    ply += "".join(f"3 {a} {b} {c}\n" for a, b, c in F)
    (DATA / "tent.ply").write_text(ply)
    # gentle tilts: n = (0.35 sin, 0.35 cos, 1) normalised, stored as (n + 1)/2
    px = []
    for y in range(8):
        for x in range(8):
            n = np.array([0.35 * np.sin(0.9 * x + 0.3 * y), 0.35 * np.cos(0.5 * x - 0.8 * y), 1.0])
            n /= np.linalg.norm(n)
            px.append(tuple(int(round((c + 1) * 0.5 * 255)) for c in n))
    img = Image.new("RGB", (8, 8))
    img.putdata(px)
    img.save(DATA / "normal.png", optimize=True)


DIFFUSE = """<bsdf type="diffuse">
            <texture name="reflectance" type="bitmap">
                <string name="filename" value="../texture/rgb8.png"/>
            </texture>
        </bsdf>"""

NORMAL_MAPPED = f"""<bsdf type="normalmap">
        <texture name="normalmap" type="bitmap">
            <string name="filename" value="normal.png"/>
            <boolean name="raw" value="true"/>
        </texture>
        {DIFFUSE}
    </bsdf>"""

# (case, plugin, file, face_normals, BSDF)
CASES = [
    ("obj-textured", "obj", "tent.obj", True, DIFFUSE),
    ("obj-normalmap", "obj", "tent.obj", True, NORMAL_MAPPED),
    ("ply-normalmap", "ply", "tent.ply", False, NORMAL_MAPPED),
]


def scene_xml(plugin, filename, face_normals, bsdf):
    fn = '\n        <boolean name="face_normals" value="true"/>' if face_normals else ""
    return f"""<scene version="3.0.0">
    <!-- written by scripts/mitsuba-no-uv-values.py; tests/bad_scenes.rs loads it -->
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <transform name="to_world">
            <lookat origin="0, 0, 4" target="0, 0, 0" up="0, 1, 0"/>
        </transform>
    </sensor>
    <emitter type="point">
        <point name="position" x="1" y="1" z="3"/>
        <rgb name="intensity" value="10"/>
    </emitter>
    <shape type="{plugin}">
        <string name="filename" value="{filename}"/>{fn}
        {bsdf}
    </shape>
</scene>
"""


def f(x):
    """The shortest decimal that reads back as the same float32, as a JSON number."""
    return float(str(np.float32(x)))


def vec(v, n=3):
    return [f(v[i]) for i in range(n)]


def trace(case, scene, seed):
    rng = np.random.default_rng(seed)
    tex = mi.load_dict({"type": "bitmap", "filename": str(ROOT / "tests/data/texture/rgb8.png")})
    wis = [np.array(w) / np.linalg.norm(w) for w in WI]
    rows = []
    while len(rows) < ROWS:
        a, b, c = (np.array(P[i]) for i in F[len(rows) % len(F)])
        b1, b2 = rng.uniform(0.08, 0.84, 2)
        if b1 + b2 > 0.92:
            continue
        target = a + b1 * (b - a) + b2 * (c - a)
        o = np.array([0.0, 0.0, 4.0]) + rng.uniform(-0.6, 0.6, 3) * [1, 1, 0]
        d = target - o
        d = d / np.linalg.norm(d)
        o32, d32 = np.float32(o), np.float32(d)
        si = scene.ray_intersect(mi.Ray3f(mi.Point3f(*o32), mi.Vector3f(*d32)))
        if not si.is_valid() or abs(float(dr.dot(si.n, mi.Vector3f(*d32)))) < 0.5:
            continue
        ctx = mi.BSDFContext()
        bsdf = si.bsdf()
        evals = [vec(bsdf.eval(ctx, si, si.to_local(mi.Vector3f(*np.float32(w))))) for w in wis]
        rows.append({
            "o": vec(o32), "d": vec(d32), "t": f(si.t), "uv": vec(si.uv, 2), "dp_du": vec(si.dp_du),
            "n": vec(si.sh_frame.n), "reflectance": vec(tex.eval(si)),
            "wi": [vec(np.float32(w)) for w in wis], "eval": evals,
        })
    return {"mitsuba": mi.__version__, "variant": "scalar_rgb", "scene": f"{case}.xml", "rows": rows}


def main():
    DATA.mkdir(parents=True, exist_ok=True)
    write_meshes()
    for k, (case, plugin, filename, face_normals, bsdf) in enumerate(CASES):
        path = DATA / f"{case}.xml"
        path.write_text(scene_xml(plugin, filename, face_normals, bsdf))
        table = trace(case, mi.load_file(str(path)), 0x6e75 + k)
        (DATA / f"{case}.json").write_text(json.dumps(table, indent=None, separators=(",", ":")) + "\n")
        print(f"{case}: {len(table['rows'])} rows")


if __name__ == "__main__":
    main()
