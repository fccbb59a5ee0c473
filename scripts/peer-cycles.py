#!/usr/bin/env python3
"""Cycles (pip `bpy`, Blender as a Python module) renders a Mitsuba 3 scene of the SMS set for a
wall-clock budget: a peer of the equal-time comparison (issue 62; docs/peers.md). Not a test.

    peer-cycles.py SCENE.xml W H BUDGET_S SEED THREADS OUT.exr [--spp N] [--no-guiding] [--max-depth D]

Cycles on the CPU, path tracing with path guiding (Open PGL: surface guiding; training samples
Cycles' default), light tree on (the default), no adaptive sampling, no denoising, no clamping
(direct and indirect), Filter Glossy 0, reflective and refractive caustics on, the pixel filter
forecast's box pixel (BOX, width 1 px; PIXEL_FILTER=scene gives Mitsuba's instead: a Gaussian of
width 2 px, Cycles tabulates exp(−2·(6v/3w)²) over ±1.5w: σ = w/4 = ½ px, Mitsuba's σ; Mitsuba
cuts it at 2 px, Cycles at 3),
SEED as `cycles.seed`, THREADS fixed. Prints `spp seconds cpu_seconds` (as mitsuba_timed.py): the
clock starts after `import bpy`; the scene build (textures, meshes) is inside the budget and
Cycles' `time_limit` gets what is left. That limit leaves out Cycles' scene synchronisation (BVH
build, image upload), so a render overruns the budget by it: the seconds printed are the real
wall time, for the log (renders.tsv). OUT.exr: linear RGB (Blender's EXR of the render result).

What maps (scripts/peer_scene.py reads the file):
- camera: Mitsuba's sensor frame with x and z negated (Blender's camera looks down −z), horizontal
  fov from Mitsuba's fov and fov_axis;
- diffuse → Diffuse BSDF (roughness 0: Lambert); textures → float images set from memory
  (Mitsuba's decoding, linear, bilinear, repeat, texel centres) on the mesh's Mitsuba uv (the
  buffer holds the file's rows top-first, so that v = 0 is Mitsuba's top row), `to_uv` as a
  Mapping node;
- dielectric → Glass BSDF, roughness 0, IOR = Mitsuba's int/ext ratio;
- conductor / roughconductor → Metallic BSDF, Physical Conductor Fresnel with Mitsuba's RGB eta
  (IOR) and k (Extinction), GGX with roughness √α (Cycles' α is roughness²); Mitsuba's material
  "none" → F82 with base colour 1 (reflectance 1). Cycles' GGX masking is the height-correlated
  Smith G, Mitsuba's the separable G1·G1 (differs slightly at grazing angles);
- roughplastic → Principled BSDF (NOT the same BSDF: base colour = the diffuse reflectance,
  roughness √α, IOR η, GGX; Principled's energy-conserving dielectric layer vs Mitsuba's
  roughplastic with internal scattering). Only the pool's dark ladder steps use it;
- normalmap → the perturbed normal built in nodes as Mitsuba's normalmap does: c = 2·rgb − 1 in
  the frame (T, cross(n, T), n), T = the UV tangent orthogonalised against n, n the front-side
  shading normal (flipped back for back-facing hits). Cycles' Normal Map node would use the
  MikkTSpace bitangent sign, which is −1 where Mitsuba's v runs against the mesh's (the sphere);
- area emitter → Emission (strength 1: radiance as given) on the front side only (Mix by
  Backfacing), emission sampling "Front";
- envmap → World Background, strength = scale, Environment Texture (equirectangular) with the
  direction mapped by a Mapping node: Cycles' lat-long (z up, u = −atan2(y, x)/2π + ½) onto
  Mitsuba's (y up, u = atan2(x, −z)/2π): (v.z, v.x, v.y) of v = to_world⁻¹·d, a rotation;
- max_depth d (segments) → max_bounces = d − 2 (Cycles' 0 bounces is direct light only), the
  per-kind bounce limits the same;
- spheres are tessellated (peer_scene.SPHERE_RES rings, smooth normals).
"""
import math
import os
import re
import resource
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import numpy as np  # noqa: E402
import peer_scene  # noqa: E402


def cpu_s():
    ru = resource.getrusage(resource.RUSAGE_SELF)
    return ru.ru_utime + ru.ru_stime


