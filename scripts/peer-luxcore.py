#!/usr/bin/env python3
"""LuxCore (pip `pyluxcore`) renders a Mitsuba 3 scene of the SMS set for a wall-clock budget: a
peer of the equal-time comparison (issue 62; docs/peers.md). Not a test.

    peer-luxcore.py SCENE.xml W H BUDGET_S SEED THREADS ENGINE OUT.exr [--spp N] [--max-depth D]

ENGINE: `path` = PATHCPU with hybrid back/forward light tracing (LuxCore's caustic answer: light
paths splatted onto the film), `path-nohybrid` = PATHCPU alone, `bidir` = BIDIRCPU. Sampler SOBOL
with its adaptive part off (`sampler.sobol.adaptive.strength` 0), no clamping, no denoiser, the
film's pixel filter forecast's box pixel (BOX, width ½ px: the pixel's square; PIXEL_FILTER=scene
gives Mitsuba's gaussian instead, GAUSSIAN α 2, radius 2 px), SEED as `renderengine.seed`.
Prints `spp seconds cpu_seconds` (as scripts/mitsuba_timed.py): the clock starts before the scene
is read (textures decoded, meshes defined, BVH built inside the budget); the session is stopped
when the budget is spent (or after N samples per pixel with --spp: mean checks).
OUT.exr: linear RGB, the frame of Mitsuba's image (top row first).

What maps (scripts/peer_scene.py reads the file):
- camera: lookat from Mitsuba's sensor frame; the screen window set explicitly from Mitsuba's
  fov and fov_axis and moved down by one pixel: LuxCore's raster y is `H − y − 1`
  (projective.cpp), which puts the image one row low otherwise (measured: the best match to
  Mitsuba's image is the unshifted one only with this); row order flipped to top-first;
- diffuse → matte; textures → image maps defined from memory (Mitsuba's decoding, texel centres,
  repeat, bilinear) with the mesh's Mitsuba uv and `to_uv` as uvmapping2d scale/delta;
- dielectric → glass (kr = kt = 1, interior ior = Mitsuba's int/ext ratio, exterior 1);
- conductor → metal2 with Mitsuba's RGB eta/k: LuxCore's metal is always glossy, so a smooth
  conductor is metal2 with α = SMOOTH_ALPHA (1e-3), not a Dirac lobe;
- roughconductor → metal2, uroughness = vroughness = α (LuxCore's roughness u·v is α²: its
  Schlick distribution D(r) is GGX with r = α²) — but LuxCore's masking is Schlick's G, not
  Smith's GGX G1·G1 (an approximation: a few % on grazing lobes);
- roughplastic → glossy2 (NOT the same BSDF: glossy2 is LuxCore's coated diffuse with a Schlick
  Fresnel, ks = F0 of Mitsuba's η, kd the diffuse reflectance; Mitsuba's roughplastic has the
  exact dielectric Fresnel and internal scattering). Only the pool's dark ladder steps use it;
- normalmap → a normalmap texture as the material's `bumptex` (2c − 1 in the frame (dp/du,
  cross(n, dp/du), n), as Mitsuba's). Not `normaltex`: pyluxcore 2.11.2 accepts that property but
  renders a glossy or specular reflection under it black (even a flat map);
- area emitter → the material's emission (gain 1, power 0: radiance as given; one-sided);
- envmap → infinite light from memory, gain = scale; its transformation maps LuxCore's lat-long
  (z up, φ = atan2(y, x)) onto Mitsuba's (y up, u = atan2(x, −z)/2π): local = (−v.z, v.x, v.y);
  LuxCore's rows are texel-centred (t·H − ½), Mitsuba's align the first and last rows with the
  poles (v·(H−1)): at most half a texel apart in θ;
- max_depth d (segments) → path.pathdepth.* = d − 1 (LuxCore counts vertices after the camera:
  depth 1 is direct light only); BIDIRCPU: path.maxdepth = light.maxdepth = d − 1, but BIDIRCPU
  has no cap on the total (eye + light) length, so it adds paths longer than Mitsuba renders.
- spheres are tessellated (peer_scene.SPHERE_RES rings, smooth vertex normals).
Meshes go to LuxCore as Python lists (Scene.DefineMesh; it takes no numpy arrays): about 1 s for
the 131k-vertex sphere on an idle core, inside the budget. (A binary PLY through
scene.shapes.*.ply was faster but its render differed from Mitsuba's in the lit floor's colour by
up to 10%, unexplained: not used.)
"""
import os
import resource
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import numpy as np  # noqa: E402
import peer_scene  # noqa: E402

