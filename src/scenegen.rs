//! Deterministic generators for the meshes of the `ring` and `figurines` scenes.
//!
//! * [`ring_obj`]: the metal band of the cardioid-caustic scene (the paper's Fig. 5): inner
//!   radius 1.0, outer radius 1.05, height 0.4, 2048 flat segments with an inner wall, an outer
//!   wall and a top rim (no bottom, it stands on the floor): exactly 12,288 triangles and 8,192
//!   vertices. Geometric normals `(v1-v0)×(v2-v0)` point out of the metal.
//! * [`figurines_objs`]: the stand-ins for the scanned models of the paper's Fig. 3, in metres
//!   and in local coordinates (resting on y = 0, centred on the y axis; the scene file places
//!   them): `knot.obj` (a (2,3) torus-knot tube, 131,072 triangles, smooth), `blob.obj` (a
//!   displaced cube-sphere, 120,000 triangles, smooth), `tin.obj` (a box, 12 triangles),
//!   `table.obj` (top + 4 legs, 60 triangles) and `hall.obj` (walls and ceiling of the
//!   40×40×8 m hall facing inwards, 10 triangles; the floor is a quad in the scene file).
//!   Knot, blob, tin and table are closed, consistently oriented two-manifolds with outward
//!   normals; the smooth meshes carry unit `vn` normals and faces `f a//a b//b c//c`.
//!
//! Output is byte-identical between calls: only fixed-order loops and fixed-precision float
//! formatting (`-0` is written as `0`) are used.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

