"""The subset of Mitsuba 3's scene format that the SMS scenes use, read into plain arrays for the
peer renderers (scripts/peer-luxcore.py, scripts/peer-cycles.py; docs/peers.md). Pure Python and
numpy (images: Pillow for 8-bit files, the `OpenEXR` package for EXR), so that it runs in each
peer's own virtual environment, none of which has Mitsuba.

Contract: `load(xml, width, height)` returns a `Scene` whose every quantity is what Mitsuba 3
(an RGB variant) renders from that file:
- camera: `cam_to_world` (4×4; columns left, up, forward, origin: Mitsuba's sensor frame, scale
  removed), the half-angle tangents `tan_x`, `tan_y` of the frame from `fov` and `fov_axis`;
- shapes as triangle meshes in world space with Mitsuba's own `uv` (the OBJ loader's flipped v;
  the rectangle's (x+1)/2, (y+1)/2; the sphere's (φ/2π, θ/π) in its local frame) and vertex
  normals (the sphere and the disk are tessellated: `SPHERE_RES` rings, twice as many segments);
- BSDFs as dicts (`type` one of diffuse, dielectric, conductor, roughconductor, roughplastic,
  each optionally inside `normalmap`), textures as {'rgb': (r, g, b)} or {'bitmap': path, 'raw':
  bool, 'to_uv': (su, sv, tu, tv)}; `eta` of a dielectric is int_ior / ext_ior; a conductor's
  RGB `eta`, `k` are the values Mitsuba 3.9.1's rgb variants compute from its spectral tables
  (`material` "Au" and "none" only: add a row to CONDUCTORS from `mi.traverse` for another);
- area emitters (RGB radiance, one-sided: the mesh's front, the side its normals face; a uniform
  `<spectrum>` radiance is the equal-energy colour Mitsuba's rgb variants make of it, not white);
- the `envmap` (its file, `scale`, `to_world`);
- `max_depth` (Mitsuba's: path segments).
Anything outside this subset is an error naming the file and the element, never a silent guess.

`load_image(path, raw)` decodes a texture as Mitsuba does: float RGB, the file's top row first;
8-bit files are sRGB-decoded (the exact piecewise curve) unless `raw`.
"""
import math
import os
import re
import xml.etree.ElementTree as ET

import numpy as np
import OpenEXR  # before any renderer's module: pyluxcore bundles another OpenEXR (free() aborts otherwise)

SPHERE_RES = 256  # rings of a tessellated sphere (and 2 × as many segments)

# RGB eta and k of Mitsuba 3.9.1's conductor `material` (scalar_rgb, mi.traverse of the BSDF)
CONDUCTORS = {
    "Au": ((0.143036, 0.375307, 1.44205), (3.983, 2.38556, 1.60336)),
    "none": ((0.0, 0.0, 0.0), (1.0, 1.0, 1.0)),  # Mitsuba's default: a perfect mirror
}
# An emitter's uniform `<spectrum value="X">` in Mitsuba 3.9.1's rgb variants: the equal-energy
# spectrum's sRGB colour (not white), X × this (mi.traverse of an area emitter with value 1)
UNIFORM_EMITTER_RGB = (1.2047939, 0.948291, 0.90891606)
# Mitsuba's named indices of refraction (the ones these scenes can reach)
IORS = {"bk7": 1.5046, "air": 1.000277, "vacuum": 1.0, "water": 1.3330, "polypropylene": 1.49}


class SceneError(Exception):
    pass


class Shape:
    def __init__(self, name, p, n, uv, tri, bsdf, radiance):
        self.name, self.p, self.n, self.uv, self.tri = name, p, n, uv, tri
        self.bsdf, self.radiance = bsdf, radiance


class Scene:
    pass


def srgb_to_linear(x):
    return np.where(x <= 0.04045, x / 12.92, ((x + 0.055) / 1.055) ** 2.4)