SMOOTH_ALPHA = 1e-3


def cpu_s():
    ru = resource.getrusage(resource.RUSAGE_SELF)
    return ru.ru_utime + ru.ru_stime


def fmt(v):
    return " ".join(repr(float(x)) for x in v)


class Builder:
    def __init__(self, lux, scene, props):
        self.lux, self.scene, self.props = lux, scene, props
        self.images = {}
        self.ntex = 0

    def set(self, k, v):
        if isinstance(v, (list, tuple, np.ndarray)):
            v = fmt(v)
        self.props.SetFromString(f"{k} = {v}\n")

    def image(self, path, raw):
        key = (path, raw)
        if key not in self.images:
            img = peer_scene.load_image(path, raw)
            name = f"img{len(self.images)}"
            h, w = img.shape[:2]
            # row 0 of the buffer is v = 0: Mitsuba's top row (peer_scene gives the file's order)
            self.scene.DefineImageMap(name, np.ascontiguousarray(img.reshape(-1).astype(np.float32)), 1.0, 3, w, h)
            self.images[key] = name
        return self.images[key]

    def texture(self, t):
        """A LuxCore texture name or an inline constant."""
        if "rgb" in t:
            return fmt(t["rgb"])
        name = f"tex{self.ntex}"
        self.ntex += 1
        p = f"scene.textures.{name}"
        self.set(p + ".type", "imagemap")
        self.set(p + ".file", self.image(t["bitmap"], t["raw"]))
        self.set(p + ".gamma", 1.0)
        self.set(p + ".mapping.type", "uvmapping2d")
        su, sv, tu, tv = t["to_uv"]
        self.set(p + ".mapping.uvscale", (su, sv))
        self.set(p + ".mapping.uvdelta", (tu, tv))
        return name

    def material(self, name, b, radiance):
        p = f"scene.materials.{name}"
        if b["type"] == "normalmap":
            nm, tex = f"nmap_{name}", self.texture(b["normalmap"])  # defined first: LuxCore parses in order
            self.set(f"scene.textures.{nm}.type", "normalmap")
            self.set(f"scene.textures.{nm}.texture", tex)
            self.set(f"scene.textures.{nm}.scale", 1.0)
            self.material(name, b["nested"], radiance)
            self.set(p + ".bumptex", nm)  # LuxCore applies a normalmap texture as the bump texture
            return
        t = b["type"]
        if t == "diffuse":
            self.set(p + ".type", "matte")
            self.set(p + ".kd", self.texture(b["reflectance"]))
        elif t == "dielectric":
            self.set(p + ".type", "glass")
            self.set(p + ".kr", (1, 1, 1))
            self.set(p + ".kt", (1, 1, 1))
            self.set(p + ".interiorior", b["eta"])
            self.set(p + ".exteriorior", 1.0)
        elif t in ("conductor", "roughconductor"):
            a = b["alpha"] if t == "roughconductor" else SMOOTH_ALPHA
            self.set(p + ".type", "metal2")
            if max(b["eta"]) == 0.0:  # Mitsuba's material "none": reflectance 1 at every angle
                self.set(f"scene.textures.fres_{name}.type", "fresnelcolor")
                self.set(f"scene.textures.fres_{name}.kr", (1, 1, 1))
                self.set(p + ".fresnel", f"fres_{name}")
            else:
                self.set(p + ".n", b["eta"])
                self.set(p + ".k", b["k"])
            self.set(p + ".uroughness", a)
            self.set(p + ".vroughness", a)
        elif t == "roughplastic":
            f0 = ((b["eta"] - 1) / (b["eta"] + 1)) ** 2
            self.set(p + ".type", "glossy2")
            self.set(p + ".kd", self.texture(b["diffuse_reflectance"]))
            self.set(p + ".ks", (f0, f0, f0))
            self.set(p + ".uroughness", b["alpha"])
            self.set(p + ".vroughness", b["alpha"])
            self.set(p + ".multibounce", 0)
        else:
            raise peer_scene.SceneError(f"no LuxCore material for {t}")
        if radiance is not None:
            self.set(p + ".emission", radiance)
            self.set(p + ".emission.gain", (1, 1, 1))
            self.set(p + ".emission.power", 0.0)
            self.set(p + ".emission.efficency", 0.0)
            self.set(p + ".emission.normalizebycolor", 0)


