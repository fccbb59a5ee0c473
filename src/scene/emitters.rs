//! The emitters that are not surfaces, after Mitsuba 3's plugins (`src/emitters/*.cpp`, the
//! spec): `spot` (a point light with an angular profile, [`Spot`]), `directional`
//! ([`DirectionalLight`]), `constant` and `envmap` ([`Environment`]). Each formula lives here
//! once: the spot's falloff and cone, the environment's radiance, its direction sampler and its
//! pdf, and the disk every light path from an infinitely distant light starts on
//! ([`BoundingSphere::disk_origin`]). `transport::direct` (next-event estimation and the escaped
//! ray), `transport::particle` (emission) and the methods call them.
//!
//! Conventions (Mitsuba's):
//! - `spot`: the beam is `to_world`'s local +z; `falloff(θ) = 1` for `θ ≤ beam_width`,
//!   `(cutoff − θ)/(cutoff − beam_width)` between, 0 from `cutoff_angle` on (linear in the angle,
//!   as `spot.cpp`'s `falloff_curve`; angles in degrees, `beam_width` defaults to ¾ of
//!   `cutoff_angle`, 20°). Emission samples the cone uniformly.
//! - `directional`: light travels along `to_world·(0,0,1)` (or `direction`), irradiance `E` on a
//!   surface facing it.
//! - `envmap`: a direction `d` in the map's frame (`to_world⁻¹·ω`, ω away from the scene) has
//!   `u = atan2(d.x, −d.z)/2π`, `v = acos(d.y)/π`; the radiance is the bilinear interpolation at
//!   texel coordinates `(u·W − ½, v·(H − 1))`, periodic in `u` and clamped in `v` (`envmap.cpp`'s
//!   `eval_spectrum`: texel-centred columns, rows on the poles), times `scale`.
//! - `constant`: radiance `L` from every direction; sampled uniformly over the sphere.
//!
//! Sampling the map: a piecewise-constant distribution over the `W × H` cells
//! `[i/W, (i+1)/W) × [j/H, (j+1)/H)` of (u, v), cell weight = the largest luminance of the texels
//! its interpolation reads × its solid angle `Ω_ij = (2π/W)(cos θ_j − cos θ_{j+1})` (the sin θ
//! weighting, integrated), drawn as a row (the marginal, `u[1]`) and then a cell in the row (the
//! conditional, `u[0]`: [`Distribution2D`]), a direction uniform in solid angle inside the cell.
//! So `pdf_w(ω) = P_ij/Ω_ij`: finite at the poles, and positive wherever the radiance is (a
//! bound, not Mitsuba's bilinear warp; any such pdf is unbiased). `P_ij/Ω_ij` is computed once,
//! when the map is built, and kept beside texel `(i, j)` ([`Texel`]): the sampler reports it,
//! `pdf_w` reads it, and an escaped ray's radiance and pdf come from the same cache lines
//! ([`Environment::radiance_pdf_w`]; the cell of `(u, v)` is one of the four texels its
//! interpolation reads, or beside them).
//!
//! Invariants: every radiance is finite, non-negative and at most `MAX_RADIANCE`; `pdf_w` of a
//! sampled direction is the pdf `pdf_w` returns for it (up to the cell boundary's rounding).

use crate::math::{luminance, Frame, Mat3, Rgb, Vec3, PI};
use crate::sampling::distribution::Distribution2D;
use crate::sampling::warp;

/// A spot light's angular profile (`spot`); the light itself is a `PointLight`.
#[derive(Clone, Debug, PartialEq)]
pub struct Spot {
    /// The light's frame: `frame.n` is the beam axis (`to_world`'s +z).
    pub frame: Frame,
    /// cos(cutoff_angle).
    pub cos_cutoff: f32,
    /// cos(beam_width).
    pub cos_beam: f32,
    /// cutoff_angle in radians.
    pub cutoff: f32,
    /// 1/(cutoff − beam_width) in 1/radians (∞ when they are equal).
    pub inv_transition: f32,
}

