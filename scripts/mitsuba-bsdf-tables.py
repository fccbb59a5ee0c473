#!/usr/bin/env python3
"""Mitsuba 3's own BSDF values on a fixed grid of directions: the tables `src/bsdf/*.rs` test
against (each BSDF file's `agrees_with_mitsuba` test).

Reads tests/data/bsdf/<plugin>.json, a list of cases {"name": ..., "mitsuba": {plugin dict}},
and writes tests/data/bsdf/<plugin>.csv with one row per (case, wo, wi):

    case,wo_x,wo_y,wo_z,wi_x,wi_y,wi_z,f_r,f_g,f_b,pdf

in the local shading frame (z = shading normal, x = tangent, as Mitsuba's `sh_frame`).
`wo` is forecast's given direction (Mitsuba's `si.wi`), `wi` the evaluated one (Mitsuba's `wo`);
f = Mitsuba's `eval` / |cos θ(wi)| (forecast's `eval` has no cosine), pdf = Mitsuba's `pdf`.
Both transport modes are written for plugins whose value depends on it: a case may set
"mode": "importance" (default "radiance").

Usage: python scripts/mitsuba-bsdf-tables.py PLUGIN [PLUGIN ...]
Needs the pip package `mitsuba` (3.9; scripts/bench-vs-mitsuba.sh makes a venv with it).
"""
import json
import math
import sys
from pathlib import Path

import mitsuba as mi

mi.set_variant("scalar_rgb")

ROOT = Path(__file__).resolve().parent.parent
DATA = ROOT / "tests" / "data" / "bsdf"

# The grid: given directions at these polar angles (degrees; negative: below the surface, for
# dielectrics), evaluated directions on a (θ, φ) grid over the whole sphere.
WO_THETA = [0.0, 20.0, 45.0, 70.0, 85.0, 160.0, 120.0]
WO_PHI = 30.0
WI_THETA = [5.0, 25.0, 40.0, 55.0, 75.0, 88.0, 100.0, 130.0, 150.0, 175.0]
WI_PHI = [0.0, 60.0, 150.0, 210.0, 300.0]


def direction(theta_deg, phi_deg):
    t, p = math.radians(theta_deg), math.radians(phi_deg)
    return [math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t)]


def rows(case):
    bsdf = mi.load_dict(case["mitsuba"])
    ctx = mi.BSDFContext()
    if case.get("mode", "radiance") == "importance":
        ctx.mode = mi.TransportMode.Importance
    out = []
    for wo_t in WO_THETA:
        wo = direction(wo_t, WO_PHI)
        si = mi.SurfaceInteraction3f()
        si.p = mi.Point3f(0, 0, 0)
        si.n = mi.Normal3f(0, 0, 1)
        si.sh_frame = mi.Frame3f(mi.Vector3f(1, 0, 0), mi.Vector3f(0, 1, 0), mi.Vector3f(0, 0, 1))
        si.uv = mi.Point2f(0.5, 0.5)
        si.wi = mi.Vector3f(*wo)
        for wi_t in WI_THETA:
            for wi_p in WI_PHI:
                wi = direction(wi_t, wi_p)
                v = mi.Vector3f(*wi)
                f = bsdf.eval(ctx, si, v)
                pdf = bsdf.pdf(ctx, si, v)
                c = abs(wi[2])
                f = [f[i] / c for i in range(3)]
                out.append([case["name"], *wo, *wi, *f, float(pdf)])
    return out


def main():
    for plugin in sys.argv[1:]:
        cases = json.loads((DATA / f"{plugin}.json").read_text())
        lines = ["case,wo_x,wo_y,wo_z,wi_x,wi_y,wi_z,f_r,f_g,f_b,pdf"]
        for case in cases:
            for r in rows(case):
                lines.append(",".join([r[0]] + [f"{x:.9g}" for x in r[1:]]))
        (DATA / f"{plugin}.csv").write_text("\n".join(lines) + "\n")
        print(f"{plugin}: {len(lines) - 1} rows -> {DATA / (plugin + '.csv')}")


if __name__ == "__main__":
    main()
