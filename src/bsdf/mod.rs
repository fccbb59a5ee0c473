//! BSDF evaluation and sampling for every `Material`, in world space around a `ShadingPoint`.
//!
//! Conventions: `wo` is the given direction (toward the previous vertex: the viewer on eye paths,
//! the light on particle paths) and `wi` the sampled one; both point away from the surface.
//! `eval` returns f without the cosine. `BsdfSample::weight` is f·|cos θ_i|/pdf_w (times the
//! radiance η² factor or the adjoint shading-normal correction, depending on `Mode`).
//!
//! Invariants: reflection lobes return 0 unless `wo` and `wi` lie on the same side of the
//! **geometric** normal (no light leaks through walls); Dirac samples have `is_delta` and their
//! pdf_w is the discrete choice probability.

mod conductor;
mod dielectric;
pub mod diffuse;
mod material;
pub mod microfacet;
mod phong;
pub mod plastic;
pub mod roughconductor;
pub mod roughdielectric;
pub mod roughplastic;
#[cfg(test)]
pub(crate) mod testing;
pub mod thindielectric;

pub use conductor::fresnel_conductor;
pub use dielectric::fresnel_dielectric;
pub use material::{Material, Slot};

use crate::math::{Frame, Rgb, Vec3};

/// Which quantity a path carries (Veach ch. 5; pbrt's TransportMode).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// Eye paths: radiance (η² scaling at refraction).
    Radiance,
    /// Light paths: importance (adjoint shading-normal correction, no η² scaling).
    Importance,
}

/// The local geometry a BSDF needs.
///
/// The tangent `s` is there only where a BSDF's value depends on it: Mitsuba orients every local
/// frame by `si.sh_frame.s` (∂p/∂u made orthogonal to the shading normal, then turned with it by a
/// normal or bump map), but an isotropic BSDF is the same under any rotation of the frame about
/// the normal, so `Scene::shade` computes the tangent (which needs the hit's ∂p/∂u: barycentrics
/// or a sphere's angles, per hit) only for a material with an anisotropic roughness, and leaves
/// it zero everywhere else: there the frame is `Frame::from_normal(ns)`, as it always was, which
/// keeps isotropic images bit for bit (a rotated frame would round differently) and the
/// untextured path free of the work. Lazily here means at `shade`, once per hit, not per
/// evaluation: the frame's BSDF calls then only read it.
#[derive(Clone, Copy, Debug)]
pub struct ShadingPoint {
    /// Position.
    pub p: Vec3,
    /// Unit geometric normal, as the shape defines it (outward for closed meshes and spheres).
    pub ng: Vec3,
    /// Unit shading normal on the `ng` side.
    pub ns: Vec3,
    /// The shading normal before a normal or bump map tilted it into `ns` (equal to `ns` where
    /// none did): the frame of the map's shadowing term ([`shadow_terminator`]).
    pub n0: Vec3,
    /// The shading tangent where the BSDF is anisotropic: unit, orthogonal to `ns`, on the line
    /// of Mitsuba's `sh_frame.s` at this point (its sign, and the handedness of the frame, do not
    /// change a microfacet BSDF, which is symmetric under x → −x and y → −y). Zero where the BSDF
    /// does not need one: the local frame is then `Frame::from_normal(ns)`.
    pub s: Vec3,
}

/// A sampled direction.
#[derive(Clone, Copy, Debug)]
pub struct BsdfSample {
    /// Sampled direction (unit, away from the surface).
    pub wi: Vec3,
    /// f·|cos θ_i| / pdf_w, with the transport-mode factor.
    pub weight: Rgb,
    /// Solid-angle pdf (for Dirac lobes: the discrete lobe probability).
    pub pdf_w: f32,
    /// Dirac lobe.
    pub is_delta: bool,
    /// Relative index of refraction η_t/η_i of a refraction (pbrt-v4's `eta`), 1 otherwise. A
    /// path's roulette divides out the radiance-mode 1/η² it put into `weight`
    /// (`transport::roulette::Throughput`).
    pub eta: f32,
}