class Builder:
    def __init__(self, bpy):
        self.bpy = bpy
        self.images = {}

    def image(self, path, raw, env=False):
        key = (path, raw, env)
        if key not in self.images:
            img = peer_scene.load_image(path, raw)
            if env:
                img = img[::-1]  # Blender's rows run bottom-up; the lat-long needs the file's orientation
            h, w = img.shape[:2]
            im = self.bpy.data.images.new(f"img{len(self.images)}", w, h, alpha=False, float_buffer=True)
            im.colorspace_settings.name = "Non-Color"
            rgba = np.ones((h, w, 4), np.float32)
            rgba[..., :3] = img
            im.pixels.foreach_set(rgba.reshape(-1))
            im.update()
            self.images[key] = im
        return self.images[key]

    def color(self, nt, t, raw=False):
        """An output socket (or a constant RGBA) for texture t."""
        if "rgb" in t:
            return tuple(t["rgb"]) + (1.0,)
        tex = nt.nodes.new("ShaderNodeTexImage")
        tex.image = self.image(t["bitmap"], raw or t["raw"])
        tex.interpolation = "Linear"
        tex.extension = "REPEAT"
        uv = nt.nodes.new("ShaderNodeUVMap")
        mp = nt.nodes.new("ShaderNodeMapping")
        mp.vector_type = "POINT"
        su, sv, tu, tv = t["to_uv"]
        mp.inputs["Scale"].default_value = (su, sv, 1.0)
        mp.inputs["Location"].default_value = (tu, tv, 0.0)
        nt.links.new(uv.outputs["UV"], mp.inputs["Vector"])
        nt.links.new(mp.outputs["Vector"], tex.inputs["Vector"])
        return tex.outputs["Color"]

    def plug(self, nt, value, socket):
        if isinstance(value, tuple):
            socket.default_value = value if len(socket.default_value) == len(value) else value[:len(socket.default_value)]
        else:
            nt.links.new(value, socket)

    def normal(self, nt, t):
        """Mitsuba's normalmap: N' = normalize(c.x T + c.y cross(n, T) + c.z n), n the front normal."""
        n = nt.nodes.new
        col = self.color(nt, t, raw=True)
        c = n("ShaderNodeVectorMath"); c.operation = "MULTIPLY_ADD"
        nt.links.new(col, c.inputs[0]); c.inputs[1].default_value = (2, 2, 2); c.inputs[2].default_value = (-1, -1, -1)
        geo = n("ShaderNodeNewGeometry")
        sgn = n("ShaderNodeMath"); sgn.operation = "MULTIPLY_ADD"
        nt.links.new(geo.outputs["Backfacing"], sgn.inputs[0]); sgn.inputs[1].default_value = -2.0; sgn.inputs[2].default_value = 1.0
        nf = n("ShaderNodeVectorMath"); nf.operation = "SCALE"
        nt.links.new(geo.outputs["Normal"], nf.inputs[0]); nt.links.new(sgn.outputs[0], nf.inputs["Scale"])
        tan = n("ShaderNodeTangent"); tan.direction_type = "UV_MAP"
        tt = n("ShaderNodeVectorMath"); tt.operation = "CROSS_PRODUCT"
        nt.links.new(nf.outputs[0], tt.inputs[0]); nt.links.new(tan.outputs["Tangent"], tt.inputs[1])
        sep = n("ShaderNodeSeparateXYZ"); nt.links.new(c.outputs[0], sep.inputs[0])
        terms = []
        for comp, vec in (("X", tan.outputs["Tangent"]), ("Y", tt.outputs[0]), ("Z", nf.outputs[0])):
            sc = n("ShaderNodeVectorMath"); sc.operation = "SCALE"
            nt.links.new(vec, sc.inputs[0]); nt.links.new(sep.outputs[comp], sc.inputs["Scale"])
            terms.append(sc.outputs[0])
        a1 = n("ShaderNodeVectorMath"); a1.operation = "ADD"
        nt.links.new(terms[0], a1.inputs[0]); nt.links.new(terms[1], a1.inputs[1])
        a2 = n("ShaderNodeVectorMath"); a2.operation = "ADD"
        nt.links.new(a1.outputs[0], a2.inputs[0]); nt.links.new(terms[2], a2.inputs[1])
        nrm = n("ShaderNodeVectorMath"); nrm.operation = "NORMALIZE"
        nt.links.new(a2.outputs[0], nrm.inputs[0])
        out = n("ShaderNodeVectorMath"); out.operation = "SCALE"
        nt.links.new(nrm.outputs[0], out.inputs[0]); nt.links.new(sgn.outputs[0], out.inputs["Scale"])
        return out.outputs[0]

    def bsdf(self, nt, b, normal=None):
        n = nt.nodes.new
        t = b["type"]
        if t == "normalmap":
            return self.bsdf(nt, b["nested"], self.normal(nt, b["normalmap"]))
        if t == "diffuse":
            s = n("ShaderNodeBsdfDiffuse")
            s.inputs["Roughness"].default_value = 0.0
            self.plug(nt, self.color(nt, b["reflectance"]), s.inputs["Color"])
        elif t == "dielectric":
            s = n("ShaderNodeBsdfGlass")
            s.distribution = "GGX"
            s.inputs["Roughness"].default_value = 0.0
            s.inputs["IOR"].default_value = b["eta"]
            s.inputs["Color"].default_value = (1, 1, 1, 1)
        elif t in ("conductor", "roughconductor"):
            s = n("ShaderNodeBsdfMetallic")
            s.distribution = "GGX"
            s.inputs["Roughness"].default_value = math.sqrt(b["alpha"]) if t == "roughconductor" else 0.0
            if max(b["eta"]) == 0.0:
                s.fresnel_type = "F82"
                s.inputs["Base Color"].default_value = (1, 1, 1, 1)
                s.inputs["Edge Tint"].default_value = (1, 1, 1, 1)
            else:
                s.fresnel_type = "PHYSICAL_CONDUCTOR"
                s.inputs["IOR"].default_value = tuple(b["eta"])
                s.inputs["Extinction"].default_value = tuple(b["k"])
        elif t == "roughplastic":
            s = n("ShaderNodeBsdfPrincipled")
            s.distribution = "GGX"
            self.plug(nt, self.color(nt, b["diffuse_reflectance"]), s.inputs["Base Color"])
            s.inputs["Roughness"].default_value = math.sqrt(b["alpha"])
            s.inputs["IOR"].default_value = b["eta"]
            s.inputs["Metallic"].default_value = 0.0
        else:
            raise peer_scene.SceneError(f"no Cycles shader for {t}")
        if normal is not None:
            nt.links.new(normal, s.inputs["Normal"])
        return s.outputs[0]

    def material(self, name, b, radiance):
        bpy = self.bpy
        m = bpy.data.materials.new(name)
        m.use_nodes = True
        nt = m.node_tree
        for node in list(nt.nodes):
            nt.nodes.remove(node)
        out = nt.nodes.new("ShaderNodeOutputMaterial")
        sh = self.bsdf(nt, b)
        if radiance is not None:
            em = nt.nodes.new("ShaderNodeEmission")
            em.inputs["Color"].default_value = tuple(radiance) + (1.0,)
            em.inputs["Strength"].default_value = 1.0
            add = nt.nodes.new("ShaderNodeAddShader")
            nt.links.new(em.outputs[0], add.inputs[0]); nt.links.new(sh, add.inputs[1])
            geo = nt.nodes.new("ShaderNodeNewGeometry")
            mix = nt.nodes.new("ShaderNodeMixShader")  # front: emission + BSDF; back: the BSDF
            nt.links.new(geo.outputs["Backfacing"], mix.inputs[0])
            nt.links.new(add.outputs[0], mix.inputs[1]); nt.links.new(sh, mix.inputs[2])
            sh = mix.outputs[0]
            m.cycles.emission_sampling = "FRONT"
        else:
            m.cycles.emission_sampling = "NONE"
        nt.links.new(sh, out.inputs["Surface"])
        return m

    def mesh(self, name, sh, mat):
        bpy = self.bpy
        me = bpy.data.meshes.new(name)
        nv, nt_ = len(sh.p), len(sh.tri)
        me.vertices.add(nv)
        me.vertices.foreach_set("co", sh.p.astype(np.float32).reshape(-1))
        me.loops.add(3 * nt_)
        me.loops.foreach_set("vertex_index", sh.tri.astype(np.int32).reshape(-1))
        me.polygons.add(nt_)
        me.polygons.foreach_set("loop_start", (np.arange(nt_, dtype=np.int32) * 3))
        uv = me.uv_layers.new(name="UVMap")
        uv.data.foreach_set("uv", sh.uv[sh.tri.reshape(-1)].astype(np.float32).reshape(-1))
        me.update()
        me.validate(clean_customdata=False)
        me.shade_smooth()
        me.normals_split_custom_set_from_vertices([tuple(v) for v in sh.n.astype(float)])
        me.materials.append(mat)
        ob = bpy.data.objects.new(name, me)
        bpy.context.scene.collection.objects.link(ob)
        return ob


