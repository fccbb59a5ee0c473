"""Mitsuba 3 with another sampler at a fixed spp, in one render call (a fairness check of
results/2026-12-06-sobol-prefix.md: Mitsuba's own low-discrepancy samplers against its default
`independent` one). Not a CI test.

    python mitsuba_sampler.py XML W H SPP THREADS MAX_DEPTH RR_DEPTH VARIANT INTEGRATOR SAMPLER SEED OUT_EXR

Prints `spp seconds`. The scene copy is scripts/mitsuba_timed.py's, with the sampler replaced.
"""
import os
import sys
import time
import xml.etree.ElementTree as ET

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..', 'scripts'))
from mitsuba_timed import scene_copy  # noqa: E402


def main(argv):
    xml, w, h, spp, threads, max_depth, rr_depth, variant, integrator, sampler, seed, out = argv
    folder = os.path.dirname(os.path.abspath(out))
    tmp = scene_copy(xml, int(w), int(h), integrator, max_depth, rr_depth, folder)
    tree = ET.parse(tmp)
    for sensor in tree.getroot().iter('sensor'):
        for s in sensor.findall('sampler'):
            sensor.remove(s)
        smp = ET.SubElement(sensor, 'sampler', type=sampler)
        ET.SubElement(smp, 'integer', name='sample_count', value=spp)
    tree.write(tmp)
    import mitsuba as mi
    import drjit as dr
    mi.set_variant(variant)
    resolver = mi.file_resolver() if hasattr(mi, 'file_resolver') else mi.Thread.thread().file_resolver()
    resolver.prepend(os.path.dirname(os.path.abspath(xml)))
    dr.set_thread_count(int(threads))
    t0 = time.perf_counter()
    try:
        scene = mi.load_file(tmp)
    finally:
        os.remove(tmp)
    img = mi.render(scene, spp=int(spp), seed=int(seed))
    dr.eval(img)
    dr.sync_thread()
    elapsed = time.perf_counter() - t0
    dr.set_thread_count(max(2, int(threads)))
    mi.Bitmap(img).write(out)
    print(spp, elapsed)


if __name__ == '__main__':
    main(sys.argv[1:])