/// A BSDF in its local shading frame: the contract every BSDF file implements (Mitsuba 3's
/// `BSDF::eval`, `pdf` and `sample`, with forecast's names).
///
/// - The frame: `z` is the shading normal as the shape orients it (never flipped toward `wo`), `x`
///   Mitsuba's tangent `sh_frame.s` (∂p/∂u orthogonal to the normal; `ShadingPoint::s`) where the
///   BSDF is anisotropic (its roughness `alpha_u` is measured along it), any tangent otherwise.
/// - `wo` is the given direction (toward the viewer on eye paths, the light on particle paths;
///   Mitsuba's `si.wi`), `wi` the sampled or evaluated one (Mitsuba's `wo`); both unit, pointing
///   away from the surface.
/// - `eval` is f(wo, wi) **without** the cosine (Mitsuba's `eval` / |cos θ_i|); Dirac lobes
///   contribute nothing to `eval` and `pdf_w`.
/// - One-sided, as Mitsuba's: a reflecting BSDF is black unless `wo.z > 0` and `wi.z > 0`
///   (`twosided` flips both to the front before calling it); dielectrics take either side.
/// - `sample`'s `weight` is f·|cos θ_i|/pdf_w, with the radiance-mode factor 1/η² of a
///   refraction (η = η_t/η_i; none in importance mode). Its `pdf_w` is the solid-angle pdf of the
///   non-Dirac lobes times their selection probability, or for a Dirac lobe that lobe's discrete
///   probability, with `is_delta` set.
/// - `pdf_w(wo, wi)` equals the pdf of `sample` drawing `wi` by its non-Dirac lobes.
pub trait LocalBsdf {
    /// f(wo, wi) without the cosine.
    fn eval(&self, wo: Vec3, wi: Vec3, mode: Mode) -> Rgb;
    /// Solid-angle pdf of `sample` drawing `wi` by a non-Dirac lobe.
    fn pdf_w(&self, wo: Vec3, wi: Vec3, mode: Mode) -> f32;
    /// Draws `wi` with three uniforms (`u[0]` picks a lobe, `u[1..]` the direction).
    fn sample(&self, wo: Vec3, u: [f32; 3], mode: Mode) -> Option<BsdfSample>;
}

impl ShadingPoint {
    /// The point `p` with geometric normal `ng` and shading normal `ns` (no normal map, no
    /// tangent).
    #[inline(always)]
    pub fn new(p: Vec3, ng: Vec3, ns: Vec3) -> ShadingPoint {
        ShadingPoint { p, ng, ns, n0: ns, s: Vec3::ZERO }
    }

    /// Normals flipped to `wo`'s geometric side: (ng', ns').
    #[inline]
    fn oriented(&self, wo: Vec3) -> (Vec3, Vec3) {
        oriented(self.ng, self.ns, wo)
    }
}

/// The geometric and shading normals flipped to `wo`'s geometric side: (ng', ns').
#[inline(always)]
pub fn oriented(ng: Vec3, ns: Vec3, wo: Vec3) -> (Vec3, Vec3) {
    if wo.dot(ng) >= 0.0 {
        (ng, ns)
    } else {
        (-ng, -ns)
    }
}

/// Whether a reflection lobe pairs `wo` and `wi` around the oriented normals `(ng, ns)`: `wi`
/// above both, `wo` above `ns` (a NaN passes, as the lanes need).
#[inline(always)]
pub fn reflects(ng: Vec3, ns: Vec3, wo: Vec3, wi: Vec3) -> bool {
    !(wi.dot(ng) <= 0.0 || wi.dot(ns) <= 0.0 || wo.dot(ns) <= 0.0)
}

/// Adjoint shading-normal correction for importance transport (Veach eq. 5.19).
#[inline]
fn shading_correction(mode: Mode, sp: &ShadingPoint, wo: Vec3, wi: Vec3) -> f32 {
    if mode == Mode::Radiance || sp.ng == sp.ns {
        return 1.0;
    }
    let den = wo.dot(sp.ng).abs() * wi.dot(sp.ns).abs();
    if den <= 0.0 {
        return 0.0;
    }
    (wo.dot(sp.ns).abs() * wi.dot(sp.ng).abs()) / den
}

/// The shadowing term of a normal-mapped point toward `wi` (Estevez, Barla, Conty and Kulla
/// 2019, "A Microfacet-Based Shadowing Function to Solve the Bump Terminator Problem"; Mitsuba's
/// `normalmap` with `use_shadowing_function`): G = 2/(1 + √(1 + α² tan²θ_i)), α² = min(tan²θ_n/8,
/// 1), θ_n the tilted normal's angle and θ_i `wi`'s against the untilted one (`n0`); 0 where `wi`
/// lies on different sides of the two normals. 1 where no normal map tilted the normal.
#[inline]
pub fn shadow_terminator(sp: &ShadingPoint, wi: Vec3) -> f32 {
    if sp.n0 == sp.ns {
        return 1.0;
    }
    let (c_i, c_n) = (wi.dot(sp.n0), sp.ns.dot(sp.n0));
    if c_i * wi.dot(sp.ns) <= 0.0 {
        return 0.0;
    }
    let tan2 = |c: f32| (1.0 - c * c).max(0.0) / (c * c);
    let alpha2 = (0.125 * tan2(c_n)).min(1.0);
    2.0 / (1.0 + (1.0 + alpha2 * tan2(c_i)).sqrt())
}