def build(bpy, s, w, h, seed, threads):
    import mathutils
    bpy.ops.wm.read_factory_settings(use_empty=True)
    sc = bpy.context.scene
    b = Builder(bpy)
    for k, sh in enumerate(s.shapes):
        b.mesh(f"shape{k}", sh, b.material(f"mat{k}", sh.bsdf, sh.radiance))
    cam = bpy.data.cameras.new("cam")
    cam.type = "PERSP"
    cam.sensor_fit = "HORIZONTAL"
    cam.angle = 2 * math.atan(s.tan_x)
    cam.clip_start, cam.clip_end = 1e-4, 1e6
    ob = bpy.data.objects.new("cam", cam)
    sc.collection.objects.link(ob)
    ob.matrix_world = mathutils.Matrix((s.cam_to_world @ np.diag([-1.0, 1.0, -1.0, 1.0])).tolist())
    sc.camera = ob
    world = bpy.data.worlds.new("world")
    world.use_nodes = True
    nt = world.node_tree
    bg = nt.nodes["Background"]
    if s.envmap:
        env = nt.nodes.new("ShaderNodeTexEnvironment")
        env.image = b.image(s.envmap["filename"], True, env=True)
        env.interpolation = "Linear"
        env.projection = "EQUIRECTANGULAR"
        tc = nt.nodes.new("ShaderNodeTexCoord")
        mp = nt.nodes.new("ShaderNodeMapping")
        mp.vector_type = "VECTOR"
        p = np.array([[0, 0, 1], [1, 0, 0], [0, 1, 0]], float)
        r = p @ np.linalg.inv(s.envmap["to_world"][:3, :3])
        mp.inputs["Rotation"].default_value = mathutils.Matrix(r.tolist()).to_euler("XYZ")
        nt.links.new(tc.outputs["Generated"], mp.inputs["Vector"])
        nt.links.new(mp.outputs["Vector"], env.inputs["Vector"])
        nt.links.new(env.outputs["Color"], bg.inputs["Color"])
        bg.inputs["Strength"].default_value = s.envmap["scale"]
    else:
        bg.inputs["Strength"].default_value = 0.0
    sc.world = world

    r = sc.render
    r.engine = "CYCLES"
    r.resolution_x, r.resolution_y, r.resolution_percentage = w, h, 100
    r.threads_mode = "FIXED"
    r.threads = threads
    r.film_transparent = False
    r.image_settings.file_format = "OPEN_EXR"
    r.image_settings.color_depth = "32"
    r.use_persistent_data = False
    sc.view_settings.view_transform = "Standard"
    cy = sc.cycles
    cy.device = "CPU"
    cy.use_adaptive_sampling = False
    cy.use_denoising = False
    cy.seed = seed
    cy.use_animated_seed = False
    d = max(0, s.max_depth - 2)
    for k in ("max_bounces", "diffuse_bounces", "glossy_bounces", "transmission_bounces", "volume_bounces"):
        setattr(cy, k, d)
    cy.transparent_max_bounces = d
    cy.caustics_reflective = True
    cy.caustics_refractive = True
    cy.blur_glossy = 0.0
    cy.sample_clamp_direct = 0.0
    cy.sample_clamp_indirect = 0.0
    f = os.environ.get("PIXEL_FILTER", "box")
    if f not in ("box", "scene"):
        sys.exit(f"peer-cycles.py: PIXEL_FILTER must be box or scene, got {f!r}")
    cy.pixel_filter_type, cy.filter_width = ("BOX", 1.0) if f == "box" else ("GAUSSIAN", 2.0)
    cy.use_light_tree = True
    return sc