#[rustfmt::skip]
mod v3 {
    //! Tiny `[f64; 3]` vector helpers.
    pub(super) type V3 = [f64; 3];
    pub(super) fn add(a: V3, b: V3) -> V3 { [a[0] + b[0], a[1] + b[1], a[2] + b[2]] }
    pub(super) fn sub(a: V3, b: V3) -> V3 { [a[0] - b[0], a[1] - b[1], a[2] - b[2]] }
    pub(super) fn mul(a: V3, s: f64) -> V3 { [a[0] * s, a[1] * s, a[2] * s] }
    pub(super) fn dot(a: V3, b: V3) -> f64 { a[0] * b[0] + a[1] * b[1] + a[2] * b[2] }
    pub(super) fn cross(a: V3, b: V3) -> V3 {
        [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
    }
    /// Unit vector; +y for the zero vector (never NaN).
    pub(super) fn normalize(a: V3) -> V3 {
        let l = dot(a, a).sqrt();
        if l > 0.0 { mul(a, 1.0 / l) } else { [0.0, 1.0, 0.0] }
    }
}
use v3::*;

/// Triangle mesh under construction; `nrm` is either empty (flat) or one unit normal per position.
#[derive(Default)]
struct Mesh {
    pos: Vec<V3>,
    nrm: Vec<V3>,
    tri: Vec<[u32; 3]>,
}

impl Mesh {
    fn vert(&mut self, p: V3) -> u32 {
        self.pos.push(p);
        (self.pos.len() - 1) as u32
    }
    /// Quad a,b,c,d (counter-clockwise seen from the side its normal points to).
    fn quad(&mut self, a: u32, b: u32, c: u32, d: u32) {
        self.tri.push([a, b, c]);
        self.tri.push([a, c, d]);
    }
    /// Geometric (unnormalised) normal of triangle `t`.
    fn face_normal(&self, t: [u32; 3]) -> V3 {
        let [a, b, c] = t.map(|i| self.pos[i as usize]);
        cross(sub(b, a), sub(c, a))
    }
    /// Area-weighted vertex normals from the faces.
    fn area_weighted_normals(&mut self) {
        let mut n = vec![[0.0; 3]; self.pos.len()];
        for &t in &self.tri {
            let f = self.face_normal(t);
            for i in t {
                n[i as usize] = add(n[i as usize], f);
            }
        }
        self.nrm = n.into_iter().map(normalize).collect();
    }
    /// Moves the mesh so its lowest point is at y = 0.
    fn rest_on_ground(&mut self) {
        let min_y = self.pos.iter().map(|p| p[1]).fold(f64::INFINITY, f64::min);
        for p in &mut self.pos {
            p[1] -= min_y;
        }
    }
    /// OBJ text: header comment, `v`, optional `vn`, then 1-based faces.
    fn to_obj(&self, name: &str, prec: usize) -> String {
        let mut s = String::with_capacity(self.pos.len() * 64 + self.tri.len() * 48);
        let _ = writeln!(s, "# forecast scenegen: {name}, {} vertices, {} triangles", self.pos.len(), self.tri.len());
        let _ = writeln!(s, "o {name}");
        for (tag, list) in [("v", &self.pos), ("vn", &self.nrm)] {
            for p in list.iter() {
                let _ = writeln!(s, "{tag} {} {} {}", fmt(p[0], prec), fmt(p[1], prec), fmt(p[2], prec));
            }
        }
        let smooth = !self.nrm.is_empty();
        for t in &self.tri {
            let [a, b, c] = t.map(|i| i + 1);
            if smooth {
                let _ = writeln!(s, "f {a}//{a} {b}//{b} {c}//{c}");
            } else {
                let _ = writeln!(s, "f {a} {b} {c}");
            }
        }
        s
    }
}

/// Fixed-precision float with `-0.000…` normalised to `0.000…`.
fn fmt(x: f64, prec: usize) -> String {
    let s = format!("{:.*}", prec, x);
    if s.starts_with('-') && s[1..].bytes().all(|b| b == b'0' || b == b'.') {
        s[1..].to_string()
    } else {
        s
    }
}

/// Segments around the ring.
const RING_SEGMENTS: usize = 2048;
/// Ring inner radius, outer radius and height.
const RING_R0: f64 = 1.0;
const RING_R1: f64 = 1.05;
const RING_H: f64 = 0.4;

fn ring_mesh() -> Mesh {
    let n = RING_SEGMENTS;
    let mut m = Mesh::default();
    // Per angle i: inner bottom, inner top, outer bottom, outer top = 4i..4i+3.
    for i in 0..n {
        let th = 2.0 * std::f64::consts::PI * i as f64 / n as f64;
        let (s, c) = th.sin_cos();
        for (r, y) in [(RING_R0, 0.0), (RING_R0, RING_H), (RING_R1, 0.0), (RING_R1, RING_H)] {
            m.vert([r * c, y, r * s]);
        }
    }
    for i in 0..n {
        let a = 4 * i as u32;
        let b = 4 * ((i + 1) % n) as u32;
        let (ib0, it0, ob0, ot0) = (a, a + 1, a + 2, a + 3);
        let (ib1, it1, ob1, ot1) = (b, b + 1, b + 2, b + 3);
        // tangent t = dθ direction; t × y = -e_r (towards the axis), y × t = +e_r, t × e_r = +y.
        m.quad(ib0, ib1, it1, it0); // inner wall, normal towards the axis
        m.quad(ob0, ot0, ot1, ob1); // outer wall, normal away from the axis
        m.quad(it0, it1, ot1, ot0); // top rim, normal +y
    }
    m
}

/// The ring scene's mesh (OBJ text): 12,288 flat triangles, 8,192 vertices, 7 decimals.
pub fn ring_obj() -> String {
    ring_mesh().to_obj("ring", 7)
}

/// Torus-knot parameters: (p, q) = (2, 3), curve scale, tube radius, samples along / around.
const KNOT_SCALE: f64 = 0.05;
const KNOT_TUBE: f64 = 0.03;
const KNOT_ALONG: usize = 1024;
const KNOT_AROUND: usize = 64;

/// Centre line of the (2,3) torus knot in the vertical x-y plane (unit parameter t ∈ [0, 2π)).
fn knot_curve(t: f64) -> V3 {
    let r = 2.0 + (3.0 * t).cos();
    mul([r * (2.0 * t).cos(), r * (2.0 * t).sin(), -(3.0 * t).sin()], KNOT_SCALE)
}
fn knot_tangent(t: f64) -> V3 {
    let r = 2.0 + (3.0 * t).cos();
    let dr = -3.0 * (3.0 * t).sin();
    normalize([
        dr * (2.0 * t).cos() - 2.0 * r * (2.0 * t).sin(),
        dr * (2.0 * t).sin() + 2.0 * r * (2.0 * t).cos(),
        -3.0 * (3.0 * t).cos(),
    ])
}

fn knot_mesh() -> Mesh {
    let (n, k) = (KNOT_ALONG, KNOT_AROUND);
    let ts: Vec<f64> = (0..n).map(|i| 2.0 * std::f64::consts::PI * i as f64 / n as f64).collect();
    let tan: Vec<V3> = ts.iter().map(|&t| knot_tangent(t)).collect();
    // Parallel-transport frames, then spread the closing twist evenly so the tube closes.
    let project = |v: V3, t: V3| normalize(sub(v, mul(t, dot(v, t))));
    let mut nor = Vec::with_capacity(n);
    nor.push(project([0.0, 0.0, 1.0], tan[0]));
    for i in 1..n {
        let prev = nor[i - 1];
        nor.push(project(prev, tan[i]));
    }
    let end = project(nor[n - 1], tan[0]);
    let twist = dot(cross(nor[0], end), tan[0]).atan2(dot(nor[0], end));
    let mut m = Mesh::default();
    for i in 0..n {
        let phi = -twist * i as f64 / n as f64;
        let (s, c) = phi.sin_cos();
        let b0 = cross(tan[i], nor[i]);
        let nn = add(mul(nor[i], c), mul(b0, s)); // rotate the normal about the tangent
        let bb = cross(tan[i], nn);
        let centre = knot_curve(ts[i]);
        for j in 0..k {
            let a = 2.0 * std::f64::consts::PI * j as f64 / k as f64;
            let dir = normalize(add(mul(nn, a.cos()), mul(bb, a.sin())));
            m.vert(add(centre, mul(dir, KNOT_TUBE)));
            m.nrm.push(dir);
        }
    }
    let id = |i: usize, j: usize| ((i % n) * k + (j % k)) as u32;
    for i in 0..n {
        for j in 0..k {
            // d/dj × d/di points outwards (around × along).
            m.quad(id(i, j), id(i, j + 1), id(i + 1, j + 1), id(i + 1, j));
        }
    }
    m.rest_on_ground();
    m
}

/// Cube faces: (axis, sign, u axis, v axis) with e_u × e_v = sign · e_axis.
const CUBE_FACES: [(usize, f64, usize, usize); 6] =
    [(0, 1.0, 1, 2), (0, -1.0, 2, 1), (1, 1.0, 2, 0), (1, -1.0, 0, 2), (2, 1.0, 0, 1), (2, -1.0, 1, 0)];

/// Blob: radius, cube-sphere grid cells per face edge (6·2·N² triangles).
const BLOB_RADIUS: f64 = 0.15;
const BLOB_GRID: usize = 100;

/// Smooth low-frequency radial scale of the blob (within [0.79, 1.21]).
fn blob_radius(d: V3) -> f64 {
    let f = 0.10 * (3.0 * d[0] + 0.5).sin() * (2.0 * d[1] - 0.3).cos()
        + 0.06 * (2.0 * d[2] + 1.5 * d[0] + 0.4).sin()
        + 0.05 * (3.0 * d[1] + d[2]).cos();
    BLOB_RADIUS * (1.0 + f)
}

fn blob_mesh() -> Mesh {
    let n = BLOB_GRID;
    let mut m = Mesh::default();
    // Shared lattice vertices on the cube surface keep the mesh watertight.
    let mut index: std::collections::HashMap<[usize; 3], u32> = std::collections::HashMap::new();
    for &(ax, sign, ua, va) in &CUBE_FACES {
        let mut ids = vec![0u32; (n + 1) * (n + 1)];
        for j in 0..=n {
            for i in 0..=n {
                let mut key = [0usize; 3];
                key[ax] = if sign > 0.0 { n } else { 0 };
                key[ua] = i;
                key[va] = j;
                let id = *index.entry(key).or_insert_with(|| {
                    // Equal-angle warp of the cube lattice for evenly sized triangles.
                    let c = key.map(|q| (std::f64::consts::FRAC_PI_4 * (2.0 * q as f64 / n as f64 - 1.0)).tan());
                    let d = normalize(c);
                    m.pos.push(mul(d, blob_radius(d)));
                    (m.pos.len() - 1) as u32
                });
                ids[j * (n + 1) + i] = id;
            }
        }
        for j in 0..n {
            for i in 0..n {
                let q = |a: usize, b: usize| ids[b * (n + 1) + a];
                m.quad(q(i, j), q(i + 1, j), q(i + 1, j + 1), q(i, j + 1));
            }
        }
    }
    m.area_weighted_normals();
    m.rest_on_ground();
    m
}

/// Appends an axis-aligned box; normals outward, or inward when `inward` (faces in `skip` omitted).
fn add_box(m: &mut Mesh, lo: V3, hi: V3, inward: bool, skip: &[(usize, f64)]) {
    for &(ax, sign, ua, va) in &CUBE_FACES {
        if skip.contains(&(ax, sign)) {
            continue;
        }
        let corner = |su: bool, sv: bool| {
            let mut p = [0.0; 3];
            p[ax] = if sign > 0.0 { hi[ax] } else { lo[ax] };
            p[ua] = if su { hi[ua] } else { lo[ua] };
            p[va] = if sv { hi[va] } else { lo[va] };
            p
        };
        let ids =
            [corner(false, false), corner(true, false), corner(true, true), corner(false, true)].map(|p| m.vert(p));
        if inward {
            m.quad(ids[0], ids[3], ids[2], ids[1]);
        } else {
            m.quad(ids[0], ids[1], ids[2], ids[3]);
        }
    }
}

fn tin_mesh() -> Mesh {
    let mut m = Mesh::default();
    add_box(&mut m, [-0.1, 0.0, -0.065], [0.1, 0.09, 0.065], false, &[]);
    m
}

/// Table top height (the table is modelled in world coordinates).
const TABLE_TOP: f64 = 0.8;

fn table_mesh() -> Mesh {
    let mut m = Mesh::default();
    add_box(&mut m, [-1.0, TABLE_TOP - 0.04, -0.5], [1.0, TABLE_TOP, 0.5], false, &[]);
    for (x, z) in [(-0.9, -0.4), (0.9, -0.4), (-0.9, 0.4), (0.9, 0.4)] {
        add_box(&mut m, [x - 0.03, 0.0, z - 0.03], [x + 0.03, TABLE_TOP - 0.04, z + 0.03], false, &[]);
    }
    m
}

fn hall_mesh() -> Mesh {
    let mut m = Mesh::default();
    add_box(&mut m, [-20.0, 0.0, -20.0], [20.0, 8.0, 20.0], true, &[(1, -1.0)]);
    m
}

/// The figurines scene's meshes: (file name relative to `scenes/figurines/`, OBJ text), in the
/// order knot, blob, tin, table, hall. Smooth meshes use 5 decimals, flat ones 6.
pub fn figurines_objs() -> Vec<(String, String)> {
    vec![
        ("knot.obj".to_string(), knot_mesh().to_obj("knot", 5)),
        ("blob.obj".to_string(), blob_mesh().to_obj("blob", 5)),
        ("tin.obj".to_string(), tin_mesh().to_obj("tin", 6)),
        ("table.obj".to_string(), table_mesh().to_obj("table", 6)),
        ("hall.obj".to_string(), hall_mesh().to_obj("hall", 6)),
    ]
}

/// Water grid: cells per side, side length (m), mean height and wave amplitude (m).
const WATER_CELLS: usize = 256;
const WATER_SIDE: f64 = 2.0;
const WATER_Y: f64 = 0.5;
const WATER_AMP: f64 = 0.012;

/// The water surface's height at `(x, z)`: a sum of four fixed sine waves.
fn water_height(x: f64, z: f64) -> f64 {
    let waves = [(7.0, 3.0, 0.0, 1.0), (-4.0, 9.0, 1.3, 0.6), (11.0, -6.0, 2.1, 0.4), (2.0, 15.0, 0.7, 0.25)];
    WATER_Y + WATER_AMP * waves.iter().map(|&(kx, kz, ph, a)| a * (kx * x + kz * z + ph).sin()).sum::<f64>()
}

fn water_mesh() -> Mesh {
    let n = WATER_CELLS;
    let mut m = Mesh::default();
    for j in 0..=n {
        for i in 0..=n {
            let (x, z) = (WATER_SIDE * (i as f64 / n as f64 - 0.5), WATER_SIDE * (j as f64 / n as f64 - 0.5));
            m.vert([x, water_height(x, z), z]);
        }
    }
    let at = |i: usize, j: usize| (j * (n + 1) + i) as u32;
    for j in 0..n {
        for i in 0..n {
            // (x, z) winding seen from +y: normals up
            m.quad(at(i, j), at(i, j + 1), at(i + 1, j + 1), at(i + 1, j));
        }
    }
    m.area_weighted_normals();
    m
}

/// The `water-caustic` stress scene's water surface (OBJ text): a 2 × 2 m height field of
/// 131,072 smooth triangles (66,049 vertices, 5 decimals), normals up.
pub fn water_obj() -> String {
    water_mesh().to_obj("water", 5)
}

/// Writes `contents` to `path` via `path.tmp` and a rename.
fn write_atomic(path: &Path, contents: &str) -> std::io::Result<()> {
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(".tmp");
    let tmp = PathBuf::from(tmp);
    std::fs::write(&tmp, contents)?;
    std::fs::rename(&tmp, path)
}

/// Writes `ring.obj`, `water.obj` and `figurines/*.obj` under `scenes_dir` (creating `figurines/`), each
/// atomically (`path.tmp`, then rename); returns the paths written.
pub fn write_all(scenes_dir: &Path) -> std::io::Result<Vec<PathBuf>> {
    let mut written = Vec::new();
    std::fs::create_dir_all(scenes_dir.join("figurines"))?;
    let ring = scenes_dir.join("ring.obj");
    write_atomic(&ring, &ring_obj())?;
    written.push(ring);
    let water = scenes_dir.join("water.obj");
    write_atomic(&water, &water_obj())?;
    written.push(water);
    for (name, text) in figurines_objs() {
        let p = scenes_dir.join("figurines").join(name);
        write_atomic(&p, &text)?;
        written.push(p);
    }
    Ok(written)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;

    /// Parses our own OBJ output back: positions, normals, 0-based triangles.
    fn parse(obj: &str) -> Mesh {
        let mut m = Mesh::default();
        let num = |w: Option<&str>| w.unwrap().parse::<f64>().unwrap();
        for line in obj.lines() {
            let mut w = line.split_whitespace();
            match w.next() {
                Some("v") => m.pos.push([num(w.next()), num(w.next()), num(w.next())]),
                Some("vn") => m.nrm.push([num(w.next()), num(w.next()), num(w.next())]),
                Some("f") => {
                    let ids: Vec<u32> = w.map(|s| s.split('/').next().unwrap().parse::<u32>().unwrap() - 1).collect();
                    assert_eq!(ids.len(), 3);
                    m.tri.push([ids[0], ids[1], ids[2]]);
                }
                _ => {}
            }
        }
        m
    }

    /// Common checks: indices in range, no degenerate triangles, unit finite normals that
    /// agree with the winding.
    fn check(m: &Mesh, min_area: f64) {
        assert!(m.nrm.is_empty() || m.nrm.len() == m.pos.len());
        for p in &m.pos {
            assert!(p.iter().all(|x| x.is_finite()));
        }
        for n in &m.nrm {
            assert!((dot(*n, *n).sqrt() - 1.0).abs() < 1e-4, "normal {n:?}");
        }
        for &t in &m.tri {
            assert!(t.iter().all(|&i| (i as usize) < m.pos.len()));
            let f = m.face_normal(t);
            let area = 0.5 * dot(f, f).sqrt();
            assert!(area > min_area, "degenerate triangle {t:?}: area {area}");
            if !m.nrm.is_empty() {
                let avg = t.iter().fold([0.0; 3], |a, &i| add(a, m.nrm[i as usize]));
                assert!(dot(normalize(f), normalize(avg)) > 0.5, "winding disagrees with vn at {t:?}");
            }
        }
    }

    /// After welding equal positions, every directed edge occurs once and its reverse once:
    /// closed and consistently oriented.
    fn assert_closed(m: &Mesh) {
        let mut weld: HashMap<[u64; 3], u32> = HashMap::new();
        let id: Vec<u32> = m
            .pos
            .iter()
            .map(|p| {
                let n = weld.len() as u32;
                *weld.entry(p.map(f64::to_bits)).or_insert(n)
            })
            .collect();
        let mut edges: HashMap<(u32, u32), u32> = HashMap::new();
        for t in &m.tri {
            for k in 0..3 {
                *edges.entry((id[t[k] as usize], id[t[(k + 1) % 3] as usize])).or_default() += 1;
            }
        }
        for (&(a, b), &c) in &edges {
            assert_eq!(c, 1, "edge {a}-{b} used {c} times");
            assert_eq!(edges.get(&(b, a)), Some(&1), "edge {a}-{b} has no twin");
        }
    }

    /// Signed volume (positive for outward-oriented closed meshes).
    fn volume(m: &Mesh) -> f64 {
        let p = |i: u32| m.pos[i as usize];
        m.tri.iter().map(|t| dot(p(t[0]), cross(p(t[1]), p(t[2]))) / 6.0).sum()
    }

    #[test]
    fn ring_counts_and_orientation() {
        let obj = ring_obj();
        assert_eq!(obj, ring_obj(), "not deterministic");
        let m = parse(&obj);
        assert_eq!(m.tri.len(), 12_288);
        assert_eq!(m.pos.len(), 8_192);
        assert!(m.nrm.is_empty());
        check(&m, 1e-5);
        let (mut inner, mut outer, mut top) = (0, 0, 0);
        for &t in &m.tri {
            let n = normalize(m.face_normal(t));
            let c = mul(t.iter().fold([0.0; 3], |a, &i| add(a, m.pos[i as usize])), 1.0 / 3.0);
            let r = (c[0] * c[0] + c[2] * c[2]).sqrt();
            let radial = dot(n, normalize([c[0], 0.0, c[2]]));
            if (c[1] - RING_H).abs() < 1e-9 {
                assert!(n[1] > 0.999999);
                assert!(r > RING_R0 && r < RING_R1);
                top += 1;
            } else if r < 0.5 * (RING_R0 + RING_R1) {
                assert!(radial < -0.999999, "inner wall must face the axis");
                inner += 1;
            } else {
                assert!(radial > 0.999999, "outer wall must face away");
                outer += 1;
            }
        }
        assert_eq!((inner, outer, top), (4096, 4096, 4096));
        let ymax = m.pos.iter().map(|p| p[1]).fold(0.0, f64::max);
        assert_eq!(ymax, RING_H);
    }

    #[test]
    fn figurines_counts_determinism_and_watertightness() {
        let a = figurines_objs();
        let b = figurines_objs();
        assert_eq!(a, b, "not deterministic");
        let names: Vec<&str> = a.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, ["knot.obj", "blob.obj", "tin.obj", "table.obj", "hall.obj"]);
        let meshes: Vec<Mesh> = a.iter().map(|(_, t)| parse(t)).collect();
        let counts: Vec<usize> = meshes.iter().map(|m| m.tri.len()).collect();
        assert_eq!(counts, [131_072, 120_000, 12, 60, 10]);
        assert!(counts.iter().sum::<usize>() >= 250_000);
        for (i, m) in meshes.iter().enumerate() {
            check(m, if i < 2 { 1e-8 } else { 1e-4 });
            if i < 4 {
                assert_closed(m);
                assert!(volume(m) > 0.0, "{} not outward", names[i]);
            }
        }
        assert!(!meshes[0].nrm.is_empty() && !meshes[1].nrm.is_empty());
        assert!(meshes[2..].iter().all(|m| m.nrm.is_empty()));
        // Figurines rest on y = 0 and are tiny compared with the hall.
        for m in &meshes[..3] {
            let (mut lo, mut hi) = ([f64::MAX; 3], [f64::MIN; 3]);
            for p in &m.pos {
                (lo, hi) = ([0, 1, 2].map(|k| lo[k].min(p[k])), [0, 1, 2].map(|k| hi[k].max(p[k])));
            }
            assert!(lo[1].abs() < 1e-5);
            assert!((0..3).all(|k| hi[k] - lo[k] < 0.45 && hi[k] - lo[k] > 0.05));
        }
        // The hall faces inwards: every face normal points toward the hall's centre.
        let h = &meshes[4];
        for &t in &h.tri {
            let c = h.pos[t[0] as usize];
            assert!(dot(h.face_normal(t), sub([0.0, 4.0, 0.0], c)) > 0.0);
        }
    }

