import os; os.chdir(os.path.join(os.path.dirname(os.path.abspath(__file__)), 'out'))
import OpenEXR, Imath, numpy as np, json
def load(p):
    f=OpenEXR.InputFile(p); dw=f.header()['dataWindow']; w=dw.max.x-dw.min.x+1; h=dw.max.y-dw.min.y+1
    g=lambda c: np.frombuffer(f.channel(c, Imath.PixelType(Imath.PixelType.FLOAT)),dtype=np.float32).reshape(h,w)
    return np.stack([g(c) for c in 'RGB'],-1)
W,H=120,68
fx=(0.150,0.230,0.120,0.330)
x0,y0=int(round(fx[0]*W)),int(round(fx[1]*H)); x1,y1=int(round((fx[0]+fx[2])*W)),int(round((fx[1]+fx[3])*H))
crops={'whole':(slice(None),slice(None)),'shadow_caustic':(slice(y0,y1),slice(x0,x1))}
spp=64
def cpu(f): u,s=open(f).read().split()[-2:]; return float(u)+float(s)
res={}
for k in ['16','4','1']:
    imgs=[load(f'k{k}-s{s}.exr') for s in range(1,7)]
    us=(cpu(f'cost-k{k}-n264.time')-cpu(f'cost-k{k}-n8.time'))/(256*W*H)*1e6
    out=[]
    for name,(ys,xs) in crops.items():
        st=np.stack([i[ys,xs] for i in imgs]).mean(-1); m_=st.mean()
        pv=st.var(0,ddof=1)
        rv=pv.mean()*spp/m_**2; rv99=np.sort(pv.ravel())[:int(pv.size*0.99)].mean()*spp/m_**2; med=np.median(pv)*spp/m_**2
        res[(k,name)]=(rv,rv99,med,us)
        out.append(f'{name}: mean {m_:.4f} relvar {rv:.3f} (99%: {rv99:.3f}, median px {med:.4f})')
    print(f'--split {k}: {us:.2f} us/sample CPU (1 thread, 264-8 spp difference);  '+'; '.join(out))
print('relvar x us relative to --split 16 (mean / 99% / median px):')
for k in ['4','1']:
    for name in crops:
        a=res[(k,name)]; b=res[('16',name)]
        print(f'  --split {k} {name}: ' + ' / '.join(f'{a[i]*a[3]/(b[i]*b[3]):.3f}' for i in range(3)))
print('crop px', x0,x1,y0,y1)
