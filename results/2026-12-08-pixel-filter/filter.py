"""Per-sample relative variance of Mitsuba 3 `path` and `ptracer` on sms-sphere with the file's
gaussian rfilter against a box rfilter (results/2026-12-08-pixel-filter.md).

    /work/mitsuba-venv/bin/python results/2026-12-08-pixel-filter/filter.py   (from the repository root)

120x68, 1,024 spp, seeds 1-4, llvm_ad_rgb, max_depth 6 (the file's). Regions: `floor` = the
shadow_caustic crop (0.150,0.230,0.120,0.330) without the pixels where the sphere is seen
(a depth AOV of the sphere alone), `crop` = shadow_caustic, `whole`. relvar = mean over the
region's pixels of the seed-to-seed variance of the luminance x spp, over the region's mean
squared.
"""
import os
import numpy as np
import mitsuba as mi

mi.set_variant('llvm_ad_rgb')
W, H, SPP = 120, 68, 1024
d = 'scenes/external/sms-sphere/'
src = open(d + 'scene.xml').read()


def scene(filt):
    tmp = d + '_filter_tmp.xml'
    open(tmp, 'w').write(src.replace('<rfilter type="gaussian"/>', f'<rfilter type="{filt}"/>'))
    try:
        return mi.load_file(tmp, width=W, height=H, spp=SPP)
    finally:
        os.remove(tmp)


sc = scene('gaussian')
only = mi.load_dict({'type': 'scene', 's': {'type': 'sphere', 'to_world': mi.ScalarTransform4f().scale(6.5)},
                     'sensor': sc.sensors()[0]})
glass = np.array(mi.render(only, integrator=mi.load_dict({'type': 'aov', 'aovs': 'd:depth'}), spp=64))[..., 0] > 0
x0, y0 = int(0.15 * W), int(0.23 * H)
x1, y1 = x0 + int(round(0.12 * W)), y0 + int(round(0.33 * H))
crop = np.zeros((H, W), bool)
crop[y0:y1, x0:x1] = True
regions = [('floor', crop & ~glass), ('crop', crop), ('whole', np.ones((H, W), bool))]
print(f'crop {crop.sum()} px, of which glass {(crop & glass).sum()}')
for filt in ('gaussian', 'box'):
    s = scene(filt)
    for integ in ('path', 'ptracer'):
        it = mi.load_dict({'type': integ, 'max_depth': 6, 'rr_depth': 5})
        a = np.array([np.array(mi.render(s, integrator=it, spp=SPP, seed=k))[..., :3].mean(2) for k in range(1, 5)])
        m, v = a.mean(0), a.var(0, ddof=1) * SPP
        print(f'{filt:8s} {integ:7s} ' + ' | '.join(
            f'{n} mean {m[r].mean():.5f} relvar {v[r].mean() / m[r].mean() ** 2:.3g}' for n, r in regions), flush=True)
