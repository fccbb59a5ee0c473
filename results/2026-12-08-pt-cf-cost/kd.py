import sys,re,json,collections,os
exec(open(os.path.join(os.path.dirname(__file__), 'classify.py')).read().split("tot = len(samples)")[0].replace("txt, js = sys.argv[1], sys.argv[2]","txt, js = sys.argv[1], sys.argv[2]"))
c=collections.Counter()
for t,fr in samples:
    if fr and any('KdTree::nearest_within' in f for f in fr[:3]):
        p=phase_of(t)
        who='SubsetGrid build (Builder::cell)' if has(fr,'Builder::cell') else ('ClusterMap::query via SubsetGrid::cluster_at (guide_at)' if has(fr,'guide_at') else ('cluster_at, light side camera_pdf_w' if has(fr,'camera_pdf') else ('other: '+next((f for f in fr if 'forecast::' in f and 'KdTree' not in f and 'spatial' not in f),'?')[:80])))
        c[(p,who)]+=1
for k,v in c.most_common(): print(v,k)
