"""Mitsuba 3 rendered for a wall-clock budget, for the side-by-side scripts (not a CI test).

    python mitsuba_timed.py XML W H BUDGET_S THREADS MAX_DEPTH RR_DEPTH VARIANT INTEGRATOR SEED OUT_EXR

INTEGRATOR is `path` or `ptracer` (max_depth and rr_depth as given; ptracer splats light paths
into the film). The film size and integrator are set in a temporary copy of XML (which also drops
the SMS renderer's `caustic_*` parameters); the XML's folder goes on Mitsuba's file resolver for
its relative mesh paths. OUT_EXR `-` writes no image.

The pixel filter: PIXEL_FILTER=box (the default) sets the film's `rfilter` to `box`, forecast's
pixel, so that every renderer of a comparison estimates the same pixel; PIXEL_FILTER=scene keeps
the file's (the SMS scenes' `gaussian`, σ ½ px, spreads each sample over about π pixels and cuts
a pixel's variance about 3×: its noise is not comparable with a box pixel's; docs/peers.md).

Timing: from just before `load_file` (scene load, BVH and LLVM JIT inside the budget) it renders
chunks of spp, the first two chunks 1 spp (the first carries the JIT), then one chunk size of about
one second (one kernel, compiled once), until the next chunk would pass the budget. The image is
the spp-weighted mean of the chunks; chunk k uses seed SEED * 1000003 + (spp rendered before it),
so no two chunks share random numbers. Prints `spp seconds cpu_seconds` (user + system CPU seconds
of this process from just before `load_file`).
"""
import os
import resource
import sys
import tempfile
import time
import xml.etree.ElementTree as ET


def scene_copy(xml, w, h, integrator, max_depth, rr_depth, folder):
    tree = ET.parse(xml)
    root = tree.getroot()
    for it in root.findall('integrator'):
        root.remove(it)
    integ = ET.Element('integrator', type=integrator)
    ET.SubElement(integ, 'integer', name='max_depth', value=str(max_depth))
    ET.SubElement(integ, 'integer', name='rr_depth', value=str(rr_depth))
    root.insert(0, integ)
    # the `caustic_*` parameters of the SMS paper's renderer (scenes/external/sms-ring), which
    # Mitsuba 3 refuses as unreferenced properties
    for parent in list(root.iter()):
        for e in [e for e in parent if (e.get('name') or '').startswith('caustic_')]:
            parent.remove(e)
    for film in root.iter('film'):
        for k, v in (('width', w), ('height', h)):
            for e in [e for e in film if e.get('name') == k]:
                film.remove(e)
            ET.SubElement(film, 'integer', name=k, value=str(v))
        if pixel_filter() == 'box':
            for e in [e for e in film if e.tag == 'rfilter']:
                film.remove(e)
            ET.SubElement(film, 'rfilter', type='box')
    fd, tmp = tempfile.mkstemp(suffix='.xml', dir=folder)
    os.close(fd)
    tree.write(tmp)
    return tmp


def pixel_filter():
    """`box` (forecast's pixel, the default) or `scene` (the file's rfilter), from PIXEL_FILTER."""
    f = os.environ.get('PIXEL_FILTER', 'box')
    if f not in ('box', 'scene'):
        sys.exit(f'mitsuba_timed.py: PIXEL_FILTER must be box or scene, got {f!r}')
    return f


def cpu_s():
    ru = resource.getrusage(resource.RUSAGE_SELF)
    return ru.ru_utime + ru.ru_stime


def main(argv):
    xml, w, h, budget, threads, max_depth, rr_depth, variant, integrator, seed, out = argv
    w, h, budget, threads, seed = int(w), int(h), float(budget), int(threads), int(seed)
    folder = os.path.dirname(os.path.abspath(out)) if out != '-' else tempfile.gettempdir()
    tmp = scene_copy(xml, w, h, integrator, max_depth, rr_depth, folder)
    import mitsuba as mi
    import drjit as dr
    mi.set_variant(variant)
    resolver = mi.file_resolver() if hasattr(mi, 'file_resolver') else mi.Thread.thread().file_resolver()
    resolver.prepend(os.path.dirname(os.path.abspath(xml)))
    dr.set_thread_count(threads)
    t0, c0 = time.perf_counter(), cpu_s()
    try:
        scene = mi.load_file(tmp)
    finally:
        os.remove(tmp)
    acc = None

    def chunk_s(n, first):
        nonlocal acc
        t = time.perf_counter()
        img = mi.render(scene, spp=n, seed=seed * 1000003 + first)
        part = img * n
        acc = part if acc is None else acc + part
        dr.eval(acc)
        dr.sync_thread()
        return time.perf_counter() - t

    chunk_s(1, 0)  # the first sample per pixel carries the JIT
    per_spp = chunk_s(1, 1)
    spp = 2
    chunk = max(1, int(1.0 / per_spp))  # one kernel size from here on: compiled once
    while budget - (time.perf_counter() - t0) >= chunk * per_spp:
        per_spp = chunk_s(chunk, spp) / chunk
        spp += chunk
    elapsed, cpu = time.perf_counter() - t0, cpu_s() - c0
    if out != '-':
        dr.set_thread_count(max(2, threads))  # Bitmap.write of an EXR hangs with one pool thread
        mi.Bitmap(acc / spp).write(out)
    print(spp, elapsed, cpu)


if __name__ == '__main__':
    main(sys.argv[1:])