def load_image(path, raw):
    """float32 (H, W, 3), the file's top row first, linear unless `raw` (Mitsuba's bitmap)."""
    if path.lower().endswith(".exr"):
        with OpenEXR.File(path) as f:
            ch = f.channels()
            if "RGB" in ch:
                img = np.asarray(ch["RGB"].pixels, dtype=np.float32)
            elif "RGBA" in ch:
                img = np.asarray(ch["RGBA"].pixels, dtype=np.float32)[..., :3]
            else:
                img = np.stack([np.asarray(ch[c].pixels, dtype=np.float32) for c in "RGB"], -1)
        return np.ascontiguousarray(img[..., :3])
    from PIL import Image
    im = Image.open(path)
    im = im.convert("RGB")
    img = np.asarray(im, dtype=np.float32) / 255.0
    if not raw:
        img = srgb_to_linear(img)
    return np.ascontiguousarray(img.astype(np.float32))


# ---------------------------------------------------------------- transforms

def _vec(e, keys, default):
    return [float(e.get(k, default)) for k in keys]


def rotation(axis, deg):
    a = np.asarray(axis, float)
    a = a / np.linalg.norm(a)
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    x, y, z = a
    r = np.array([[c + x * x * (1 - c), x * y * (1 - c) - z * s, x * z * (1 - c) + y * s],
                  [y * x * (1 - c) + z * s, c + y * y * (1 - c), y * z * (1 - c) - x * s],
                  [z * x * (1 - c) - y * s, z * y * (1 - c) + x * s, c + z * z * (1 - c)]])
    m = np.eye(4)
    m[:3, :3] = r
    return m


def _triple(s):
    v = [float(t) for t in re.split(r"[,\s]+", s.strip()) if t]
    if len(v) != 3:
        raise ValueError(s)
    return np.array(v)


def parse_transform(e, ctx):
    m = np.eye(4)
    for op in e:
        t = op.tag
        if t == "translate":
            if op.get("value") is not None:
                v = _triple(op.get("value"))
            else:
                v = np.array(_vec(op, "xyz", 0))
            o = np.eye(4)
            o[:3, 3] = v
        elif t == "scale":
            if op.get("value") is not None:
                vs = [float(x) for x in re.split(r"[,\s]+", op.get("value").strip()) if x]
                v = vs * 3 if len(vs) == 1 else vs
            else:
                v = _vec(op, "xyz", 1)
            o = np.diag([v[0], v[1], v[2], 1.0])
        elif t == "rotate":
            if op.get("value") is not None:
                axis = _triple(op.get("value"))
            else:
                axis = _vec(op, "xyz", 0)
            o = rotation(axis, float(op.get("angle")))
        elif t == "lookat":
            org, tgt = _triple(op.get("origin")), _triple(op.get("target"))
            up = _triple(op.get("up", "0,1,0"))
            d = tgt - org
            d /= np.linalg.norm(d)
            left = np.cross(up, d)
            left /= np.linalg.norm(left)
            nup = np.cross(d, left)
            o = np.eye(4)
            o[:3, 0], o[:3, 1], o[:3, 2], o[:3, 3] = left, nup, d, org
        elif t == "matrix":
            v = [float(x) for x in re.split(r"[,\s]+", op.get("value").strip()) if x]
            if len(v) == 16:
                o = np.array(v).reshape(4, 4)
            elif len(v) == 9:
                o = np.eye(4)
                o[:3, :3] = np.array(v).reshape(3, 3)
            else:
                raise SceneError(f"{ctx}: <matrix> needs 9 or 16 values")
        else:
            raise SceneError(f"{ctx}: transform element <{t}> is not supported")
        m = o @ m
    return m


# ---------------------------------------------------------------- meshes

