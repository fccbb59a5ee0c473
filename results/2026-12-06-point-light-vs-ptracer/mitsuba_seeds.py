"""Mitsuba 3 `ptracer` renders of an exported scene: SEEDS seeds of SPP each at W×H, written as
the mean of all seeds (OUT.exr) and of each half of them (OUT.half0.exr, OUT.half1.exr), the
independent halves `forecast diff --half0/--half1` takes.

    python mitsuba_seeds.py XML W H SPP SEEDS OUT
"""
import os
import pathlib
import sys
import tempfile

import mitsuba as mi
import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[2] / 'scripts'))
from mitsuba_timed import scene_copy  # noqa: E402

xml, w, h, spp, seeds, out = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4]), int(sys.argv[5]), sys.argv[6]
mi.set_variant('llvm_ad_rgb')
folder = os.path.dirname(os.path.abspath(xml))
mi.file_resolver().prepend(folder)
with tempfile.TemporaryDirectory() as tmp:
    copy = scene_copy(xml, w, h, 'ptracer', 65, 5, tmp)
    scene = mi.load_file(copy)
imgs = [np.array(mi.render(scene, spp=spp, seed=s), dtype=np.float64) for s in range(seeds)]
half = seeds // 2
for name, group in (('', imgs), ('.half0', imgs[:half]), ('.half1', imgs[half:])):
    mi.Bitmap(np.mean(group, axis=0).astype(np.float32)).write(f'{out}{name}.exr')
print(f'{seeds} seeds x {spp} spp, mean {np.mean(imgs):.6f}')
