import OpenEXR, Imath, numpy as np, glob, json, sys
def load(p):
    f=OpenEXR.InputFile(p); dw=f.header()['dataWindow']; w=dw.max.x-dw.min.x+1; h=dw.max.y-dw.min.y+1
    g=lambda c: np.frombuffer(f.channel(c, Imath.PixelType(Imath.PixelType.FLOAT)),dtype=np.float32).reshape(h,w)
    return np.stack([g(c) for c in 'RGB'],-1), np.stack([g('var.'+c) for c in 'RGB'],-1)
crops={'whole':(slice(None),slice(None)),'floor':(slice(64,96),slice(None)),'below_ball':(slice(60,80),slice(30,66))}
for a in ['0.2','0.3']:
    for tc in ['0','1']:
        fs=sorted(glob.glob(f'out/a{a}-tc{tc}-s*.exr'))
        imgs=[load(f) for f in fs]; spp=128
        us=[json.load(open(f.replace('.exr','.json')))['method_stats']['profile_per_sample']['total_us'] for f in fs]
        row=[]
        for name,(ys,xs) in crops.items():
            m=np.mean([i[0][ys,xs].mean() for i in imgs])
            # per-sample variance from the seed spread of the crop's pixels (robust to a bad variance layer)
            stack=np.stack([i[0][ys,xs] for i in imgs])
            vs=stack.var(0,ddof=1).mean()*spp
            vl=np.mean([i[1][ys,xs].mean() for i in imgs])*spp
            row.append(f'{name}: mean {m:.4f} relvar(seeds) {vs/m**2:.3f} relvar(layer) {vl/m**2:.3f}')
        print(f'alpha {a} table-cache {tc} (n={len(fs)}) us/sample {np.mean(us):.2f}\n   '+'\n   '.join(row))