def load_obj(path):
    """Mitsuba's OBJ loader: vertices unique per (v, vt, vn) triple, polygons fanned, vt's v
    flipped (flip_tex_coords)."""
    vs, vts, vns = [], [], []
    key, P, N, UV, T = {}, [], [], [], []
    with open(path) as f:
        for line in f:
            if line.startswith("v "):
                vs.append([float(x) for x in line.split()[1:4]])
            elif line.startswith("vt "):
                vts.append([float(x) for x in line.split()[1:3]])
            elif line.startswith("vn "):
                vns.append([float(x) for x in line.split()[1:4]])
            elif line.startswith("f "):
                idx = []
                for c in line.split()[1:]:
                    parts = c.split("/")
                    k = []
                    for i, (arr) in enumerate((vs, vts, vns)):
                        if i < len(parts) and parts[i]:
                            j = int(parts[i])
                            k.append(j - 1 if j > 0 else len(arr) + j)
                        else:
                            k.append(-1)
                    k = tuple(k)
                    if k not in key:
                        key[k] = len(P)
                        P.append(vs[k[0]])
                        UV.append(vts[k[1]] if k[1] >= 0 else [0.0, 0.0])
                        N.append(vns[k[2]] if k[2] >= 0 else [0.0, 0.0, 0.0])
                    idx.append(key[k])
                for i in range(1, len(idx) - 1):
                    T.append([idx[0], idx[i], idx[i + 1]])
    p, uv, tri = np.array(P, float), np.array(UV, float), np.array(T, np.int64)
    n = np.array(N, float) if vns else None
    uv[:, 1] = 1.0 - uv[:, 1]
    if n is None:
        n = vertex_normals(p, tri)
    return p, n, uv, tri


def load_ply(path):
    """PLY (ascii or binary little/big endian): x y z, optional nx ny nz, u v (or s t),
    faces as a vertex_indices/vertex_index list (fanned)."""
    with open(path, "rb") as f:
        if f.readline().strip() != b"ply":
            raise SceneError(f"{path}: not a PLY file")
        fmt, elems = None, []
        while True:
            line = f.readline().decode("ascii").strip()
            if line == "end_header":
                break
            w = line.split()
            if not w or w[0] in ("comment", "obj_info"):
                continue
            if w[0] == "format":
                fmt = w[1]
            elif w[0] == "element":
                elems.append([w[1], int(w[2]), []])
            elif w[0] == "property":
                elems[-1][2].append(w[1:])
        body = f.read()
    types = {"char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "i2", "int16": "i2",
             "ushort": "u2", "uint16": "u2", "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
             "float": "f4", "float32": "f4", "double": "f8", "float64": "f8"}
    data = {}
    if fmt == "ascii":
        toks = body.split()
        pos = 0
        for name, count, props in elems:
            rows = []
            for _ in range(count):
                row = []
                for pr in props:
                    if pr[0] == "list":
                        k = int(toks[pos]); pos += 1
                        row.append([float(t) for t in toks[pos:pos + k]]); pos += k
                    else:
                        row.append(float(toks[pos])); pos += 1
                rows.append(row)
            data[name] = (props, rows)
    else:
        end = "<" if fmt == "binary_little_endian" else ">"
        pos = 0
        for name, count, props in elems:
            if all(pr[0] != "list" for pr in props):
                dt = np.dtype([(pr[1], end + types[pr[0]]) for pr in props])
                arr = np.frombuffer(body, dt, count, pos)
                pos += dt.itemsize * count
                data[name] = (props, arr)
            else:
                rows = []
                for _ in range(count):
                    row = []
                    for pr in props:
                        if pr[0] == "list":
                            ct, it = np.dtype(end + types[pr[1]]), np.dtype(end + types[pr[2]])
                            k = int(np.frombuffer(body, ct, 1, pos)[0]); pos += ct.itemsize
                            row.append(np.frombuffer(body, it, k, pos).tolist()); pos += it.itemsize * k
                        else:
                            t = np.dtype(end + types[pr[0]])
                            row.append(float(np.frombuffer(body, t, 1, pos)[0])); pos += t.itemsize
                    rows.append(row)
                data[name] = (props, rows)

    def column(name, prop):
        props, rows = data[name]
        names = [pr[-1] for pr in props]
        if prop not in names:
            return None
        if isinstance(rows, np.ndarray):
            return rows[prop].astype(float)
        i = names.index(prop)
        return np.array([r[i] for r in rows], float)
    p = np.stack([column("vertex", c) for c in "xyz"], 1)
    n = None
    if column("vertex", "nx") is not None:
        n = np.stack([column("vertex", c) for c in ("nx", "ny", "nz")], 1)
    u = column("vertex", "u") if column("vertex", "u") is not None else column("vertex", "s")
    v = column("vertex", "v") if column("vertex", "v") is not None else column("vertex", "t")
    uv = np.stack([u, 1.0 - v], 1) if u is not None else np.zeros((len(p), 2))  # flip as OBJ
    props, rows = data["face"]
    li = [i for i, pr in enumerate(props) if pr[0] == "list"][0]
    tri = []
    for r in rows:
        f = [int(x) for x in r[li]]
        for i in range(1, len(f) - 1):
            tri.append([f[0], f[i], f[i + 1]])
    tri = np.array(tri, np.int64)
    if n is None:
        n = vertex_normals(p, tri)
    return p, n, uv, tri


