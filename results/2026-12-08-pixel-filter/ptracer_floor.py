"""Mitsuba 3 `ptracer` against `path` on the shadow_caustic crop of sms-sphere-smooth, with the
file's light made 60x wider at equal power (tests/normal_mapped_casters.rs's wide_light), split
into the crop's floor pixels and the pixels where the sphere is seen (results/2026-12-08-pixel-filter.md).

    /work/mitsuba-venv/bin/python results/2026-12-08-pixel-filter/ptracer_floor.py   (from the repository root)

240x135, 4 x 256 spp, llvm_ad_rgb, max_depth 64, the file's gaussian rfilter (as the earlier check).
"""
import os
import numpy as np
import mitsuba as mi

mi.set_variant('llvm_ad_rgb')
W, H = 240, 135
d = 'scenes/external/sms-sphere-smooth/'
src = open(d + 'scene.xml').read()
wide = src.replace('<scale x="0.2" y="1" z="0.2"/>', '<scale x="12" y="1" z="12"/>').replace(
    'value="50000"', 'value="13.888889"').replace('value="30000"', 'value="8.333333"')
assert wide != src
tmp = d + '_wide_tmp.xml'
open(tmp, 'w').write(wide)
try:
    sc = mi.load_file(tmp, width=W, height=H, spp=64)
finally:
    os.remove(tmp)
only = mi.load_dict({'type': 'scene', 's': {'type': 'sphere', 'to_world': mi.ScalarTransform4f().scale(6.5)},
                     'sensor': sc.sensors()[0]})
glass = np.array(mi.render(only, integrator=mi.load_dict({'type': 'aov', 'aovs': 'd:depth'}), spp=64))[..., 0] > 0
x0, y0 = int(0.15 * W), int(0.23 * H)
x1, y1 = x0 + int(round(0.12 * W)), y0 + int(round(0.33 * H))
g = glass[y0:y1, x0:x1]
print(f'shadow_caustic {g.size} px, sphere seen in {g.mean():.3f} of them')
img = {}
for integ in ('path', 'ptracer'):
    it = mi.load_dict({'type': integ, 'max_depth': 64, 'rr_depth': 5})
    img[integ] = np.mean([np.array(mi.render(sc, integrator=it, spp=256, seed=s))[..., :3] for s in range(4)], 0)[y0:y1, x0:x1].mean(2)
a, b = img['path'], img['ptracer']
print(f'whole crop: path {a.mean():.5f} ptracer {b.mean():.5f} ratio {b.mean() / a.mean():.3f}')
print(f'floor only: path {a[~g].mean():.5f} ptracer {b[~g].mean():.5f} ratio {b[~g].mean() / a[~g].mean():.3f}')
print(f'sphere seen: path {a[g].mean():.5f} ptracer {b[g].mean():.5f}')