/// BSDF value f(wo, wi) without the cosine, as `mode` transports it (they differ only across a
/// refraction), with a normal map's shadowing term; zero for Dirac and black materials.
#[inline]
pub fn eval(m: &Material, sp: &ShadingPoint, wo: Vec3, wi: Vec3, mode: Mode) -> Rgb {
    let f = eval_untilted(m, sp, wo, wi, mode);
    if sp.n0 == sp.ns {
        f
    } else {
        f * shadow_terminator(sp, toward_light(mode, wo, wi))
    }
}

/// The direction toward the light side: `wi` in radiance mode, `wo` in importance mode (a light
/// path's `wo` is where its light came from). The normal map's shadowing term is the radiance
/// estimator's, on the direction toward the light, so a light path (`Mode::Importance`) applies
/// it to its incoming direction, not to the direction it samples: the light side of `pt-cf`,
/// IWS's point lights and photons then carry the transport `pt` measures (Mitsuba's `normalmap`
/// applies it to the sampled direction in both modes, which is not reciprocal).
#[inline]
fn toward_light(mode: Mode, wo: Vec3, wi: Vec3) -> Vec3 {
    match mode {
        Mode::Radiance => wi,
        Mode::Importance => wo,
    }
}

/// `eval` without the normal map's shadowing term.
#[inline(always)]
fn eval_untilted(m: &Material, sp: &ShadingPoint, wo: Vec3, wi: Vec3, mode: Mode) -> Rgb {
    match *m {
        Material::Diffuse { albedo } => diffuse::eval(albedo, sp.ng, sp.ns, wo, wi),
        Material::Glossy { albedo, specular, exponent } => {
            let (ng, ns) = sp.oriented(wo);
            if !reflects(ng, ns, wo, wi) {
                return Rgb::ZERO;
            }
            phong::eval(albedo, specular, exponent, ns, wo, wi)
        }
        Material::RoughConductor(b) => eval_local(&b, m, sp, wo, wi, mode),
        Material::RoughDielectric(b) => eval_local(&b, m, sp, wo, wi, mode),
        Material::Plastic(b) => eval_local(&b, m, sp, wo, wi, mode),
        Material::RoughPlastic(b) => eval_local(&b, m, sp, wo, wi, mode),
        _ => {
            let _ = mode;
            Rgb::ZERO
        }
    }
}

/// The local frame of a BSDF at `sp` seen from `wo`: around the shading normal, flipped to
/// `wo`'s side for a two-sided reflecting BSDF (Mitsuba's `twosided`), as the shape orients it
/// for one that scatters from both sides by nature (a dielectric); its `x` axis the tangent
/// `sp.s` where there is one (Mitsuba's `sh_frame.s`), else any (`Frame::from_normal`).
#[inline]
fn frame(m: &Material, sp: &ShadingPoint, wo: Vec3) -> Frame {
    let ns = if m.is_two_sided_by_nature() { sp.ns } else { sp.oriented(wo).1 };
    if sp.s == Vec3::ZERO {
        return Frame::from_normal(ns);
    }
    Frame { s: sp.s, t: ns.cross(sp.s), n: ns }
}

/// True when the geometric normal agrees with the local directions `(lo, li)` about whether
/// `wo` → `wi` is a reflection or a transmission (no light through walls).
#[inline]
fn sides_agree(sp: &ShadingPoint, wo: Vec3, wi: Vec3, lo: Vec3, li: Vec3) -> bool {
    ((wo.dot(sp.ng) > 0.0) == (wi.dot(sp.ng) > 0.0)) == ((lo.z > 0.0) == (li.z > 0.0))
}

