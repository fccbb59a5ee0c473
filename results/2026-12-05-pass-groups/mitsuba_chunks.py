"""Mitsuba 3 `path` on a scene at 256x256, `chunk` samples per pixel per `mi.render` call, for
`budget` seconds (after one warm-up call that carries the JIT): prints the CPU nanoseconds per
sample. Run under `perf record` to split them between Embree and the JIT'd kernel.

    python mitsuba_chunks.py SCENE.xml CHUNK BUDGET_S      (2 threads, max_depth 65, rr_depth 5)
"""
import os
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..', 'scripts'))
import mitsuba_timed as mt  # noqa: E402
import drjit as dr  # noqa: E402
import mitsuba as mi  # noqa: E402

xml, chunk, budget = sys.argv[1], int(sys.argv[2]), float(sys.argv[3])
mi.set_variant('llvm_ad_rgb')
mi.file_resolver().prepend(os.path.dirname(os.path.abspath(xml)))
dr.set_thread_count(2)
tmp = mt.scene_copy(xml, 256, 256, 'path', 65, 5, os.path.dirname(os.path.abspath(xml)))
try:
    scene = mi.load_file(tmp)
finally:
    os.remove(tmp)
img = mi.render(scene, spp=chunk, seed=0)
dr.eval(img)
dr.sync_thread()
t0, c0 = time.perf_counter(), mt.cpu_s()
spp, k = 0, 1
while time.perf_counter() - t0 < budget:
    img = mi.render(scene, spp=chunk, seed=k)
    dr.eval(img)
    dr.sync_thread()
    spp, k = spp + chunk, k + 1
e, c = time.perf_counter() - t0, mt.cpu_s() - c0
print('chunk', chunk, 'spp', spp, 's', round(e, 3), 'cpu', round(c, 3), 'ns/sample cpu', round(c / (spp * 65536) * 1e9, 1))