def vertex_normals(p, tri):
    fn = np.cross(p[tri[:, 1]] - p[tri[:, 0]], p[tri[:, 2]] - p[tri[:, 0]])
    n = np.zeros_like(p)
    for k in range(3):
        np.add.at(n, tri[:, k], fn)
    return n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-30)


def rectangle():
    p = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], float)
    uv = (p[:, :2] + 1) / 2
    n = np.tile([0.0, 0.0, 1.0], (4, 1))
    return p, n, uv, np.array([[0, 1, 2], [0, 2, 3]])


def sphere(rings=SPHERE_RES):
    """Mitsuba's sphere param: u = φ/2π (φ = atan2(y, x)), v = θ/π (θ = acos z), exact normals
    at the vertices; a seam column and a vertex per segment at each pole."""
    segs = 2 * rings
    th = np.linspace(0, math.pi, rings + 1)
    ph = np.linspace(0, 2 * math.pi, segs + 1)
    T, PH = np.meshgrid(th, ph, indexing="ij")
    p = np.stack([np.sin(T) * np.cos(PH), np.sin(T) * np.sin(PH), np.cos(T)], -1).reshape(-1, 3)
    uv = np.stack([PH / (2 * math.pi), T / math.pi], -1).reshape(-1, 2)
    i = np.arange(rings)[:, None] * (segs + 1) + np.arange(segs)[None, :]
    a, b, c, d = i, i + 1, i + segs + 1, i + segs + 2
    # outward winding: (a, c, d), (a, d, b) with a at (θ, φ), c at (θ + dθ, φ)
    tri = np.concatenate([np.stack([a, c, d], -1).reshape(-1, 3)[:-segs],   # no degenerate tri at θ=π
                          np.stack([a, d, b], -1).reshape(-1, 3)[segs:]])   # nor at θ=0
    return p, p.copy(), uv, tri


def disk(rings=64):
    segs = 4 * rings
    r = np.linspace(0, 1, rings + 1)
    ph = np.linspace(0, 2 * math.pi, segs + 1)
    R, PH = np.meshgrid(r, ph, indexing="ij")
    p = np.stack([R * np.cos(PH), R * np.sin(PH), np.zeros_like(R)], -1).reshape(-1, 3)
    uv = np.stack([R, PH / (2 * math.pi)], -1).reshape(-1, 2)
    i = np.arange(rings)[:, None] * (segs + 1) + np.arange(segs)[None, :]
    a, b, c, d = i, i + 1, i + segs + 1, i + segs + 2
    tri = np.concatenate([np.stack([a, c, d], -1).reshape(-1, 3), np.stack([a, d, b], -1).reshape(-1, 3)[segs:]])
    return p, np.tile([0.0, 0.0, 1.0], (len(p), 1)), uv, tri