/// `b`'s f(wo, wi) at `sp` (world directions).
#[inline]
fn eval_local(b: &impl LocalBsdf, m: &Material, sp: &ShadingPoint, wo: Vec3, wi: Vec3, mode: Mode) -> Rgb {
    let f = frame(m, sp, wo);
    let (lo, li) = (f.to_local(wo), f.to_local(wi));
    if !sides_agree(sp, wo, wi, lo, li) {
        return Rgb::ZERO;
    }
    b.eval(lo, li, mode)
}

/// `b`'s pdf_w(wo, wi) at `sp` (world directions).
#[inline]
fn pdf_local(b: &impl LocalBsdf, m: &Material, sp: &ShadingPoint, wo: Vec3, wi: Vec3) -> f32 {
    let f = frame(m, sp, wo);
    let (lo, li) = (f.to_local(wo), f.to_local(wi));
    if !sides_agree(sp, wo, wi, lo, li) {
        return 0.0;
    }
    b.pdf_w(lo, li, Mode::Radiance)
}

/// `b`'s sample at `sp` (world directions), before the adjoint shading-normal factor.
#[inline]
fn sample_local(
    b: &impl LocalBsdf,
    m: &Material,
    sp: &ShadingPoint,
    wo: Vec3,
    u: [f32; 3],
    mode: Mode,
) -> Option<BsdfSample> {
    let f = frame(m, sp, wo);
    let lo = f.to_local(wo);
    let s = b.sample(lo, u, mode)?;
    let wi = f.to_world(s.wi);
    // a pdf that is not positive (0 or NaN) cannot weight a sample
    if !sides_agree(sp, wo, wi, lo, s.wi) || s.pdf_w.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return None;
    }
    Some(BsdfSample { wi, ..s })
}

/// Solid-angle pdf of `sample` producing `wi` (0 for Dirac and black materials, and where a
/// normal map's shadowing term is 0).
#[inline]
pub fn pdf_w(m: &Material, sp: &ShadingPoint, wo: Vec3, wi: Vec3) -> f32 {
    if sp.n0 != sp.ns && wi.dot(sp.n0) * wi.dot(sp.ns) <= 0.0 {
        return 0.0;
    }
    match *m {
        Material::Diffuse { .. } => diffuse::pdf_w(sp.ng, sp.ns, wo, wi),
        Material::Glossy { albedo, specular, exponent } => {
            let (ng, ns) = sp.oriented(wo);
            if wi.dot(ng) <= 0.0 {
                return 0.0;
            }
            phong::pdf_w(albedo, specular, exponent, ns, wo, wi)
        }
        Material::RoughConductor(b) => pdf_local(&b, m, sp, wo, wi),
        Material::RoughDielectric(b) => pdf_local(&b, m, sp, wo, wi),
        Material::Plastic(b) => pdf_local(&b, m, sp, wo, wi),
        Material::RoughPlastic(b) => pdf_local(&b, m, sp, wo, wi),
        _ => 0.0,
    }
}

/// Samples `wi` given `wo` with three uniforms; its weight has a normal map's shadowing term.
#[inline]
pub fn sample(m: &Material, sp: &ShadingPoint, wo: Vec3, u: [f32; 3], mode: Mode) -> Option<BsdfSample> {
    let s = sample_untilted(m, sp, wo, u, mode)?;
    if sp.n0 == sp.ns {
        return Some(s);
    }
    let g = shadow_terminator(sp, toward_light(mode, wo, s.wi));
    (g > 0.0).then_some(BsdfSample { weight: s.weight * g, ..s })
}