impl Spot {
    /// The spot of Mitsuba's `cutoff_angle` and `beam_width` (degrees) about `axis` (unit). The
    /// error names what is wrong (the reader adds the key): cutoff in (0°, 90°], beam width in
    /// [0°, cutoff].
    pub fn new(axis: Vec3, frame_x: Vec3, cutoff_deg: f32, beam_deg: f32) -> Result<Spot, (&'static str, String)> {
        if !(cutoff_deg.is_finite() && cutoff_deg > 0.0 && cutoff_deg <= 90.0) {
            return Err(("cutoff_angle", format!("cutoff_angle {cutoff_deg}: must be in (0, 90] degrees")));
        }
        if !(beam_deg.is_finite() && beam_deg >= 0.0 && beam_deg <= cutoff_deg) {
            return Err((
                "beam_width",
                format!("beam_width {beam_deg}: must be in [0, cutoff_angle = {cutoff_deg}] degrees"),
            ));
        }
        let n = axis.normalize();
        let s = (frame_x - n * n.dot(frame_x)).normalize();
        let frame = if s.is_finite() { Frame { s, t: n.cross(s), n } } else { Frame::from_normal(n) };
        let (cutoff, beam) = (cutoff_deg.to_radians(), beam_deg.to_radians());
        Ok(Spot {
            frame,
            cos_cutoff: cutoff.cos(),
            cos_beam: beam.cos(),
            cutoff,
            inv_transition: 1.0 / (cutoff - beam),
        })
    }

    /// Mitsuba's `falloff_curve` toward the unit direction `w` (away from the light), in [0, 1].
    #[inline]
    pub fn falloff(&self, w: Vec3) -> f32 {
        let c = w.dot(self.frame.n);
        if c <= self.cos_cutoff {
            0.0
        } else if c >= self.cos_beam {
            1.0
        } else {
            ((self.cutoff - c.clamp(-1.0, 1.0).acos()) * self.inv_transition).clamp(0.0, 1.0)
        }
    }

    /// A direction uniform in the cone of `cutoff_angle` and its solid-angle pdf.
    #[inline]
    pub fn sample_dir(&self, u: [f32; 2]) -> (Vec3, f32) {
        let cos_t = 1.0 - u[0] * (1.0 - self.cos_cutoff);
        let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
        let phi = 2.0 * PI * u[1];
        let w = self.frame.to_world(Vec3::new(sin_t * phi.cos(), sin_t * phi.sin(), cos_t));
        (w, self.cone_pdf())
    }

    /// The pdf of [`Spot::sample_dir`] at `w` (0 outside the cone).
    #[inline]
    pub fn pdf_dir(&self, w: Vec3) -> f32 {
        if w.dot(self.frame.n) > self.cos_cutoff {
            self.cone_pdf()
        } else {
            0.0
        }
    }

    #[inline]
    fn cone_pdf(&self) -> f32 {
        1.0 / (2.0 * PI * (1.0 - self.cos_cutoff))
    }

    /// `∫ falloff dω` (the spot's power is intensity × this), by the midpoint rule in θ.
    pub fn falloff_solid_angle(&self) -> f32 {
        let n = 256;
        let dt = self.cutoff / n as f32;
        (0..n)
            .map(|k| {
                let t = (k as f32 + 0.5) * dt;
                let w = self.frame.to_world(Vec3::new(t.sin(), 0.0, t.cos()));
                2.0 * PI * t.sin() * dt * self.falloff(w)
            })
            .sum()
    }
}

/// A `directional` emitter: irradiance `E` along the unit direction `d` light travels.
#[derive(Clone, Debug, PartialEq)]
pub struct DirectionalLight {
    /// The direction light travels (unit); the light lies toward `−d`.
    pub d: Vec3,
    /// Irradiance on a surface facing it.
    pub irradiance: Rgb,
}

