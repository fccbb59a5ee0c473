import OpenEXR, Imath, numpy as np, glob, json
def load(p):
    f=OpenEXR.InputFile(p); dw=f.header()['dataWindow']; w=dw.max.x-dw.min.x+1; h=dw.max.y-dw.min.y+1
    g=lambda c: np.frombuffer(f.channel(c, Imath.PixelType(Imath.PixelType.FLOAT)),dtype=np.float32).reshape(h,w)
    return np.stack([g(c) for c in 'RGB'],-1)
crops={'whole':(slice(None),slice(None)),'pool_floor':(slice(34,54),slice(36,78))}
spp=32; n=120*68*spp
for m in ['pt-cf','pt']:
    for k in ['16','1']:
        fs=sorted(glob.glob(f'out/{m}-k{k}-s*.exr'))
        if len(fs)<2: continue
        imgs=[load(f) for f in fs]
        js=[json.load(open(f.replace('.exr','.json'))) for f in fs]
        ph=[{p['phase']:p['wall_s'] for p in j['phases']} for j in js]
        us=np.median([p['passes'] for p in ph])/n*1e6
        fixed=np.median([sum(v for kk,v in p.items() if kk!='passes') for p in ph])
        out=[]
        for name,(ys,xs) in crops.items():
            st=np.stack([i[ys,xs] for i in imgs]); m_=st.mean()
            # robust: median over pixels of per-pixel variance too
            pv=st.var(0,ddof=1)
            out.append(f'{name}: mean {m_:.4f} relvar {pv.mean()*spp/m_**2:.2f} (99%: {np.sort(pv.ravel())[:int(pv.size*0.99)].mean()*spp/m_**2:.2f}, median px {np.median(pv)*spp/m_**2:.3f})')
        print(f'{m} --emission-split {k} (n={len(fs)}): passes {us:.2f} us/sample (1 thread wall), fixed phases {fixed:.2f} s;  '+'; '.join(out))
