import sys, json, re, collections
txt, js = sys.argv[1], sys.argv[2]
d = json.load(open(js))
phases = [(p['phase'], p['wall_s']) for p in d['phases']]
samples = []
cur = None
for line in open(txt):
    if not line.strip():
        continue
    if not line.startswith('\t') and not line.startswith(' '):
        m = re.match(r'\s*(\d+)\s+([\d.]+):', line)
        cur = [float(m.group(2)), []]; samples.append(cur)
    else:
        parts = line.strip().split(' ', 1)
        cur[1].append(parts[1] if len(parts) > 1 else '')
t0 = samples[0][0]
bounds = []; acc = 0
for n, w in phases:
    bounds.append((acc, acc + w, n)); acc += w
def phase_of(t):
    for a, b, n in bounds:
        if a <= t - t0 < b: return n
    return 'after'
def has(fr, s): return any(s in f for f in fr)
# operation: first matching leaf-most frame
OPS = [
 ('kd nearest_within', 'KdTree::nearest_within'),
 ('kd k_nearest', 'KdTree::k_nearest'),
 ('cluster_at (grid)', 'SubsetGrid::cluster_at'),
 ('cluster_map query', 'ClusterMap::query'),
 ('table build', 'ForecastTables::build'),
 ('table gather', 'ForecastMaps::gather'),
 ('table cache get/normal_bin', 'table_cache::'),
 ('mixture', 'DefensiveMixture'),
 ('table sample/pdf', 'direction_table::'),
 ('closest', 'World::closest'),
 ('occluded', 'World::occluded'),
 ('intersect other', 'accel::'),
 ('texture/shade', 'Scene::shade'),
 ('texture/shade', 'texture::'),
 ('bsdf', 'bsdf::'),
 ('light sample/emission', 'scene::light'),
 ('light sample/emission', 'transport::direct'),
 ('light first/next ratio', 'pt_cf::light::first_ratio'),
 ('light first/next ratio', 'pt_cf::light::next_ratio'),
 ('camera_weight', 'camera_weight'),
 ('rng', 'sampling::rng'),
 ('malloc/free', 'malloc'), ('malloc/free', 'free'), ('malloc/free', 'realloc'), ('malloc/free','memcpy'),
]
def op_of(fr):
    if has(fr,'build_tables') or has(fr,'ForecastTables::build'): return 'TABLE BUILD (gather+build)'
    if has(fr,'table_cache::') or has(fr,'TableCache'): return 'table cache get/normal_bin/cell'
    if has(fr,'sample_light_mis') or has(fr,'light_sample_mis') or has(fr,'direct::'): return 'NEE (light sample+mis pdf)'
    if has(fr,'World::closest') or has(fr, 'World::intersect') : return 'closest'
    if has(fr,'World::occluded') or has(fr,'occluded'): return 'occluded'
    if has(fr,'Scene::shade') or has(fr,'texture::'): return 'texture/shade'
    for f in fr:
        for name, key in OPS:
            if key in f: return name
    return 'other:' + (fr[0][:60] if fr else '?')
def ctx_of(fr):
    if has(fr, 'light_splats') or has(fr, 'pt_cf::light::Tracer'): return 'light side'
    if has(fr, 'GuidedPathTracer::split'): return 'camera: split continuations'
    if has(fr, 'GuidedPathTracer::guided') or has(fr, '::guided (inlined)') or has(fr,'GuidedPathTracer::guide_in'): return 'camera: guided vertex'
    if has(fr, 'guide_at') or has(fr, 'guide_of'): return 'camera: lookup (guide_at)'
    if has(fr, 'estimate_batch') or has(fr, 'trace_batch') or has(fr, 'GuidedPathTracer::trace'): return 'camera: pt vertices'
    if has(fr, 'trace_passes'): return 'passes other'
    return 'other'
tot = len(samples)
byphase = collections.Counter(); byctx = collections.Counter(); byop = collections.defaultdict(collections.Counter)
for t, fr in samples:
    p = phase_of(t); byphase[p] += 1
    if p == 'passes':
        c = ctx_of(fr); byctx[c] += 1; byop[c][op_of(fr)] += 1
print('samples', tot)
for p, n in byphase.most_common(): print(f'{p:20s} {n:6d} {100*n/tot:5.1f}%')
P = byphase['passes']
print('--- passes by context (share of passes)')
for c, n in byctx.most_common():
    print(f'{c:32s} {n:6d} {100*n/P:5.1f}%')
    for o, k in byop[c].most_common(12): print(f'      {o:40s} {k:5d} {100*k/P:5.1f}%')