/// The sphere bounding the scene's shapes (Mitsuba's `bbox().bounding_sphere()`, radius grown by
/// a relative 1e-4): where the light paths of a directional light or an environment start.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoundingSphere {
    /// Centre.
    pub center: Vec3,
    /// Radius (> 0).
    pub radius: f32,
}

impl BoundingSphere {
    /// The sphere around the box `(lo, hi)`.
    pub fn of_box(lo: Vec3, hi: Vec3) -> BoundingSphere {
        let radius = ((hi - lo).length() * 0.5 * (1.0 + 1e-4)).max(1e-4);
        BoundingSphere { center: (lo + hi) * 0.5, radius }
    }

    /// The start of a light path travelling along the unit direction `d` from the disk of radius
    /// `radius` perpendicular to `d` behind the sphere, at the disk point of `u` (concentric
    /// map), and the disk's area density `1/(π r²)` (Mitsuba's `sample_ray` of `directional` and
    /// `envmap`). Every point of the sphere lies on exactly one such ray.
    #[inline]
    pub fn disk_origin(&self, d: Vec3, u: [f32; 2]) -> (Vec3, f32) {
        let o = warp::sample_concentric_disk(u);
        let f = Frame::from_normal(d);
        let p = self.center + (f.s * o.x + f.t * o.y - d) * self.radius;
        (p, 1.0 / (PI * self.radius * self.radius))
    }

    /// The disk's area `π r²` (an infinitely distant light's power is this × its irradiance).
    pub fn disk_area(&self) -> f32 {
        PI * self.radius * self.radius
    }
}

/// An environment emitter: `constant` or `envmap`.
#[derive(Clone, Debug)]
pub struct Environment {
    /// The map's rotation (local → world); the identity for `constant`.
    pub to_world: Mat3,
    /// Its inverse (world → local).
    pub to_local: Mat3,
    /// What it emits.
    pub map: EnvMap,
}

/// The radiance of an [`Environment`].
#[derive(Clone, Debug)]
pub enum EnvMap {
    /// `constant`: the same radiance from every direction.
    Constant(Rgb),
    /// `envmap`: a latitude-longitude image.
    LatLong(LatLong),
}

/// A latitude-longitude image (`envmap`), `scale` already applied to its texels.
#[derive(Clone, Debug)]
pub struct LatLong {
    /// Width (φ), at least 2.
    pub width: usize,
    /// Height (θ), at least 3.
    pub height: usize,
    /// Texels, row-major, the top row (θ = 0, +y) first.
    pub texels: Vec<Texel>,
    /// The cell distribution (module docs): cell `(i, j)` is column `i` of row `j`.
    pub cells: Distribution2D,
    /// cos θ at the top of each cell row and at the bottom of the last (`H + 1` values).
    cos_rows: Vec<f32>,
    /// Each cell's weight (the pick's power estimate is their sum).
    pub total_weight: f32,
}

/// A texel of a [`LatLong`] map and the pdf of its cell: one 16-byte record, so that a lookup
/// reads both from one cache line.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(16))]
pub struct Texel {
    /// The radiance of texel `(i, j)`.
    pub rgb: Rgb,
    /// `pdf_w` of the directions of cell `(i, j)` (module docs).
    pub pdf_w: f32,
}