def main(argv):
    spp, guiding, depth = None, True, None
    if "--max-depth" in argv:
        i = argv.index("--max-depth")
        depth = int(argv[i + 1])
        argv = argv[:i] + argv[i + 2:]
    if "--spp" in argv:
        i = argv.index("--spp")
        spp = int(argv[i + 1])
        argv = argv[:i] + argv[i + 2:]
    if "--no-guiding" in argv:
        argv.remove("--no-guiding")
        guiding = False
    if len(argv) != 7:
        sys.exit(__doc__.split("\n\n")[1])
    xml, w, h, budget, seed, threads, out = argv
    w, h, budget, seed, threads = int(w), int(h), float(budget), int(seed), int(threads)
    import bpy
    t0, c0 = time.perf_counter(), cpu_s()
    s = peer_scene.load(xml, w, h)
    if depth is not None:
        s.max_depth = depth
    sc = build(bpy, s, w, h, seed, threads)
    cy = sc.cycles
    cy.use_guiding = guiding
    cy.use_surface_guiding = guiding
    cy.use_volume_guiding = False
    stats = []
    bpy.app.handlers.render_stats.append(lambda txt: stats.append(txt))
    sc.render.filepath = os.path.abspath(out) if out != "-" else os.path.join("/tmp", f"cycles-{os.getpid()}.exr")
    if spp:
        cy.samples = spp
        cy.time_limit = 0.0
    else:
        # Cycles' time_limit leaves out its scene synchronisation (BVH, images), which this render
        # then spends beyond the budget: the wall seconds printed show it. (A first one-sample
        # render with persistent data, to sync inside the budget, left the timed render at its one
        # sample in Blender 5.2: not used.)
        cy.samples = 1 << 24
        cy.time_limit = max(0.05, budget - (time.perf_counter() - t0))
    bpy.ops.render.render(write_still=True)
    elapsed, cpu = time.perf_counter() - t0, cpu_s() - c0
    done = 0
    for txt in stats:
        m = re.search(r"Sample (\d+)/", txt)
        if m:
            done = max(done, int(m.group(1)))
    if out == "-":
        os.remove(sc.render.filepath)
    print(spp or done, elapsed, cpu, flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
