import mitsuba as mi, numpy as np, sys
mi.set_variant('llvm_ad_rgb')
xml, integ, spp = sys.argv[1], sys.argv[2], int(sys.argv[3])
sc = mi.load_file(xml, width=120, height=68, spp=spp)
it = mi.load_dict({'type': integ, 'max_depth': int(sys.argv[4]), 'rr_depth': 5})
res = []
for seed in range(4):
    img = np.array(mi.render(sc, integrator=it, spp=spp, seed=seed))
    # shadow_caustic = 0.150,0.230,0.120,0.330 (x, y, w, h fractions)
    x0, y0 = int(0.15*120), int(0.23*68); x1, y1 = x0+int(round(0.12*120)), y0+int(round(0.33*68))
    res.append((img[y0:y1, x0:x1, :3].mean(), img[..., :3].mean()))
r = np.array(res)
print(xml.split('/')[-1], integ, spp, 'shadow %.5f ± %.5f' % (r[:,0].mean(), r[:,0].std(ddof=1)/2), 'whole %.5f ± %.5f' % (r[:,1].mean(), r[:,1].std(ddof=1)/2))
