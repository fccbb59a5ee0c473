import OpenEXR, numpy as np, sys, glob
def load(p):
    ch=OpenEXR.File(p).channels()
    rgb=np.asarray(ch['RGB'].pixels); var=np.asarray(ch['var'].pixels)
    return rgb, var
d=sys.argv[1]; n=int(sys.argv[2]); spp=int(sys.argv[3])
x,y,w,h=map(int,sys.argv[4].split(','))
ims=[load(f'{d}/s{s}.exr') for s in range(1,n+1)]
m=np.array([a[y:y+h,x:x+w].mean(axis=2) for a,_ in ims])   # seeds x h x w (lum-ish mean)
v=np.array([b[y:y+h,x:x+w].reshape(h,w,-1).mean(axis=2) for _,b in ims])
mu=m.mean(axis=0)
err=((m-mu)**2).mean(axis=(1,2))*n/(n-1)
print("per-seed wall MSE x spp:", np.round(err*spp,6))
print("crop-mean per seed:", np.round(m.mean(axis=(1,2)),5))
print("var layer mean per seed x spp:", np.round(v.mean(axis=(1,2))*spp,6))
pv=v*spp
print("per-pixel var-per-pass quantiles (all seeds):", np.quantile(pv,[0.5,0.9,0.99,0.999,1.0]))
# which pixels dominate between-seed error
e2=((m-mu)**2).sum(axis=0)
fl=np.sort(e2.ravel())[::-1]
print("share of between-seed SSE in top 1%, 5% pixels:", fl[:len(fl)//100].sum()/fl.sum(), fl[:len(fl)//20].sum()/fl.sum())