impl LatLong {
    /// The map of `texels` (W × H, row-major, scale applied). `Err` names the problem: fewer
    /// than 2 × 3 texels, or a texel that is not finite and non-negative.
    pub fn new(width: usize, height: usize, texels: Vec<Rgb>) -> Result<LatLong, String> {
        if width < 2 || height < 3 {
            return Err(format!(
                "an environment map of {width}x{height} texels: at least 2x3 are needed (use `constant` for a uniform one)"
            ));
        }
        let lum: Vec<f32> = texels.iter().map(|&t| luminance(t).max(0.0)).collect();
        let (w, h) = (width, height);
        let mut weights = vec![0.0f32; w * h];
        for j in 0..h {
            // rows read by the interpolation for v in [j/H, (j+1)/H]
            let r0 = ((j as f32 * (h - 1) as f32 / h as f32).floor() as usize).min(h - 1);
            let r1 = (((j + 1) as f32 * (h - 1) as f32 / h as f32).ceil() as usize).min(h - 1);
            let (c0, c1) = (Self::cos_row(j, h), Self::cos_row(j + 1, h));
            let omega = 2.0 * PI / w as f32 * (c0 - c1).max(0.0);
            for i in 0..w {
                let mut m = 0.0f32;
                for r in r0..=r1 {
                    for c in [i + w - 1, i, i + 1] {
                        m = m.max(lum[r * w + c % w]);
                    }
                }
                weights[j * w + i] = m * omega;
            }
        }
        let total_weight: f32 = weights.iter().map(|&x| x as f64).sum::<f64>() as f32;
        let cells = Distribution2D::new(&weights, w).unwrap_or_default();
        let cos_rows = (0..=h).map(|j| Self::cos_row(j, h)).collect();
        let mut map = LatLong { width, height, texels: Vec::new(), cells, cos_rows, total_weight };
        map.texels = (0..w * h)
            .map(|k| Texel { rgb: texels[k], pdf_w: map.cell_pdf_w(map.cells.pmf(k % w, k / w), k / w) })
            .collect();
        Ok(map)
    }

    /// cos θ at the top of cell row `j` (θ = π j/H).
    #[inline]
    fn cos_row(j: usize, h: usize) -> f32 {
        if j == 0 {
            1.0
        } else if j == h {
            -1.0
        } else {
            (PI * j as f32 / h as f32).cos()
        }
    }

    /// The pdf `P_ij/Ω_ij` of the cell `(u, v)` lies in.
    #[inline]
    fn pdf_w_at(&self, u: f32, v: f32) -> f32 {
        self.texels[self.cell_index(u, v)].pdf_w
    }

    /// `P_ij/Ω_ij` of a cell of row `j` whose probability is `pmf` (0 where not finite): the pdf
    /// kept in the texels and the one the sampler reports (the same `pmf`, the same float).
    #[inline]
    fn cell_pdf_w(&self, pmf: f32, j: usize) -> f32 {
        let pdf = pmf / (2.0 * PI / self.width as f32 * (self.cos_rows[j] - self.cos_rows[j + 1]));
        if pdf.is_finite() {
            pdf
        } else {
            0.0
        }
    }

    /// The texel index of the cell `(u, v)` lies in, whose pdf `pdf_w_at` reads.
    #[inline(always)]
    fn cell_index(&self, u: f32, v: f32) -> usize {
        let i = ((u * self.width as f32) as usize).min(self.width - 1);
        let j = ((v * self.height as f32) as usize).min(self.height - 1);
        j * self.width + i
    }

    /// The bilinear footprint of `lookup` at `(u, v)` (module docs): the columns `x0`, `x1`
    /// (wrapped), the first of the two rows `y0` and `y0 + 1`, and the weights toward `x1` and
    /// `y0 + 1`.
    #[inline(always)]
    fn bilinear_cell(&self, u: f32, v: f32) -> (usize, usize, usize, f32, f32) {
        let (w, h) = (self.width, self.height);
        let u = u - u.floor();
        let xc = u * w as f32 - 0.5;
        let x0f = xc.floor();
        let fx = xc - x0f;
        let x0 = (x0f as i64).rem_euclid(w as i64) as usize;
        let x1 = (x0 + 1) % w;
        let yc = v.clamp(0.0, 1.0) * (h - 1) as f32;
        let y0 = (yc.floor() as usize).min(h - 2);
        let fy = (yc - y0 as f32).clamp(0.0, 1.0);
        (x0, x1, y0, fx, fy)
    }