# ---------------------------------------------------------------- the XML

class Parser:
    def __init__(self, xml, width, height):
        self.xml = os.path.abspath(xml)
        self.dir = os.path.dirname(self.xml)
        self.params = {}
        self.ids = {}
        self.width, self.height = width, height

    def err(self, e, msg):
        return SceneError(f"{self.xml}: <{e.tag} {' '.join(f'{k}={v!r}' for k, v in e.attrib.items())}>: {msg}")

    def sub(self, s):
        return re.sub(r"\$(\w+)", lambda m: str(self.params[m.group(1)]), s) if s else s

    def props(self, e):
        """name → element of the child properties, values substituted."""
        out = {}
        for c in e:
            for k in ("value", "name", "filename"):
                if c.get(k) is not None:
                    c.set(k, self.sub(c.get(k)))
            if c.get("name") is not None:
                out[c.get("name")] = c
        return out

    def num(self, e, name, default):
        p = self.props(e)
        return float(p[name].get("value")) if name in p else default

    def color(self, c):
        if c.tag in ("rgb", "spectrum", "float"):
            v = [float(x) for x in re.split(r"[,\s]+", c.get("value").strip()) if x]
            if c.tag == "spectrum" and len(v) != 1:
                raise self.err(c, "only a uniform <spectrum value=…> is supported")
            return tuple(v * 3 if len(v) == 1 else v)
        raise self.err(c, "expected an rgb, spectrum or float")

    def texture(self, c, raw_default=False):
        if c.tag in ("rgb", "spectrum", "float") and c.get("type") is None:
            return {"rgb": self.color(c)}
        if c.tag in ("texture", "spectrum") and c.get("type") == "bitmap":
            p = self.props(c)
            fn = os.path.join(self.dir, p["filename"].get("value"))
            if not os.path.exists(fn):
                raise self.err(c, f"texture file {fn} does not exist")
            raw = raw_default
            if "raw" in p:
                raw = p["raw"].get("value") == "true"
            su = sv = 1.0
            tu = tv = 0.0
            for t in c.findall("transform"):
                m = parse_transform(t, self.xml)
                if abs(m[0, 1]) > 1e-12 or abs(m[1, 0]) > 1e-12:
                    raise self.err(t, "to_uv: only scale and translate are supported")
                su, sv, tu, tv = m[0, 0], m[1, 1], m[0, 3], m[1, 3]
            for k in ("filter_type", "wrap_mode"):
                if k in p and p[k].get("value") not in ("bilinear", "repeat"):
                    raise self.err(c, f"{k} {p[k].get('value')} is not supported (bilinear, repeat)")
            return {"bitmap": fn, "raw": raw, "to_uv": (su, sv, tu, tv)}
        raise self.err(c, "unsupported texture")

    def ior(self, p, name, default):
        if name not in p:
            return IORS[default]
        v = p[name].get("value")
        try:
            return float(v)
        except ValueError:
            if v not in IORS:
                raise self.err(p[name], f"unknown IOR name {v}")
            return IORS[v]

    def bsdf(self, e):
        if e.tag == "ref":
            return self.ids[e.get("id")]
        t = e.get("type")
        p = self.props(e)
        if t == "twosided":
            b = self.bsdf(e.find("bsdf"))
        elif t == "diffuse":
            b = {"type": "diffuse", "reflectance": self.texture(p["reflectance"]) if "reflectance" in p else {"rgb": (0.5,) * 3}}
        elif t in ("dielectric", "thindielectric"):
            if t == "thindielectric":
                raise self.err(e, "thindielectric is not supported")
            b = {"type": "dielectric", "eta": self.ior(p, "int_ior", "bk7") / self.ior(p, "ext_ior", "air")}
        elif t in ("conductor", "roughconductor"):
            if "eta" in p or "k" in p:
                b = {"eta": self.color(p["eta"]), "k": self.color(p["k"])}
            else:
                mat = p["material"].get("value") if "material" in p else "none"
                if mat not in CONDUCTORS:
                    raise self.err(e, f"conductor material {mat}: add its RGB eta, k to CONDUCTORS")
                b = {"eta": CONDUCTORS[mat][0], "k": CONDUCTORS[mat][1]}
            b["type"] = t
            if "specular_reflectance" in p:
                raise self.err(e, "specular_reflectance is not supported")
            if t == "roughconductor":
                b["alpha"] = self.alpha(e, p)
        elif t == "roughplastic":
            if p.get("nonlinear") is not None and p["nonlinear"].get("value") == "true":
                raise self.err(e, "nonlinear roughplastic is not supported")
            b = {"type": "roughplastic", "alpha": self.alpha(e, p),
                 "diffuse_reflectance": self.texture(p["diffuse_reflectance"]) if "diffuse_reflectance" in p else {"rgb": (0.5,) * 3},
                 "eta": self.ior(p, "int_ior", "polypropylene") / self.ior(p, "ext_ior", "air")}
        elif t == "normalmap":
            inner = [c for c in e if c.tag in ("bsdf", "ref")]
            b = {"type": "normalmap", "normalmap": self.texture(p["normalmap"], raw_default=True),
                 "nested": self.bsdf(inner[0])}
        else:
            raise self.err(e, f"BSDF type {t} is not supported")
        if e.get("id"):
            self.ids[e.get("id")] = b
        return b

    def alpha(self, e, p):
        if "distribution" in p and p["distribution"].get("value") != "ggx":
            raise self.err(e, "only the ggx distribution is supported")
        if "alpha_u" in p or "alpha_v" in p:
            raise self.err(e, "anisotropic alpha is not supported")
        return float(p["alpha"].get("value")) if "alpha" in p else 0.1

    def shape(self, e, k):
        t = e.get("type")
        p = self.props(e)
        m = np.eye(4)
        for tr in e.findall("transform"):
            m = parse_transform(tr, self.xml)
        if t == "obj" or t == "ply":
            fn = os.path.join(self.dir, p["filename"].get("value"))
            if not os.path.exists(fn):
                raise self.err(e, f"mesh file {fn} does not exist")
            pos, n, uv, tri = (load_obj if t == "obj" else load_ply)(fn)
            if "face_normals" in p and p["face_normals"].get("value") == "true":
                raise self.err(e, "face_normals is not supported")
        elif t == "rectangle":
            pos, n, uv, tri = rectangle()
        elif t == "sphere":
            pos, n, uv, tri = sphere()
            r = self.num(e, "radius", 1.0)
            c = _triple(p["center"].get("value")) if "center" in p and p["center"].get("value") else (
                np.array(_vec(p["center"], "xyz", 0)) if "center" in p else np.zeros(3))
            o = np.diag([r, r, r, 1.0])
            o[:3, 3] = c
            m = m @ o
        elif t == "disk":
            pos, n, uv, tri = disk()
        else:
            raise self.err(e, f"shape type {t} is not supported")
        if "flip_normals" in p and p["flip_normals"].get("value") == "true":
            raise self.err(e, "flip_normals is not supported")
        ph = np.c_[pos, np.ones(len(pos))] @ m.T
        pw = ph[:, :3]
        nw = n @ np.linalg.inv(m[:3, :3])
        nw /= np.maximum(np.linalg.norm(nw, axis=1, keepdims=True), 1e-30)
        if np.linalg.det(m[:3, :3]) < 0:  # a mirroring transform: keep the winding with the normals
            tri = tri[:, ::-1]
        bs = [c for c in e if c.tag in ("bsdf", "ref")]
        bsdf = self.bsdf(bs[0]) if bs else {"type": "diffuse", "reflectance": {"rgb": (0.5,) * 3}}
        radiance = None
        em = e.find("emitter")
        if em is not None:
            if em.get("type") != "area":
                raise self.err(em, "only area emitters on shapes are supported")
            rad = self.props(em)["radiance"]
            radiance = self.color(rad)
            if rad.tag == "spectrum":
                radiance = tuple(v * w for v, w in zip(radiance, UNIFORM_EMITTER_RGB))
        return Shape(f"shape{k}", pw, nw, uv, tri, bsdf, radiance)

    def parse(self):
        root = ET.parse(self.xml).getroot()
        for d in root.findall("default"):
            self.params[d.get("name")] = d.get("value")
        self.params["width"], self.params["height"] = self.width, self.height
        for el in root.iter():
            for k, v in el.attrib.items():
                if "$" in v:
                    el.set(k, self.sub(v))
        s = Scene()
        s.xml, s.width, s.height = self.xml, self.width, self.height
        s.shapes, s.envmap, s.max_depth = [], None, -1
        for e in root:
            if e.tag in ("film", "sampler", "rfilter") and e.get("id"):
                self.ids[e.get("id")] = e
            elif e.tag == "bsdf":
                self.bsdf(e)
        k = 0
        for e in root:
            if e.tag == "integrator":
                if e.get("type") not in ("path", "ptracer", "volpath"):
                    pass  # the peers render their own way; only max_depth is read
                s.max_depth = int(self.num(e, "max_depth", -1))
            elif e.tag == "sensor":
                self.sensor(e, s)
            elif e.tag == "shape":
                s.shapes.append(self.shape(e, k))
                k += 1
            elif e.tag == "emitter":
                if e.get("type") != "envmap":
                    raise self.err(e, f"emitter {e.get('type')} is not supported (envmap only)")
                p = self.props(e)
                m = np.eye(4)
                for tr in e.findall("transform"):
                    m = parse_transform(tr, self.xml)
                fn = os.path.join(self.dir, p["filename"].get("value"))
                if not os.path.exists(fn):
                    raise self.err(e, f"envmap file {fn} does not exist")
                s.envmap = {"filename": fn, "scale": self.num(e, "scale", 1.0), "to_world": m}
            elif e.tag in ("default", "film", "sampler", "bsdf", "texture"):
                pass
            else:
                raise self.err(e, "unsupported top-level element")
        if s.max_depth < 0:
            raise SceneError(f"{self.xml}: the integrator's max_depth must be given (peers cannot render unbounded paths alike)")
        return s

    def sensor(self, e, s):
        if e.get("type") != "perspective":
            raise self.err(e, "only the perspective sensor is supported")
        p = self.props(e)
        m = np.eye(4)
        for tr in e.findall("transform"):
            m = parse_transform(tr, self.xml)
        c = m.copy()
        for i in range(3):
            c[:3, i] /= np.linalg.norm(c[:3, i])
        s.cam_to_world = c
        fov = float(p["fov"].get("value"))
        axis = p["fov_axis"].get("value") if "fov_axis" in p else "x"
        w, h = self.width, self.height
        t = math.tan(math.radians(fov) / 2)
        if axis == "smaller":
            axis = "x" if w <= h else "y"
        elif axis == "larger":
            axis = "x" if w >= h else "y"
        if axis == "x":
            s.tan_x, s.tan_y = t, t * h / w
        elif axis == "y":
            s.tan_x, s.tan_y = t * w / h, t
        elif axis == "diagonal":
            d = t / math.hypot(w, h)
            s.tan_x, s.tan_y = d * w, d * h
        else:
            raise self.err(e, f"fov_axis {axis}")
        for k in ("focal_length", "principal_point_offset_x", "principal_point_offset_y"):
            if k in p:
                raise self.err(e, f"{k} is not supported")


def load(xml, width, height):
    return Parser(xml, width, height).parse()


def write_exr(path, img):
    """Linear RGB float32 EXR, top row first (the OpenEXR package)."""
    hdr = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    with OpenEXR.File(hdr, {"RGB": np.ascontiguousarray(img[..., :3].astype(np.float32))}) as f:
        f.write(path)
