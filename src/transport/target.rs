//! The targeted emission's directions [BAJ08 §3.2]: uniform over the union of the cones that a
//! few spheres around the Dirac objects subtend from the light point (`Scene::dirac_spheres`).
//!
//! From a light point `y` outside sphere `k` (centre `c_k`, radius `r_k`), the sphere subtends
//! the cone of half-angle `θ_k`, `cos θ_k = √(1 − r_k²/|c_k − y|²)`, solid angle
//! `Ω_k = 2π(1 − cos θ_k)`. Cone `k` is picked with probability `Ω_k/Ω` (`Ω = Σ Ω_k`) and a
//! direction drawn uniformly inside it, so
//!
//!   `pdf_w(ω) = Σ_k (Ω_k/Ω) · 1[ω ∈ cone_k]/Ω_k = #{k : ω ∈ cone_k} / Ω`,
//!
//! uniform over the union where the cones do not overlap. One sphere is BAJ08's single cone, bit
//! for bit. When `y` lies inside any sphere, [`Targets::cones`] answers `None` and the emission
//! falls back to the light's own (`Emission::sample_dir`).
//!
//! For a light at infinity (directional, environment: light along `d`, from the disk of the
//! scene's bounding sphere perpendicular to `d`) the spheres are aimed at in position instead:
//! their shadows on that plane are discs of radius `r_k`, disc `k` is picked with probability
//! `r_k²/Σ r_j²` and a point drawn uniformly in it, so `pdf_a(x) = #{k : x ∈ disc_k}/(π Σ r_j²)`
//! ([`Targets::sample_beam`], [`Targets::beam_pdf`]).
//!
//! Invariants: `1 ≤ n ≤ MAX_TARGETS` spheres with radius > 0; the pdf of a sampled direction
//! counts its own cone even where rounding puts it on that cone's boundary.

use crate::math::{Frame, Vec3};
pub use crate::scene::MAX_TARGETS;
use std::f32::consts::PI;

/// The spheres aimed at (at most [`MAX_TARGETS`]; a `Copy` value, as `Emission` is).
#[derive(Clone, Copy, PartialEq)]
pub struct Targets {
    spheres: [(Vec3, f32); MAX_TARGETS],
    n: usize,
}

/// The cones of a [`Targets`] seen from one light point.
pub struct Cones {
    /// `c_k − y`, its length and `cos θ_k` of each cone.
    cone: [(Vec3, f32, f32); MAX_TARGETS],
    /// Each cone's solid angle `Ω_k`.
    omega: [f32; MAX_TARGETS],
    /// `Ω = Σ Ω_k`.
    total: f32,
    n: usize,
}

impl std::fmt::Debug for Targets {
    /// `Targets [(centre, radius), …]`, the spheres in use only (the JSON reports show it).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_tuple("Targets").field(&self.spheres()).finish()
    }
}

impl Targets {
    /// The target of `spheres` (`None` when empty). Panics on more than [`MAX_TARGETS`] or a
    /// radius that is not positive (the callers build them so).
    pub fn new(spheres: &[(Vec3, f32)]) -> Option<Targets> {
        assert!(spheres.len() <= MAX_TARGETS && spheres.iter().all(|s| s.1 > 0.0), "bad target spheres");
        let mut t = Targets { spheres: [(Vec3::ZERO, 0.0); MAX_TARGETS], n: spheres.len() };
        t.spheres[..t.n].copy_from_slice(spheres);
        (t.n > 0).then_some(t)
    }

    /// The spheres `(centre, radius)`.
    pub fn spheres(&self) -> &[(Vec3, f32)] {
        &self.spheres[..self.n]
    }

    /// The cones seen from `y`, or `None` when `y` is inside (or on) a sphere.
    #[inline]
    pub fn cones(&self, y: Vec3) -> Option<Cones> {
        let mut c =
            Cones { cone: [(Vec3::ZERO, 0.0, 0.0); MAX_TARGETS], omega: [0.0; MAX_TARGETS], total: 0.0, n: self.n };
        for (k, &(center, radius)) in self.spheres().iter().enumerate() {
            let to_c = center - y;
            let dist2 = to_c.length_squared();
            if dist2 <= radius * radius * 1.0001 {
                return None;
            }
            let cos_max = (1.0 - radius * radius / dist2).max(0.0).sqrt();
            let dist = dist2.sqrt();
            c.cone[k] = (to_c, dist, cos_max);
            c.omega[k] = 2.0 * PI * (1.0 - cos_max);
            c.total += c.omega[k];
        }
        Some(c)
    }
}

