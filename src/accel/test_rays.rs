//! The back ends' hit tests' shared inputs (tests only): a fixed-seed LCG, scenes loaded from the
//! repository, the ray stream every tree is compared on, and the random soup and spheres.

use crate::math::Vec3;
use crate::scene::Scene;

/// A small LCG for the tests' rays (fixed seed).
pub(super) struct Lcg(pub(super) u64);

impl Lcg {
    pub(super) fn f(&mut self) -> f32 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }
    pub(super) fn v(&mut self, lo: Vec3, hi: Vec3) -> Vec3 {
        lo + (hi - lo) * Vec3::new(self.f(), self.f(), self.f())
    }
}

/// A scene of the repository, by its path from the crate root.
pub(super) fn load(path: &str) -> Scene {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    crate::scene::load(&root.join(path)).expect("scene loads")
}

/// `n` rays `(i, o, d, tmax)` over `scene` (primitive boxes `b`): from random points of the
/// scene's box (grown 10%), from points on its triangles (a surface's own hit at t ≈ 0), along
/// random, axis-parallel and −0.0-component directions, with tmax 0, ∞, `f32::MAX` and random.
pub(super) fn rays<'a>(
    scene: &'a Scene,
    b: &[(Vec3, Vec3)],
    n: usize,
    seed: u64,
) -> impl Iterator<Item = (usize, Vec3, Vec3, f32)> + 'a {
    let (lo, hi) =
        b.iter().fold((Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)), |(l, h), &(a, c)| (l.min(a), h.max(c)));
    let (lo, hi) = (lo - (hi - lo) * 0.1, hi + (hi - lo) * 0.1);
    let mut r = Lcg(seed);
    (0..n).map(move |i| {
        let o = if i % 4 == 1 && scene.ntri() > 0 {
            let t = &scene.triangles[(r.f() * scene.ntri() as f32) as usize % scene.ntri() as usize];
            let (u, v) = (r.f(), r.f());
            let (u, v) = if u + v > 1.0 { (1.0 - u, 1.0 - v) } else { (u, v) };
            t.p[0] + u * (t.p[1] - t.p[0]) + v * (t.p[2] - t.p[0])
        } else {
            r.v(lo, hi)
        };
        let mut d = r.v(Vec3::splat(-1.0), Vec3::ONE).normalize_or(Vec3::Z);
        match i % 16 {
            3 => d = [Vec3::X, Vec3::Y, Vec3::Z, -Vec3::X, -Vec3::Y, -Vec3::Z][(i / 16) % 6],
            5 => d = Vec3::new(-0.0, d.y, d.z).normalize(),
            7 => d = Vec3::new(d.x, -0.0, -0.0).normalize_or(-Vec3::X),
            9 => d = Vec3::new(-0.0, -1.0, -0.0),
            _ => {}
        }
        let tmax = match i % 5 {
            0 => f32::INFINITY,
            1 => 0.0,
            2 => r.f() * (hi - lo).length(),
            _ => f32::MAX,
        };
        (i, o, d, tmax)
    })
}

/// The cornell box with 200 random spheres added, and the same with a 20k random-triangle soup
/// (overlapping, slivers, coincident copies) in place of its triangles.
pub(super) fn spheres_and_soup() -> (Scene, Scene) {
    let mut scene = load("scenes/cornell-box.toml");
    let mut r = Lcg(3);
    let t0 = scene.triangles[0].clone();
    let mut soup = scene.triangles.clone();
    for k in 0..20_000 {
        let c = r.v(Vec3::splat(-2.0), Vec3::splat(2.0));
        let s = if k % 10 == 0 { 0.001 } else { 0.2 * r.f() };
        let mut t = t0.clone();
        t.p = [c + r.v(-Vec3::splat(s), Vec3::splat(s)), c + r.v(-Vec3::splat(s), Vec3::splat(s)), c];
        if k % 50 == 1 {
            t.p = soup[soup.len() - 1].p; // a coincident copy
        }
        soup.push(t);
    }
    let s0 = scene.spheres[0].clone();
    for _ in 0..200 {
        let mut sp = s0.clone();
        sp.center = r.v(Vec3::splat(-2.0), Vec3::splat(2.0));
        sp.radius = 0.01 + 0.2 * r.f();
        scene.spheres.push(sp);
    }
    let mut with_soup = scene.clone();
    with_soup.triangles = soup;
    (scene, with_soup)
}
