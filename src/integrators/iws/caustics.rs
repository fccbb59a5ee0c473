//! The caustic term `Ĺ_c(x, ω_o, d)` of the IWS recursion (spec §1) behind one trait, the
//! shading-point query it receives, and the shared `L_c` integrand along one direction.
//!
//! Implementations: [`NoCaustics`] (`iws`: L_c omitted by design), the photon map (`iws-pm`,
//! `iws_pm`), Caustic Forecasting (`iws-cf`, `iws_cf`) and [`BsdfCaustics`], the
//! plain unbiased BSDF-sampled `L_c` (used by tests to check that the split is complete).

use crate::accel::{offset_origin, Hit, World};
use crate::bsdf::{self, Mode};
use crate::math::{Rgb, Vec3};
use crate::profile::{Phase, Profile};
use crate::sampling::rng::Rng;
use crate::scene::NO_EMITTER;
pub use crate::transport::context::{Context, ShadingQuery};
use crate::transport::dirac::{environment, follow_dirac_chain};
use crate::transport::particle::MAX_VERTICES;
use crate::transport::roulette::{q_recursion, roulette};

/// Full estimator `L̂(y, ω_o, d)` at a hit, given to caustic estimators so that Dirac chains
/// ending at a non-specular vertex can recurse (spec §1 "Chain following").
pub trait Recurse {
    /// `L̂(y→ω_o)` at `hit` with diffuse depth `depth`: `Le` on emitters, the full estimator at
    /// non-specular hits (a mixed material's Dirac lobe included, spec §1 "Mixed materials"),
    /// 0 on Dirac hits.
    fn l_hat(&self, world: &World, hit: &Hit, wo: Vec3, depth: u32, ctx: &mut Context) -> Rgb;
}

/// The caustic term `Ĺ_c(x, ω_o, d)` plugged into the IWS recursion (spec §1).
pub trait CausticEstimator: Send + Sync {
    /// Short name for the stats.
    fn name(&self) -> &'static str;
    /// One estimate of `L_c` at `q`; `full` evaluates `L̂` at chain ends.
    fn estimate(&self, world: &World, q: &ShadingQuery, ctx: &mut Context, full: &dyn Recurse) -> Rgb;
    /// Statistics for the JSON report.
    fn stats(&self, _profile: &Profile) -> serde_json::Value {
        serde_json::json!({})
    }
}

/// `Ĺ_c = 0`: the plain `iws` method ("Total Without Caustics").
pub struct NoCaustics;

impl CausticEstimator for NoCaustics {
    fn name(&self) -> &'static str {
        "none"
    }
    fn estimate(&self, _: &World, _: &ShadingQuery, _: &mut Context, _: &dyn Recurse) -> Rgb {
        Rgb::ZERO
    }
    fn stats(&self, _: &Profile) -> serde_json::Value {
        serde_json::json!({ "caustics": "omitted (L_c not estimated)" })
    }
}

/// Unbiased `Ĺ_c` by one BSDF-sampled direction: it counts only if the first hit is Dirac
/// (spec §1), then follows the chain and evaluates `L̂` at its end (what CF does outside kept
/// clusters, spec §4). Noisy but exact.
pub struct BsdfCaustics;

impl CausticEstimator for BsdfCaustics {
    fn name(&self) -> &'static str {
        "bsdf"
    }
    fn estimate(&self, world: &World, q: &ShadingQuery, ctx: &mut Context, full: &dyn Recurse) -> Rgb {
        if q.depth + 1 >= MAX_VERTICES {
            return Rgb::ZERO;
        }
        let u = ctx.rng.next_3d();
        let Some(bs) = bsdf::sample(q.m, q.x, q.wo, u, Mode::Radiance) else {
            return Rgb::ZERO;
        };
        if bs.is_delta {
            return Rgb::ZERO; // L_c integrates x's non-Dirac lobes only (spec §1)
        }
        caustic_chain(world, q, bs.wi, bs.weight, ctx, full)
    }
}

/// The L_c integrand along `wi` from `q.x`, times `weight`, the sample's whole estimator weight
/// (f·|cos|/p over the sample count): 0 unless the first hit is Dirac (spec §1: L_d owns diffuse
/// and emitter first hits); else roulette on `weight`, the Dirac chain, and `L̂` at its end with
/// diffuse depth + 1.
pub fn caustic_chain(
    world: &World,
    q: &ShadingQuery,
    wi: Vec3,
    weight: Rgb,
    ctx: &mut Context,
    full: &dyn Recurse,
) -> Rgb {
    let x = q.x;
    let Some(hit) = world.intersect(offset_origin(x.p, x.ng, wi), wi, f32::INFINITY) else {
        return Rgb::ZERO;
    };
    let m = world.scene.material_of(hit.prim);
    if world.scene.emitter_of(hit.prim) != NO_EMITTER || !(m.is_dirac() || m.has_mixed_lobes()) {
        return Rgb::ZERO;
    }
    let Some(w) = roulette(weight, q_recursion(weight, q.depth + 1), &mut ctx.rng) else {
        return Rgb::ZERO;
    };
    let t0 = ctx.profile.start(Phase::CfChain);
    ctx.profile.cf_chains += 1;
    let start =
        if m.has_mixed_lobes() { dirac_lobe(world, &hit, wi, w, &mut ctx.rng) } else { Some((Some(hit), wi, w)) };
    let chain = match start {
        Some((Some(hit), wi, w)) => follow_dirac_chain(world, hit, wi, w, MAX_VERTICES, &mut ctx.rng),
        escaped => escaped,
    };
    let l = match chain {
        Some((Some(z), d, beta)) => beta * full.l_hat(world, &z, -d, q.depth + 1, ctx),
        Some((None, d, beta)) => beta * environment(world, d),
        None => Rgb::ZERO,
    };
    ctx.profile.record(Phase::CfChain, t0);
    l
}

/// The Dirac-lobe part of a mixed material at `hit` (reached along `d` with throughput `beta`):
/// one BSDF sample, which counts only where it picked a Dirac lobe (its weight already divides
/// by that lobe's probability, so the expectation is the Dirac lobes' light alone, spec §1
/// "Mixed materials"); returns the next hit (`None`: it escapes), the direction to it and the
/// throughput.
pub fn dirac_lobe(world: &World, hit: &Hit, d: Vec3, beta: Rgb, rng: &mut Rng) -> Option<(Option<Hit>, Vec3, Rgb)> {
    let (m, sp) = world.shade(hit, -d);
    let bs = bsdf::sample(&m, &sp, -d, rng.next_3d(), Mode::Radiance).filter(|bs| bs.is_delta)?;
    let next = world.intersect(offset_origin(hit.p, hit.ng, bs.wi), bs.wi, f32::INFINITY);
    Some((next, bs.wi, beta * bs.weight))
}
