#!/usr/bin/env python3
"""Mitsuba 3's `<rotate>`: the world positions of the unit vectors e_x, e_y, e_z (a one-triangle
PLY mesh) under `<rotate x y z angle>` for axes of other lengths than 1, as Mitsuba's XML parser
builds them (Transform4f::rotate: Dr.Jit's Rodrigues matrix of the axis as written, not
normalised). Prints the Rust table of tests/mitsuba.rs
(`rotate_uses_the_axis_as_written_as_mitsuba`): `Rotation`s (axis, angle, [M e_x, M e_y, M e_z]).

    /work/mitsuba-venv/bin/python scripts/mitsuba-rotate.py
"""
import os
import tempfile

import mitsuba as mi
import numpy as np

mi.set_variant("scalar_rgb")

CASES = [((0, 0, 2), 30), ((1, 2, 3), 70), ((0.3, 0, 0), -45), ((0, 1, 0), 90), ((0.6, 0.8, 0), 120)]
PLY = """ply
format ascii 1.0
element vertex 3
property float x
property float y
property float z
element face 1
property list uchar int vertex_indices
end_header
1 0 0
0 1 0
0 0 1
3 0 1 2
"""

with tempfile.TemporaryDirectory() as d:
    path = os.path.join(d, "unit.ply")
    with open(path, "w") as f:
        f.write(PLY)
    print(f"// mitsuba {mi.__version__}, scripts/mitsuba-rotate.py")
    print("const MITSUBA_ROTATE: &[Rotation] = &[")
    for axis, angle in CASES:
        xml = f"""<scene version="3.0.0"><shape type="ply" id="m"><string name="filename" value="{path}"/>
<transform name="to_world"><rotate x="{axis[0]}" y="{axis[1]}" z="{axis[2]}" angle="{angle}"/></transform></shape></scene>"""
        params = mi.traverse(mi.load_string(xml))
        v = list(params["m.vertex_positions"])
        # f32 values in their shortest round-trip form
        f = lambda x: (lambda t: t if any(c in t for c in ".e") else t + ".0")(str(np.float32(x)))
        cols = [[f(v[3 * i + k]) for k in range(3)] for i in range(3)]
        a = ", ".join(f(x) for x in axis)
        print(f"    ([{a}], {f(angle)}, [{', '.join('[' + ', '.join(c) + ']' for c in cols)}]),")
    print("];")