impl Targets {
    /// A point of the plane through `o` perpendicular to the unit `d` inside the shadow of a
    /// sphere along `d`, and its area pdf (module docs).
    #[inline]
    pub fn sample_beam(&self, o: Vec3, d: Vec3, u: [f32; 2]) -> (Vec3, f32) {
        let total: f32 = self.spheres().iter().map(|s| s.1 * s.1).sum();
        let mut x = u[0] * total;
        let mut k = self.n - 1;
        for (j, s) in self.spheres().iter().enumerate() {
            if x < s.1 * s.1 || j == self.n - 1 {
                k = j;
                break;
            }
            x -= s.1 * s.1;
        }
        let (c, r) = self.spheres[k];
        let u0 = (x / (r * r)).clamp(0.0, 1.0);
        let disk = crate::sampling::warp::sample_concentric_disk([u0, u[1]]);
        let f = Frame::from_normal(d);
        let centre = c - d * d.dot(c - o);
        let p = centre + (f.s * disk.x + f.t * disk.y) * r;
        (p, self.beam_pdf(o, d, p))
    }

    /// The area pdf with which [`Targets::sample_beam`] draws the point where the line through
    /// `p` along `d` meets the plane through `o` perpendicular to `d` (0 outside every shadow).
    #[inline]
    pub fn beam_pdf(&self, o: Vec3, d: Vec3, p: Vec3) -> f32 {
        let total: f32 = self.spheres().iter().map(|s| s.1 * s.1).sum();
        let q = p - d * d.dot(p - o);
        let count = self
            .spheres()
            .iter()
            .filter(|&&(c, r)| {
                let centre = c - d * d.dot(c - o);
                (q - centre).length_squared() <= r * r * 1.0001
            })
            .count();
        count as f32 / (PI * total)
    }
}

impl Cones {
    /// A direction and its pdf `pdf_w` (the module's formula); `None` when the cones are too
    /// narrow for f32 (a zero solid angle).
    #[inline]
    pub fn sample(&self, u: [f32; 2]) -> Option<(Vec3, f32)> {
        let (k, u0) = self.pick(u[0]);
        let (to_c, dist, cos_max) = self.cone[k];
        // uniform in cone k: cos θ uniform in [cos θ_k, 1]
        let cos_t = 1.0 - u0 * (1.0 - cos_max);
        let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
        let phi = 2.0 * PI * u[1];
        let w = Frame::from_normal(to_c / dist).to_world(Vec3::new(sin_t * phi.cos(), sin_t * phi.sin(), cos_t));
        let count = 1 + (0..self.n).filter(|&j| j != k && self.inside(j, w)).count();
        let pdf_w = count as f32 / self.total;
        (pdf_w.is_finite() && pdf_w > 0.0).then_some((w, pdf_w))
    }

    /// The pdf with which [`Cones::sample`] draws `w` (0 outside every cone).
    #[inline]
    pub fn pdf(&self, w: Vec3) -> f32 {
        let count = (0..self.n).filter(|&k| self.inside(k, w)).count();
        let pdf_w = count as f32 / self.total;
        if pdf_w.is_finite() {
            pdf_w
        } else {
            0.0
        }
    }

    /// Cone `k` with probability `Ω_k/Ω`, and `u` rescaled to [0, 1) within its interval
    /// (unchanged for one cone).
    #[inline]
    fn pick(&self, u: f32) -> (usize, f32) {
        if self.n == 1 {
            return (0, u);
        }
        let x = u * self.total;
        let mut below = 0.0;
        for k in 0..self.n - 1 {
            if x < below + self.omega[k] {
                return (k, ((x - below) / self.omega[k]).clamp(0.0, 1.0));
            }
            below += self.omega[k];
        }
        let last = self.n - 1;
        (last, ((x - below) / self.omega[last]).clamp(0.0, 1.0))
    }

