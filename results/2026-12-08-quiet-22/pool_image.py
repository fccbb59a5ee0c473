"""docs/images/pool-equal-time-60s.png: forecast `auto` (left), Mitsuba `path` (middle) and Cycles
with path guiding (right), seed 1 of the 60-s equal-time run, every renderer on the box pixel;
the EXRs through the sRGB curve, no tone mapping (values clipped at 1).

    /work/mitsuba-venv/bin/python results/2026-12-08-quiet-22/pool_image.py out/q22/et-pool docs/images/pool-equal-time-60s.png
"""
import sys
import numpy as np
import mitsuba as mi

mi.set_variant('scalar_rgb')
run, out = sys.argv[1], sys.argv[2]
imgs = [np.array(mi.Bitmap(f'{run}/{n}-1.exr'))[..., :3] for n in ('auto', 'mitsuba-path', 'cycles')]
gap = np.ones((imgs[0].shape[0], 4, 3), np.float32)
row = np.concatenate([imgs[0], gap, imgs[1], gap, imgs[2]], 1).astype(np.float32)
mi.Bitmap(np.clip(row, 0, 1)).convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.UInt8, srgb_gamma=True).write(out)