    /// The bilinear lookup at `(u, v)` (module docs).
    #[inline]
    pub fn lookup(&self, u: f32, v: f32) -> Rgb {
        let (x0, x1, y0, fx, fy) = self.bilinear_cell(u, v);
        let w = self.width;
        let t = |x: usize, y: usize| self.texels[y * w + x].rgb;
        let top = t(x0, y0) * (1.0 - fx) + t(x1, y0) * fx;
        let bottom = t(x0, y0 + 1) * (1.0 - fx) + t(x1, y0 + 1) * fx;
        top * (1.0 - fy) + bottom * fy
    }

    /// The texel indices `lookup` and `pdf_w_at` at `(u, v)` read: the bilinear footprint's four
    /// (`(x0, y0), (x1, y0), (x0, y0 + 1), (x1, y0 + 1)`), then the cell's pdf.
    #[inline]
    pub fn texels_read(&self, u: f32, v: f32) -> [usize; 5] {
        let (x0, x1, y0, _, _) = self.bilinear_cell(u, v);
        let w = self.width;
        [y0 * w + x0, y0 * w + x1, (y0 + 1) * w + x0, (y0 + 1) * w + x1, self.cell_index(u, v)]
    }
}

/// `(u, v)` of a unit direction in the map's frame (Mitsuba's `direction_to_uv`).
#[inline]
fn direction_to_uv(d: Vec3) -> (f32, f32) {
    let u = d.x.atan2(-d.z) * (0.5 / PI);
    (u - u.floor(), d.y.clamp(-1.0, 1.0).acos() / PI)
}

impl Environment {
    /// A `constant` environment.
    pub fn constant(radiance: Rgb) -> Environment {
        Environment { to_world: Mat3::IDENTITY, to_local: Mat3::IDENTITY, map: EnvMap::Constant(radiance) }
    }

    /// An `envmap` turned by the rotation `to_world`.
    pub fn lat_long(map: LatLong, to_world: Mat3) -> Environment {
        Environment { to_world, to_local: to_world.transpose(), map: EnvMap::LatLong(map) }
    }

    /// The radiance arriving from the unit world direction `w` (pointing away from the scene).
    #[inline]
    pub fn radiance(&self, w: Vec3) -> Rgb {
        match &self.map {
            EnvMap::Constant(l) => *l,
            EnvMap::LatLong(m) => {
                let (u, v) = direction_to_uv((self.to_local * w).normalize());
                m.lookup(u, v)
            }
        }
    }

    /// [`Environment::radiance`] and [`Environment::pdf_w`] of the unit world direction `w`, from
    /// one `(u, v)` (an escaped ray: its radiance and its MIS weight).
    #[inline]
    pub fn radiance_pdf_w(&self, w: Vec3) -> (Rgb, f32) {
        match &self.map {
            EnvMap::Constant(l) => (*l, warp::uniform_sphere_pdf()),
            EnvMap::LatLong(m) => {
                let (u, v) = direction_to_uv((self.to_local * w).normalize());
                (m.lookup(u, v), m.pdf_w_at(u, v))
            }
        }
    }

    /// Asks the cache for the texels [`Environment::radiance_pdf_w`] of the unit world direction
    /// `w` reads ([`LatLong::texels_read`]): a hint, no effect on any value.
    #[inline]
    pub fn prefetch(&self, w: Vec3) {
        if let EnvMap::LatLong(m) = &self.map {
            let (u, v) = direction_to_uv((self.to_local * w).normalize());
            for k in m.texels_read(u, v) {
                crate::texture::prefetch(m.texels.as_ptr().wrapping_add(k));
            }
        }
    }