    #[inline]
    fn inside(&self, k: usize, w: Vec3) -> bool {
        let (to_c, dist, cos_max) = self.cone[k];
        w.dot(to_c) >= cos_max * dist
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::rng::Rng;

    /// Two overlapping cones and one apart: the sampled directions' histogram over a fine
    /// grid of directions matches `pdf` (a Monte Carlo integral of pdf over each cell), and the
    /// pdf integrates to 1 over the sphere.
    #[test]
    fn the_cone_mixture_samples_its_pdf() {
        let t = Targets::new(&[
            (Vec3::new(0.0, 0.0, 3.0), 1.0),
            (Vec3::new(0.6, 0.0, 3.0), 0.8),
            (Vec3::new(-3.0, 1.0, 0.5), 0.5),
        ])
        .unwrap();
        let c = t.cones(Vec3::ZERO).unwrap();
        // ∫ pdf dω by uniform directions over the sphere
        let mut rng = Rng::keyed(1, crate::sampling::rng::stream::MISC, 0, 0);
        let n = 2_000_000;
        let mut integral = 0.0f64;
        for _ in 0..n {
            let w = crate::sampling::warp::sample_uniform_sphere(rng.next_2d());
            integral += c.pdf(w) as f64 * 4.0 * std::f64::consts::PI / n as f64;
        }
        assert!((integral - 1.0).abs() < 0.01, "∫ pdf = {integral}");
        // E[1/pdf(w)] over sampled w is the solid angle of the union; E[g(w)/pdf] for g = the
        // indicator of the first cone is its solid angle (unbiasedness of the pair).
        let (mut union, mut first, mut differ) = (0.0f64, 0.0f64, 0);
        for _ in 0..n {
            let (w, p) = c.sample(rng.next_2d()).unwrap();
            differ += (p != c.pdf(w)) as usize; // only on a cone's boundary, by rounding
            union += 1.0 / p as f64 / n as f64;
            first += if c.inside(0, w) { 1.0 / p as f64 } else { 0.0 } / n as f64;
        }
        let omega0 = c.omega[0] as f64;
        assert!((first - omega0).abs() < 0.01 * omega0, "first cone {first} against {omega0}");
        assert!(differ < n / 10_000, "{differ} sampled pdfs differ from pdf()");
        assert!(union < c.total as f64 && union > c.omega[0] as f64 + c.omega[2] as f64, "union {union}");
    }

    /// The shadows' sampler: its pdf integrates to 1 over the plane and matches the samples'
    /// (`E[1/pdf]` is the union's area, `E[1/pdf · 1[disc 0]]` disc 0's).
    #[test]
    fn the_beam_samples_its_pdf() {
        let t = Targets::new(&[(Vec3::new(0.0, 0.0, 0.0), 1.0), (Vec3::new(0.8, 0.3, 2.0), 0.7)]).unwrap();
        let d = Vec3::new(0.2, -1.0, 0.1).normalize();
        let o = -d * 5.0;
        let f = Frame::from_normal(d);
        let mut rng = Rng::keyed(2, crate::sampling::rng::stream::MISC, 0, 0);
        let n = 1_000_000;
        let mut integral = 0.0f64;
        for _ in 0..n {
            let [a, b] = rng.next_2d();
            let p = o + (f.s * (a * 6.0 - 3.0) + f.t * (b * 6.0 - 3.0));
            integral += t.beam_pdf(o, d, p) as f64 * 36.0 / n as f64;
        }
        assert!((integral - 1.0).abs() < 0.01, "∫ pdf = {integral}");
        let (mut union, mut first) = (0.0f64, 0.0f64);
        for _ in 0..n {
            let (p, pdf) = t.sample_beam(o, d, rng.next_2d());
            assert!(pdf > 0.0 && (d.dot(p - o)).abs() < 1e-4);
            union += 1.0 / pdf as f64 / n as f64;
            first += if (p - (o + d * 0.0)).cross(d).length() <= 1.0 { 1.0 / pdf as f64 } else { 0.0 } / n as f64;
        }
        assert!((first - PI as f64).abs() < 0.01 * PI as f64, "disc 0: {first}");
        assert!(union > PI as f64 && union < PI as f64 * (1.0 + 0.49), "union {union}");
    }

    /// One sphere is the single cone of BAJ08 (solid angle 2π(1 − cos θ), pdf its inverse).
    #[test]
    fn one_sphere_is_the_single_cone() {
        let t = Targets::new(&[(Vec3::new(0.0, 5.0, 0.0), 1.0)]).unwrap();
        let c = t.cones(Vec3::ZERO).unwrap();
        let cos_max = (1.0f32 - 1.0 / 25.0).sqrt();
        assert_eq!(c.pdf(Vec3::Y), 1.0 / (2.0 * PI * (1.0 - cos_max)));
        assert_eq!(c.pdf(Vec3::X), 0.0);
        assert!(t.cones(Vec3::new(0.0, 4.5, 0.0)).is_none(), "inside the sphere: no cone");
    }
}
