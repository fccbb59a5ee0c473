import OpenEXR, numpy as np, sys
from math import erf, sqrt
def load(p):
    ch=OpenEXR.File(p).channels()
    print(p, list(ch.keys()))
    rgb=np.asarray(ch['RGB'].pixels,dtype=np.float64) if 'RGB' in ch else np.stack([np.asarray(ch[c].pixels,dtype=np.float64) for c in 'RGB'],-1)
    v=np.asarray(ch['var'].pixels,dtype=np.float64) if 'var' in ch else np.stack([np.asarray(ch['var.'+c].pixels,dtype=np.float64) for c in 'RGB'],-1)
    return rgb,v
a,va=load(sys.argv[1]); b,vb=load(sys.argv[2])
la=a.mean(-1); lb=b.mean(-1)
# luminance-ish: mean of channels; variance of mean of 3 correlated channels approx by mean of vars (upper-ish)
z=(a-b)/np.sqrt(va+vb+1e-30)
h,w,_=a.shape
n=h*w*3
from statistics import NormalDist
thr=NormalDist().inv_cdf(1-(1-(1-0.01)**(1/n))/2)
print('pixels',h*w,'max|z|',np.abs(z).max().round(2),'Sidak threshold (alpha 0.01)',round(thr,2))
gz=(a.sum()-b.sum())/np.sqrt(va.sum()+vb.sum())
print('global z',round(gz,2),'means',a.mean().round(5),b.mean().round(5))
x0,x1,y0,y1=0.62,0.80,0.35,0.75
ra=a[int(y0*h):int(y1*h),int(x0*w):int(x1*w)]; rb=b[int(y0*h):int(y1*h),int(x0*w):int(x1*w)]
rva=va[int(y0*h):int(y1*h),int(x0*w):int(x1*w)]; rvb=vb[int(y0*h):int(y1*h),int(x0*w):int(x1*w)]
print('right region means',ra.mean().round(5),rb.mean().round(5),'z',round((ra.sum()-rb.sum())/np.sqrt(rva.sum()+rvb.sum()),2))
x0,x1,y0,y1=0.30,0.65,0.5,0.8
ra=a[int(y0*h):int(y1*h),int(x0*w):int(x1*w)]; rb=b[int(y0*h):int(y1*h),int(x0*w):int(x1*w)]
rva=va[int(y0*h):int(y1*h),int(x0*w):int(x1*w)]; rvb=vb[int(y0*h):int(y1*h),int(x0*w):int(x1*w)]
print('pool_floor means',ra.mean().round(5),rb.mean().round(5),'z',round((ra.sum()-rb.sum())/np.sqrt(rva.sum()+rvb.sum()),2))
zz=np.abs(z).max(-1)
idx=np.argsort(zz.ravel())[::-1][:8]
for i in idx:
    y,x=divmod(i,w); print((x,y),'z',z[y,x].round(2),'ptcf',a[y,x].round(4),'pt',b[y,x].round(4),'sd',np.sqrt(va[y,x]).round(4),np.sqrt(vb[y,x]).round(4))
print('count |z|>4.7:',(zz>4.7).sum(),' >3:',(zz>3).sum(),'expected >3 of',h*w*3,':',round(h*w*3*0.0027,1))
