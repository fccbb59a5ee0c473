//! Next-event estimation: one light sample (picked ∝ power) with a shadow ray, MIS-weighted
//! against BSDF sampling by the power heuristic for area lights and the environment; point,
//! spot and directional lights (Dirac in position or direction) by NEE only.
//!
//! `emitter_pdf_w` gives the light-sampling pdf of a BSDF-sampled hit on an emitter, and
//! `environment_pdf_w` that of a ray that escapes to the environment, so the path tracer can
//! weight those hits with the same heuristic (Veach 1997 §9.2); `escaped` is that weighted
//! environment radiance. A shadow ray toward a light at infinity is unbounded (`tmax = ∞`).

use crate::accel::{offset_origin, Hit, Ray, World};
use crate::bsdf::{self, Mode, ShadingPoint};
use crate::math::{Rgb, Vec3};
use crate::sampling::power_heuristic;
use crate::sampling::rng::Rng;
use crate::scene::{LightRef, Material, NO_EMITTER};

/// Solid-angle pdf that `sample_light` picks the point `y` (normal `ny`) of emitter `e` from a
/// point at distance² `dist2` with light-side cosine `cos_l`: [`light_pdf_w`] with the pick's
/// pmf and `Scene::sample_emitter_point`'s area density, so that the two pdfs of an MIS pair are
/// the same floating-point expression.
#[inline]
pub fn emitter_pdf_w(world: &World, emitter: u32, dist2: f32, cos_l: f32) -> f32 {
    let s = &world.scene;
    if cos_l <= 0.0 {
        return 0.0;
    }
    let li = emitter as usize; // area emitters come first in `Scene::lights`
    light_pdf_w(s.light_pick.pmf(li), 1.0 / s.emitters[emitter as usize].area, dist2, cos_l)
}

/// Solid-angle pdf that `sample_light` picks the environment direction `d` (the pick's pmf
/// times `Environment::pdf_w`); 0 without an environment.
#[inline]
pub fn environment_pdf_w(world: &World, d: Vec3) -> f32 {
    world.scene.environment.as_ref().map_or(0.0, |env| picked_environment_pdf_w(world, env.pdf_w(d)))
}

/// The pick's pmf times the environment's own `pdf_w` (0 when the environment is not a light).
#[inline]
fn picked_environment_pdf_w(world: &World, pdf_w: f32) -> f32 {
    let s = &world.scene;
    s.environment_light().map_or(0.0, |li| s.light_pick.pmf(li) * pdf_w)
}

/// A ray along `d` that hit nothing: `(Le, MIS weight)` of the environment, weighted as
/// [`emitter_hit`] (the direction sampler against NEE); `None` without an environment.
#[inline]
pub fn escaped(world: &World, d: Vec3, prev_delta: bool, prev_pdf_w: f32) -> Option<(Rgb, f32)> {
    let env = world.scene.environment.as_ref()?;
    let (le, pdf_w) = env.radiance_pdf_w(d);
    let w = if prev_delta { 1.0 } else { power_heuristic(prev_pdf_w, picked_environment_pdf_w(world, pdf_w)) };
    Some((le, w))
}

/// The unbounded shadow ray from the surface point `sp` toward a light at infinity along `wi`.
#[inline]
pub fn ray_to_infinity(sp: &ShadingPoint, wi: Vec3) -> Ray {
    Ray { o: offset_origin(sp.p, sp.ng, wi), d: wi, tmax: f32::INFINITY }
}

/// The direction from `p` toward the light point `y` (normal `ny`): `(wi, distance², cos θ_l)`,
/// the light-side cosine positive where `y` faces `p`.
#[inline(always)]
pub fn toward(p: Vec3, y: Vec3, ny: Vec3) -> (Vec3, f32, f32) {
    let d = y - p;
    let dist2 = d.length_squared();
    let wi = d / dist2.sqrt();
    (wi, dist2, ny.dot(-wi))
}

/// The solid-angle pdf of a light point picked with probability `pmf` and area density `pdf_a`,
/// at distance² `dist2` and light-side cosine `cos_l`.
#[inline(always)]
pub fn light_pdf_w(pmf: f32, pdf_a: f32, dist2: f32, cos_l: f32) -> f32 {
    pmf * pdf_a * dist2 / cos_l
}

/// An area light's NEE contribution `Le·f·|cos θ_s|/pdf_light`, MIS-weighted by the power
/// heuristic against the caller's direction sampler (`pdf_other`).
#[inline(always)]
pub fn area_light_value(le: Rgb, f: Rgb, cos_s: f32, pdf_light: f32, pdf_other: f32) -> Rgb {
    le * f * (cos_s.abs() / pdf_light) * power_heuristic(pdf_light, pdf_other)
}

/// A hit on an emitter's front reached along `d`: `(Le, MIS weight)`, the weight of the
/// direction sampler (pdf `prev_pdf_w`, or a Dirac lobe when `prev_delta`) against NEE by the
/// power heuristic. `None` when `hit` is not on an emitter or sees its back (no light).
#[inline]
pub fn emitter_hit(world: &World, hit: &Hit, d: Vec3, prev_delta: bool, prev_pdf_w: f32) -> Option<(Rgb, f32)> {
    let em = world.scene.emitter_of(hit.prim);
    let cos_l = hit.ng.dot(-d);
    if em == NO_EMITTER {
        return None;
    }
    (cos_l > 0.0).then(|| {
        let le = world.scene.emitters[em as usize].radiance;
        let w =
            if prev_delta { 1.0 } else { power_heuristic(prev_pdf_w, emitter_pdf_w(world, em, hit.t * hit.t, cos_l)) };
        (le, w)
    })
}