def pixel_filter():
    """The film's filter lines: forecast's box pixel (PIXEL_FILTER=box, the default) or Mitsuba's
    gaussian (PIXEL_FILTER=scene; the SMS scenes' rfilter)."""
    f = os.environ.get("PIXEL_FILTER", "box")
    if f == "box":
        return ["film.filter.type = BOX", "film.filter.width = 0.5"]
    if f == "scene":
        return ["film.filter.type = GAUSSIAN", "film.filter.width = 2.0", "film.filter.gaussian.alpha = 2.0"]
    sys.exit(f"peer-luxcore.py: PIXEL_FILTER must be box or scene, got {f!r}")


def build(lux, s, w, h, seed, threads, engine, spp):
    scene = lux.Scene()
    props = lux.Properties()
    b = Builder(lux, scene, props)
    c = s.cam_to_world
    org, left, up, fwd = c[:3, 3], c[:3, 0], c[:3, 1], c[:3, 2]
    b.set("scene.camera.type", "perspective")
    b.set("scene.camera.lookat.orig", org)
    b.set("scene.camera.lookat.target", org + fwd)
    b.set("scene.camera.up", up)
    b.set("scene.camera.fieldofview", np.degrees(2 * np.arctan(s.tan_y)))
    ax, dy = s.tan_x / s.tan_y, 2.0 / h
    b.set("scene.camera.screenwindow", (-ax, ax, -1 - dy, 1 - dy))
    b.set("scene.camera.cliphither", 1e-4)
    b.set("scene.camera.clipyon", 1e30)
    for k, sh in enumerate(s.shapes):
        mat = f"mat{k}"
        b.material(mat, sh.bsdf, sh.radiance)
        scene.DefineMesh(f"mesh{k}", [tuple(v) for v in sh.p.astype(float)], [tuple(int(i) for i in t) for t in sh.tri],
                         [tuple(v) for v in sh.n.astype(float)], [tuple(v) for v in sh.uv.astype(float)], None, None)
        b.set(f"scene.objects.obj{k}.shape", f"mesh{k}")
        b.set(f"scene.objects.obj{k}.material", mat)
    if s.envmap:
        env = peer_scene.load_image(s.envmap["filename"], True)
        eh, ew = env.shape[:2]
        scene.DefineImageMap("envmap", np.ascontiguousarray(env.reshape(-1)), 1.0, 3, ew, eh)
        # local_lux = R · v with v = to_world⁻¹ · d: (−v.z, v.x, v.y); lightToWorld = to_world · R⁻¹
        r = np.array([[0, 0, -1], [1, 0, 0], [0, 1, 0]], float)
        l2w = np.eye(4)
        l2w[:3, :3] = s.envmap["to_world"][:3, :3] @ np.linalg.inv(r)
        b.set("scene.lights.env.type", "infinite")
        b.set("scene.lights.env.file", "envmap")
        b.set("scene.lights.env.gamma", 1.0)
        b.set("scene.lights.env.gain", (s.envmap["scale"],) * 3)
        b.set("scene.lights.env.transformation", l2w.T.reshape(-1))  # column-major
    scene.Parse(props)

    cfg = lux.Properties()
    eng = {"path": "PATHCPU", "path-nohybrid": "PATHCPU", "bidir": "BIDIRCPU"}[engine]
    d = max(1, s.max_depth - 1)
    lines = [
        f"renderengine.type = {eng}",
        f"renderengine.seed = {seed}",
        f"native.threads.count = {threads}",
        "sampler.type = SOBOL",
        "sampler.sobol.adaptive.strength = 0",
        "sampler.random.adaptive.strength = 0",
        f"film.width = {w}", f"film.height = {h}",
        *pixel_filter(),
        "film.outputs.0.type = RGB", "film.outputs.0.filename = unused.exr",
        "path.clamping.variance.maxvalue = 0",
        "path.forceblackbackground.enable = 0",
        "batch.haltthreshold = -1",
        "film.noiseestimation.warmup = 1000000000",
        "path.russianroulette.depth = 5",
        "light.russianroulette.depth = 5",
    ]
    if eng == "PATHCPU":
        lines += [f"path.pathdepth.{k} = {d}" for k in ("total", "diffuse", "glossy", "specular")]
        lines += [f"path.hybridbackforward.enable = {1 if engine == 'path' else 0}"]
    else:
        lines += [f"path.maxdepth = {d}", f"light.maxdepth = {d}"]
    if spp:
        lines += [f"batch.haltspp = {spp}"]
    cfg.SetFromString("\n".join(lines) + "\n")
    return lux.RenderConfig(cfg, scene)