    /// A direction toward the environment (unit, world) and its solid-angle pdf; `None` when the
    /// map is black.
    #[inline]
    pub fn sample(&self, u: [f32; 2]) -> Option<(Vec3, f32)> {
        match &self.map {
            EnvMap::Constant(_) => Some((warp::sample_uniform_sphere(u), warp::uniform_sphere_pdf())),
            EnvMap::LatLong(m) => {
                if m.cells.is_empty() {
                    return None;
                }
                let ((i, j), pmf, [ur, vr]) = m.cells.sample(u);
                let (c0, c1) = (m.cos_rows[j], m.cos_rows[j + 1]);
                let phi = 2.0 * PI * (i as f32 + ur) / m.width as f32;
                let cos_t = c0 - vr * (c0 - c1);
                let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
                let local = Vec3::new(phi.sin() * sin_t, cos_t, -phi.cos() * sin_t);
                // not read from the texel: a draw that the BSDF rejects never loads its line
                let pdf = m.cell_pdf_w(pmf, j);
                (pdf > 0.0).then(|| ((self.to_world * local).normalize(), pdf))
            }
        }
    }

    /// The solid-angle pdf with which [`Environment::sample`] draws the unit world direction `w`.
    #[inline]
    pub fn pdf_w(&self, w: Vec3) -> f32 {
        match &self.map {
            EnvMap::Constant(_) => warp::uniform_sphere_pdf(),
            EnvMap::LatLong(m) => {
                if m.cells.is_empty() {
                    return 0.0;
                }
                let (u, v) = direction_to_uv((self.to_local * w).normalize());
                m.pdf_w_at(u, v)
            }
        }
    }