    #[test]
    fn blob_is_star_shaped_outward() {
        let m = blob_mesh();
        let lo = m.pos.iter().map(|p| p[1]).fold(f64::MAX, f64::min);
        let hi = m.pos.iter().map(|p| p[1]).fold(f64::MIN, f64::max);
        let centre = [0.0, 0.5 * (lo + hi), 0.0];
        for &t in &m.tri {
            let c = sub(m.pos[t[0] as usize], centre);
            assert!(dot(normalize(m.face_normal(t)), normalize(c)) > 0.3);
        }
    }

    #[test]
    fn knot_tube_does_not_self_intersect() {
        // Centre-line points more than π·tube apart along the curve must stay > 2.2·tube apart
        // in space, and the curvature radius must exceed the tube radius.
        let n = 1440;
        let pts: Vec<V3> = (0..n).map(|i| knot_curve(2.0 * std::f64::consts::PI * i as f64 / n as f64)).collect();
        let mut arc = vec![0.0];
        for i in 1..=n {
            let d = sub(pts[i % n], pts[i - 1]);
            arc.push(arc[i - 1] + dot(d, d).sqrt());
        }
        let total = arc[n];
        let mut min_d = f64::MAX;
        for i in 0..n {
            for j in i + 1..n {
                let s = arc[j] - arc[i];
                if s.min(total - s) > std::f64::consts::PI * KNOT_TUBE {
                    let d = sub(pts[i], pts[j]);
                    min_d = min_d.min(dot(d, d).sqrt());
                }
            }
            let (a, b, c) = (pts[(i + n - 1) % n], pts[i], pts[(i + 1) % n]);
            let (ab, bc, ac) = (sub(b, a), sub(c, b), sub(c, a));
            let twice_area = dot(cross(ab, ac), cross(ab, ac)).sqrt();
            let radius = (dot(ab, ab) * dot(bc, bc) * dot(ac, ac)).sqrt() / (2.0 * twice_area);
            assert!(radius > 2.0 * KNOT_TUBE, "curvature radius {radius}");
        }
        assert!(min_d > 2.2 * KNOT_TUBE, "strands {min_d} apart, tube radius {KNOT_TUBE}");
        // The twist-corrected frames close the tube: no stretched edges at the seam.
        let m = knot_mesh();
        assert_closed(&m);
        for t in &m.tri {
            for k in 0..3 {
                let d = sub(m.pos[t[k] as usize], m.pos[t[(k + 1) % 3] as usize]);
                assert!(dot(d, d).sqrt() < 0.006, "stretched edge in {t:?}");
            }
        }
    }

    #[test]
    fn fmt_is_fixed_and_has_no_negative_zero() {
        assert_eq!(fmt(-0.0000001, 6), "0.000000");
        assert_eq!(fmt(-0.5, 3), "-0.500");
        assert_eq!(fmt(1.0, 5), "1.00000");
    }

    #[test]
    fn write_all_writes_every_file() {
        let dir = std::env::temp_dir().join(format!("scenegen-test-{}", std::process::id()));
        let paths = write_all(&dir).unwrap();
        assert_eq!(paths.len(), 7);
        assert_eq!(std::fs::read_to_string(&paths[0]).unwrap(), ring_obj());
        for p in &paths {
            assert!(p.exists());
            assert!(!p.with_extension("obj.tmp").exists());
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