def main(argv):
    spp, depth = None, None
    if "--max-depth" in argv:
        i = argv.index("--max-depth")
        depth = int(argv[i + 1])
        argv = argv[:i] + argv[i + 2:]
    if "--spp" in argv:
        i = argv.index("--spp")
        spp = int(argv[i + 1])
        argv = argv[:i] + argv[i + 2:]
    if len(argv) != 8:
        sys.exit(__doc__.split("\n\n")[1])
    xml, w, h, budget, seed, threads, engine, out = argv
    w, h, budget, seed, threads = int(w), int(h), float(budget), int(seed), int(threads)
    import pyluxcore as lux
    lux.Init(lambda msg: None)
    global T0
    T0, c0 = time.perf_counter(), cpu_s()  # after the import, as mitsuba_timed.py
    s = peer_scene.load(xml, w, h)
    if depth is not None:
        s.max_depth = depth
    config = build(lux, s, w, h, seed, threads, engine, spp)
    session = lux.RenderSession(config)
    session.Start()
    deadline = T0 + budget
    while True:
        if spp:
            session.UpdateStats()  # LuxCore checks its halt conditions here
            if session.HasDone():
                break
        elif time.perf_counter() >= deadline:
            break
        time.sleep(0.02 if spp else max(0.0, min(0.05, deadline - time.perf_counter())))
    session.UpdateStats()
    passes = session.GetStats().Get("stats.renderengine.pass").GetInt()
    session.Stop()
    elapsed, cpu = time.perf_counter() - T0, cpu_s() - c0
    buf = np.zeros(h * w * 3, np.float32)
    session.GetFilm().GetOutputFloat(lux.FilmOutputType.RGB, buf)
    img = buf.reshape(h, w, 3)[::-1]  # LuxCore's film rows run bottom-up
    if out != "-":
        peer_scene.write_exr(out, img)
    print(passes, elapsed, cpu, flush=True)
    sys.stderr.flush()
    os._exit(0)  # pyluxcore's threads abort Python's finalization


if __name__ == "__main__":
    main(sys.argv[1:])
