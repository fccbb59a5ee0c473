import subprocess,sys,re,glob,collections
# report.py TAG: per config, total samples and top symbols, base vs new
tag=sys.argv[1]
funcs=sys.argv[2].split(',') if len(sys.argv)>2 else None
def rep(f):
    out=subprocess.run(['perf','report','--stdio','-i',f,'--sort','symbol','--percent-limit','0.5'],capture_output=True,text=True).stdout
    m=re.search(r"Event count \(approx.\): (\d+)",out)
    tot=int(m.group(1))//250000  # cpu-clock ns / 4 kHz: samples
    shares={}
    for line in out.splitlines():
        mm=re.match(r'\s+([\d.]+)%\s+\[\.\]\s+(.*)',line)
        if mm: shares[mm.group(2).split('  ')[0].strip()]=float(mm.group(1))
    return tot,shares
for c in ['poolpt','poolptcf','sphereptcf','pooldef']:
    res=collections.defaultdict(list)
    for b in ['base','new']:
        for f in sorted(glob.glob(f'/tmp/pfperf/{tag}-{c}-{b}-*.data')):
            t=open(f.replace('.data','.time')).read().split()
            tot,sh=rep(f); res[b].append((tot,sh,t))
    if not res['base']: continue
    print(f'== {c}')
    for b in ['base','new']:
        print(b,'samples',[r[0] for r in res[b]],'cpu',[r[2] for r in res[b]])
    names=set()
    for b in res:
        for r in res[b]: names|=set(k for k,v in r[1].items() if v>=1.0)
    rows=[]
    for n in names:
        mb=sum(r[1].get(n,0) for r in res['base'])/len(res['base'])
        mn=sum(r[1].get(n,0) for r in res['new'])/len(res['new'])
        sb=sum(r[1].get(n,0)*r[0]/100 for r in res['base'])/len(res['base'])
        sn=sum(r[1].get(n,0)*r[0]/100 for r in res['new'])/len(res['new'])
        rows.append((sb,n,mb,mn,sn))
    rows.sort(reverse=True)
    print(f"| function | base % | new % | base samples | new samples |")
    for sb,n,mb,mn,sn in rows[:18]:
        print(f"| `{n[:60]}` | {mb:.1f} | {mn:.1f} | {sb:.0f} | {sn:.0f} |")