/// One NEE sample at a non-Dirac point: Le·f·cos/pdf with MIS (area lights) or exact (point lights).
#[inline]
pub fn sample_light(world: &World, sp: &ShadingPoint, m: &Material, wo: Vec3, rng: &mut Rng) -> Rgb {
    sample_light_mis(world, sp, m, wo, rng, |wi| bsdf::pdf_w(m, sp, wo, wi))
}

/// [`sample_light`] with the MIS weight taken against `pdf_other(wi)`, the solid-angle pdf with
/// which the caller's own direction sampler would draw `wi` (`bsdf::pdf_w` for `pt`; a guided
/// mixture's `q` for `pt-cf`). The BSDF-sampled emitter hit must use the same pair of pdfs.
pub fn sample_light_mis(
    world: &World,
    sp: &ShadingPoint,
    m: &Material,
    wo: Vec3,
    rng: &mut Rng,
    pdf_other: impl Fn(Vec3) -> f32,
) -> Rgb {
    unoccluded(world, light_sample_mis(world, sp, m, wo, rng, pdf_other))
}

/// A NEE sample's contribution once its shadow ray is traced: its value, or 0 when blocked or
/// when there is no sample.
#[inline]
pub fn unoccluded(world: &World, ls: Option<LightSample>) -> Rgb {
    match ls {
        Some(ls) if !world.occluded(ls.shadow.o, ls.shadow.d, ls.shadow.tmax) => ls.value,
        _ => Rgb::ZERO,
    }
}

/// One NEE sample before its shadow ray: the contribution if the segment is unoccluded.
#[derive(Clone, Copy, Debug)]
pub struct LightSample {
    /// `Le·f·cos/pdf` with its MIS weight (area lights), or the exact point-light term.
    pub value: Rgb,
    /// The shadow segment; `value` counts only if nothing blocks it.
    pub shadow: Ray,
}

/// [`sample_light_mis`] without the shadow ray, for callers that trace shadow rays in batches
/// (the wavefront `pt`, `integrators::pt::wavefront`): the same random numbers, and `None`
/// exactly where `sample_light_mis` returns 0 without tracing.
pub fn light_sample_mis(
    world: &World,
    sp: &ShadingPoint,
    m: &Material,
    wo: Vec3,
    rng: &mut Rng,
    pdf_other: impl Fn(Vec3) -> f32,
) -> Option<LightSample> {
    let s = &world.scene;
    let (li, pmf, _) = s.light_pick.sample(rng.next_f32());
    let u = rng.next_2d();
    match s.lights[li] {
        LightRef::Area(e) => {
            let (y, ny, pdf_a) = s.sample_emitter_point(e, u);
            let (wi, dist2, cos_l) = toward(sp.p, y, ny);
            if dist2 <= 0.0 || cos_l <= 0.0 {
                return None;
            }
            let f = bsdf::eval(m, sp, wo, wi, Mode::Radiance);
            if f == Rgb::ZERO {
                return None;
            }
            let pdf_light = light_pdf_w(pmf, pdf_a, dist2, cos_l);
            let pdf_bsdf = pdf_other(wi);
            let shadow = world.visibility_ray(sp.p, sp.ng, y, ny)?;
            let le = s.emitters[e as usize].radiance;
            let value = area_light_value(le, f, wi.dot(sp.ns), pdf_light, pdf_bsdf);
            Some(LightSample { value, shadow })
        }
        LightRef::Point(i) => {
            let pl = &s.point_lights[i as usize];
            let d = pl.position - sp.p;
            let dist2 = d.length_squared();
            if dist2 <= 0.0 {
                return None;
            }
            let dist = dist2.sqrt();
            let wi = d / dist;
            let f = bsdf::eval(m, sp, wo, wi, Mode::Radiance);
            if f == Rgb::ZERO {
                return None;
            }
            let i = pl.intensity_toward(-wi);
            if i == Rgb::ZERO {
                return None;
            }
            let o = offset_origin(sp.p, sp.ng, wi);
            let len = (pl.position - o).length();
            let value = i * f * (wi.dot(sp.ns).abs() / (dist2 * pmf));
            Some(LightSample { value, shadow: Ray { o, d: (pl.position - o) / len, tmax: len } })
        }
        LightRef::Directional(i) => {
            let dl = &s.directional_lights[i as usize];
            let wi = -dl.d;
            let f = bsdf::eval(m, sp, wo, wi, Mode::Radiance);
            if f == Rgb::ZERO {
                return None;
            }
            let value = dl.irradiance * f * (wi.dot(sp.ns).abs() / pmf);
            Some(LightSample { value, shadow: ray_to_infinity(sp, wi) })
        }
        LightRef::Environment => {
            let env = s.environment.as_ref()?;
            let (wi, pdf_w) = env.sample(u)?;
            let f = bsdf::eval(m, sp, wo, wi, Mode::Radiance);
            if f == Rgb::ZERO {
                return None;
            }
            let le = env.radiance(wi);
            let value = area_light_value(le, f, wi.dot(sp.ns), pmf * pdf_w, pdf_other(wi));
            Some(LightSample { value, shadow: ray_to_infinity(sp, wi) })
        }
    }
}