    /// `∫ luminance(L) dω` (an upper bound for a map), the light pick's power per unit area of
    /// the disk.
    pub fn power_per_area(&self) -> f32 {
        match &self.map {
            EnvMap::Constant(l) => 4.0 * PI * luminance(*l),
            EnvMap::LatLong(m) => m.total_weight,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::rng::{stream, Rng};

    fn test_map() -> Environment {
        let (w, h) = (8, 5);
        let texels = (0..w * h)
            .map(|k| {
                let (x, y) = (k % w, k / w);
                Rgb::new(0.1 + (x * y) as f32, if x == 3 { 5.0 } else { 0.0 }, y as f32 * 0.5)
            })
            .collect();
        let rot = Mat3::from_rotation_y(0.7) * Mat3::from_rotation_x(-0.4);
        Environment::lat_long(LatLong::new(w, h, texels).unwrap(), rot)
    }

    /// Mitsuba's convention: +y is the top row (v = 0), −z is u = 0, +x is u = ¼.
    #[test]
    fn lat_long_orientation_is_mitsubas() {
        assert_eq!(direction_to_uv(Vec3::Y).1, 0.0);
        assert_eq!(direction_to_uv(-Vec3::Y).1, 1.0);
        assert_eq!(direction_to_uv(-Vec3::Z), (0.0, 0.5));
        let (u, v) = direction_to_uv(Vec3::X);
        assert!((u - 0.25).abs() < 1e-6 && (v - 0.5).abs() < 1e-6);
        // a texel-centred column: u = (i + ½)/W reads column i exactly on the pole row
        let m = LatLong::new(4, 3, (0..12).map(|k| Rgb::splat(k as f32)).collect()).unwrap();
        assert_eq!(m.lookup(2.5 / 4.0, 0.0), Rgb::splat(2.0));
        assert_eq!(m.lookup(2.5 / 4.0, 0.5), Rgb::splat(6.0));
        // u = 0 lies between the last column and the first (periodic): texels 11 and 8 of row 2
        assert_eq!(m.lookup(0.0, 1.0), Rgb::splat(11.0 * 0.5 + 8.0 * 0.5));
    }

    /// The texels an escaped ray's prefetch fetches are the texels its lookup reads: with 1 on
    /// the four of `texels_read(u, v)` and 0 elsewhere the lookup is 1, with 0 on them and 1
    /// elsewhere it is 0; the fifth is the cell of `(u, v)`, whose pdf `pdf_w_at` returns.
    #[test]
    fn texels_read_are_the_texels_the_lookup_reads() {
        let (w, h) = (7, 5);
        let mut rng = Rng::keyed(5, stream::MISC, 0, 0);
        let map = |read: &[usize], on: f32, off: f32| {
            let texels = (0..w * h).map(|k| Rgb::splat(if read.contains(&k) { on } else { off })).collect();
            LatLong::new(w, h, texels).unwrap()
        };
        let pdfs = test_map();
        let EnvMap::LatLong(pdfs) = &pdfs.map else { unreachable!() };
        for n in 0..2000 {
            let [a, b] = rng.next_2d();
            // u beyond [0, 1) too, and v on the poles
            let (u, v) = (a * 3.0 - 1.0, if n % 10 == 0 { (n / 10 % 2) as f32 } else { b });
            let read = map(&[], 0.0, 0.0).texels_read(u, v);
            let ones = map(&read[..4], 1.0, 0.0).lookup(u, v);
            assert!((ones - Rgb::ONE).abs().max_element() < 1e-5, "{u} {v}: {read:?} {ones}");
            assert_eq!(map(&read[..4], 0.0, 1.0).lookup(u, v), Rgb::ZERO, "{u} {v}: {read:?}");
            let pr = pdfs.texels_read(u, v);
            assert_eq!(pdfs.texels[pr[4]].pdf_w, pdfs.pdf_w_at(u, v));
            if (0.0..1.0).contains(&u) && v < 1.0 {
                let (i, j) = ((pr[4] % pdfs.width) as f32, (pr[4] / pdfs.width) as f32);
                let (cw, ch) = (pdfs.width as f32, pdfs.height as f32);
                assert!(i <= u * cw && u * cw < i + 1.0 && j <= v * ch && v * ch < j + 1.0, "{u} {v}: {pr:?}");
            }
        }
    }

    /// The sampler's pdf integrates to 1 and agrees with `pdf_w` at its samples; the radiance is
    /// positive only where the pdf is.
    #[test]
    fn sampler_pdf_is_consistent() {
        let env = test_map();
        let mut rng = Rng::keyed(3, stream::MISC, 0, 0);
        let n = 400_000;
        let (mut integral, mut differ, mut uncovered) = (0.0f64, 0, 0);
        for _ in 0..n {
            let w = warp::sample_uniform_sphere(rng.next_2d());
            let p = env.pdf_w(w);
            integral += p as f64 * 4.0 * std::f64::consts::PI / n as f64;
            uncovered += (p == 0.0 && luminance(env.radiance(w)) > 0.0) as usize;
            let (ws, ps) = env.sample(rng.next_2d()).unwrap();
            differ += ((ps - env.pdf_w(ws)).abs() > 1e-3 * ps) as usize;
        }
        assert!((integral - 1.0).abs() < 0.01, "∫ pdf = {integral}");
        assert!(differ < n / 1000, "{differ} sampled pdfs differ");
        assert_eq!(uncovered, 0);
    }

    #[test]
    fn spot_falloff_is_mitsubas() {
        let s = Spot::new(Vec3::Z, Vec3::X, 20.0, 15.0).unwrap();
        let at = |deg: f32| s.falloff(Vec3::new(deg.to_radians().sin(), 0.0, deg.to_radians().cos()));
        assert_eq!(at(0.0), 1.0);
        assert_eq!(at(14.9), 1.0);
        assert!((at(17.5) - 0.5).abs() < 1e-3);
        assert_eq!(at(20.1), 0.0);
        assert!(Spot::new(Vec3::Z, Vec3::X, 0.0, 0.0).is_err());
        assert!(Spot::new(Vec3::Z, Vec3::X, 91.0, 10.0).is_err());
        assert!(Spot::new(Vec3::Z, Vec3::X, 20.0, 25.0).is_err());
    }
}
