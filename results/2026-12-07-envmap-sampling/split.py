import sys,subprocess,re,collections
f=sys.argv[1]
out=subprocess.run(['perf','report','-i',f,'--no-children','--sort','dso,symbol','--stdio','-g','none'],capture_output=True,text=True).stdout
cats=collections.OrderedDict((k,0.0) for k in ['traversal+triangle tests','hit records','integrator (pt lanes, NEE, MIS)','BSDF sampling/eval','textures','envmap','emission split + probe (Dirac chains)','camera/sampler','loading (decode, hash, mesh, BVH build, page faults)','other'])
def cat(dso,sym):
    if 'embree' in dso or re.search(r'ObvhsBvh|World::occluded|closest16|occluded16|occluded_batch|sphere_t',sym): return 'traversal+triangle tests'
    if re.search(r'World::intersect|hit_at',sym): return 'hit records'
    if re.search(r'from_decoded|content_hash|zune|png::|fdeflate|exr::|miniz|tobj|obj::|load_|mitsuba::|ploc|Ploc|obvhs::|kallsyms|clear_page|decode|LatLong::new|Distribution1D::new|Distribution2D::new|_dl_|memmove|memset|CharSearcher|parse',sym) or dso.startswith('[kernel'): return 'loading (decode, hash, mesh, BVH build, page faults)'
    if re.search(r'texel|Bitmap::|bilinear|normal_mapped|uv_at|material_at|shade_varying|Surface::shading_point',sym): return 'textures'
    if re.search(r'Environment|LatLong::|Distribution1D|Distribution2D|direct::escaped|atan|acos|cosf|sincos|sinf',sym): return 'envmap'
    if re.search(r'dirac|follow_chain|prefix_emission|probe|split_sample',sym): return 'emission split + probe (Dirac chains)'
    if re.search(r'bsdf|microfacet|roughplastic|gauss_legendre|coat',sym): return 'BSDF sampling/eval'
    if re.search(r'camera_lanes|pixel::|Rng|sobol',sym): return 'camera/sampler'
    if re.search(r'integrators|Lanes|wavefront|estimate|Scene::shade|PathTracer',sym): return 'integrator (pt lanes, NEE, MIS)'
    return 'other'
oth=collections.Counter()
for line in out.splitlines():
    m=re.match(r'\s+([\d.]+)%\s+(\S+)\s+\[.\]\s+(.*?)\s+-\s+-',line) or re.match(r'\s+([\d.]+)%\s+(\S+)\s+\[.\]\s+(.*)',line)
    if not m: continue
    p=float(m.group(1)); c=cat(m.group(2),m.group(3)); cats[c]+=p
    if c=='other': oth[m.group(3).strip()[:60]]+=p
for k,v in cats.items(): print(f'{k:55s} {v:5.1f}%')
print('  other top:',oth.most_common(5))