/// `sample` without the normal map's shadowing term.
#[inline(always)]
fn sample_untilted(m: &Material, sp: &ShadingPoint, wo: Vec3, u: [f32; 3], mode: Mode) -> Option<BsdfSample> {
    let (ng, ns) = sp.oriented(wo);
    let s = match *m {
        Material::Diffuse { albedo } => {
            let (wi, pdf_w, valid) = diffuse::sample(sp.ng, sp.ns, wo, [u[0], u[1]]);
            if !valid {
                return None;
            }
            diffuse::sampled(albedo, wi, pdf_w)
        }
        Material::Glossy { albedo, specular, exponent } => {
            let (wi, pdf) = phong::sample(albedo, specular, exponent, ns, wo, u)?;
            if !reflects(ng, ns, wo, wi) || pdf <= 0.0 {
                return None;
            }
            let f = phong::eval(albedo, specular, exponent, ns, wo, wi);
            BsdfSample { wi, weight: f * wi.dot(ns) / pdf, pdf_w: pdf, is_delta: false, eta: 1.0 }
        }
        Material::Mirror { reflectance } => {
            let wi = crate::math::reflect(wo, ns);
            if wi.dot(ng) <= 0.0 {
                return None;
            }
            BsdfSample { wi, weight: reflectance, pdf_w: 1.0, is_delta: true, eta: 1.0 }
        }
        Material::Conductor { reflectance, eta, k } => {
            let wi = crate::math::reflect(wo, ns);
            if wi.dot(ng) <= 0.0 {
                return None;
            }
            let f = fresnel_conductor(wo.dot(ns), eta, k);
            BsdfSample { wi, weight: reflectance * f, pdf_w: 1.0, is_delta: true, eta: 1.0 }
        }
        Material::Glass { ior } => dielectric::sample(ior, sp, wo, u[0], mode)?,
        Material::RoughConductor(b) => sample_local(&b, m, sp, wo, u, mode)?,
        Material::RoughDielectric(b) => sample_local(&b, m, sp, wo, u, mode)?,
        Material::Plastic(b) => sample_local(&b, m, sp, wo, u, mode)?,
        Material::RoughPlastic(b) => sample_local(&b, m, sp, wo, u, mode)?,
        Material::ThinDielectric(b) => sample_local(&b, m, sp, wo, u, mode)?,
        Material::Black => return None,
    };
    // Veach's adjoint factor on light paths, Dirac glass included (pbrt-v3's
    // `CorrectShadingNormal`): 1 where ns = ng, and where glass fell back to ng (wo below ns)
    let fell_back = matches!(m, Material::Glass { .. }) && dielectric::falls_back(sp, wo);
    let corr = if fell_back { 1.0 } else { shading_correction(mode, sp, wo, s.wi) };
    Some(BsdfSample { weight: s.weight * corr, ..s })
}

#[cfg(test)]
mod adjoint_tests {
    use super::*;

    /// A normal-mapped point: the geometric normal +z, the untilted shading normal too, the map's
    /// normal tilted 35° toward +x.
    fn tilted() -> ShadingPoint {
        let n = Vec3::new(35f32.to_radians().sin(), 0.0, 35f32.to_radians().cos());
        ShadingPoint { n0: Vec3::Z, ..ShadingPoint::new(Vec3::ZERO, Vec3::Z, n) }
    }

    /// A light path sees the transport `pt` measures: the importance-mode BSDF from `a` (toward
    /// the light) to `b` is the radiance-mode BSDF from `b` (toward the camera) to `a` times
    /// Veach's adjoint factor, the map's shadowing term on `a` in both; so is the sampled weight
    /// of a Dirac conductor (its only direction), where the shadowing term of the sampled
    /// direction (Mitsuba's choice) would differ.
    #[test]
    fn importance_mode_shadows_the_direction_toward_the_light() {
        let sp = tilted();
        let m = Material::Diffuse { albedo: Rgb::splat(0.5) };
        let a = Vec3::new(-0.8, 0.1, 0.3).normalize(); // grazing, away from the tilt: G(a) < 1
        let b = Vec3::new(0.3, -0.2, 0.9).normalize();
        let (ga, gb) = (shadow_terminator(&sp, a), shadow_terminator(&sp, b));
        assert!(ga < 0.95 && (ga - gb).abs() > 0.05, "G(a) {ga}, G(b) {gb}: the test has no power");
        let imp = eval(&m, &sp, a, b, Mode::Importance);
        let rad = eval(&m, &sp, b, a, Mode::Radiance);
        assert!((imp.x - rad.x).abs() <= 1e-6 * rad.x.abs().max(1e-6), "importance {imp:?} radiance {rad:?}");
        // a Dirac conductor: the importance weight's shadowing term is G(wo = toward the light)
        let c = Material::Mirror { reflectance: Rgb::splat(1.0) };
        let wo = Vec3::new(0.6, 0.1, 0.3).normalize(); // grazing toward the tilt: reflects near ns
        let bs = sample(&c, &sp, wo, [0.5; 3], Mode::Importance).expect("reflects");
        let (g_o, g_i) = (shadow_terminator(&sp, wo), shadow_terminator(&sp, bs.wi));
        assert!((g_o - g_i).abs() > 0.05, "G(wo) {g_o}, G(wi) {g_i}: no power");
        let want = shading_correction(Mode::Importance, &sp, wo, bs.wi) * g_o;
        assert!((bs.weight.x - want).abs() < 1e-5, "weight {} against {want}", bs.weight.x);
    }
}
