import OpenEXR, numpy as np, sys
def load(p):
    ch=OpenEXR.File(p).channels()
    return np.asarray(ch['RGB'].pixels).reshape(-1), np.asarray(ch['var'].pixels).reshape(-1)
seeds=range(int(sys.argv[2]), int(sys.argv[3]))
d=sys.argv[1]
data={smp:[load(f'{d}/{smp}-{s}.exr') for s in seeds] for smp in ['sobol','independent']}
# truth: mean over all renders of both samplers (each unbiased)
truth=np.mean([m for smp in data for m,_ in data[smp]],axis=0)
for smp in data:
    z=np.array([(m-truth)/np.sqrt(np.maximum(v,1e-30)) for m,v in data[smp]])
    err=np.array([m-truth for m,_ in data[smp]])
    est=np.array([v for _,v in data[smp]])
    print(f"{smp:12s} z: sd {z.std():.3f}  frac|z|>3 {np.mean(abs(z)>3):.5f}  frac|z|>4 {np.mean(abs(z)>4):.5f}  max|z| per render: median {np.median(abs(z).max(axis=1)):.2f} worst {abs(z).max():.2f}; mean sq err {np.mean(err**2):.4e} mean est var {np.mean(est):.4e}")
