//! `iws-pm`: the caustic photon map (Jensen 2001; spec §6) as the `Ĺ_c` of the IWS recursion.
//!
//! Build (once, rank 0, in `preprocess`): light paths from the shared particle tracer
//! (`transport::particle`, stream `PHOTON`, pass 0); every non-specular hit whose previous vertex
//! was Dirac is stored with flux `Φ = β / paths launched` (spec §6 ⚠: never divided by the
//! number stored; `particle::collect_caustic_points`, shared with the forecasters). `--photons N`
//! is the number of **stored** photons targeted (the paper's "200K" counts stored photons):
//! paths are traced in fixed-size index blocks and the map keeps exactly the paths `0..P`, where
//! `P` is the first path count with `≥ N` photons stored, so the normaliser `P` is exact and the
//! map is a pure function of the seed. Tracing stops at `PATH_FACTOR·N` paths in scenes where
//! caustics are rare (or absent).
//!
//! Estimate at `x`: `L_c ≈ Σ_{p≤k} f(x,ω_p,ω_o)·Φ_p·w_p / (C·π·r²)` with Jensen's cone filter
//! `w_p = 1 − d_p/(k_c·r)`, `C = 1 − 2/(3k_c)`, `k_c = 1.1` (integrates to 1 over the disc),
//! `r` the distance to the k-th nearest photon within `r_max`, or `r_max` when fewer are found.
//! Normal check: a photon counts only if its lit-side geometric normal agrees with `x`'s
//! (`n_p·n_x > 0.9`) and it arrives from `x`'s side. Default `r_max` = 2% of the scene-bounds
//! diagonal (7 cm in the Cornell box: about `k` photons at the density of the mirror sphere's
//! room-wide caustic with 200k stored).
//!
//! The estimate is biased (blur, boundary darkening), consistent as `N → ∞, k/N → 0`.

use super::iws::caustics::{CausticEstimator, Recurse, ShadingQuery};
use super::iws::Iws;
use super::{Context, Integrator, MethodArgs, MethodError, MethodSpec};
use crate::accel::World;
use crate::bsdf::{self, Mode, ShadingPoint};
use crate::math::{Rgb, Vec3, PI};
use crate::profile::{Phase, Profile};
use crate::progress::Phases;
use crate::sampling::rng::stream;
use crate::scene::Material;
use crate::spatial::KdTree;
use crate::transport::particle::{self, Emission};
use std::time::Instant;

/// Jensen's cone-filter constant `k_c`.
pub const CONE_K: f32 = 1.1;
/// Minimum cosine between a photon's normal and `x`'s normal.
const NORMAL_COS: f32 = 0.9;

/// `iws-pm` parameters.
#[derive(clap::Args, Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct PmArgs {
    /// Caustic photons to store.
    #[arg(long, value_name = "N", default_value_t = 200_000)]
    pub photons: u64,
    /// Photons per radiance estimate.
    #[arg(long, value_name = "K", default_value_t = 100, value_parser = clap::value_parser!(u32).range(1..))]
    pub gather: u32,
    /// Largest gather radius in scene units (default: 2% of the scene's diagonal).
    #[arg(long, value_name = "R", value_parser = parse_positive)]
    pub max_radius: Option<f32>,
}

impl PmArgs {
    /// The limits of `crate::param_limits`.
    pub fn validate(&self) -> Result<(), MethodError> {
        MethodError::check_limit(&crate::param_limits::PHOTONS, "--photons", self.photons)
    }
}

fn parse_positive(s: &str) -> Result<f32, String> {
    match s.trim().parse::<f32>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!("`{s}` must be a positive number")),
    }
}

/// The `iws-pm` method: IWS with the photon map as `Ĺ_c`.
pub struct IwsPm;

impl MethodSpec for IwsPm {
    type Product = PhotonMap;
    fn preprocess(world: &World, args: &MethodArgs, seed: u64, phases: &dyn Phases) -> Result<PhotonMap, MethodError> {
        let pm = &args.pm;
        let phase = phases.phase("photon map", Some(pm.photons));
        let map = PhotonMap::build(world, pm.photons, pm.gather, pm.max_radius, seed, &|n| {
            phase.set(n);
            !phases.stop()
        });
        Ok(map)
    }
    fn build(world: &World, args: &MethodArgs, pm: PhotonMap) -> Result<Box<dyn Integrator>, MethodError> {
        pm.validate().map_err(MethodError::BadProduct)?;
        crate::integrators::iws::check_direct(world, args)?;
        Ok(Box::new(Iws::new(world, args, Box::new(pm))))
    }
}

/// One stored caustic photon (position lives in the kd-tree).
#[derive(Clone, Copy, Debug, PartialEq, bitcode::Encode, bitcode::Decode)]
pub struct Photon {
    /// Geometric normal on the side the photon arrived from.
    pub n: [f32; 3],
    /// Direction toward the previous (Dirac) vertex.
    pub w_in: [f32; 3],
    /// Flux `β / paths launched`.
    pub flux: [f32; 3],
}

/// The caustic photon map plus its build statistics (serialized with bitcode for the broadcast).
#[derive(Clone, Debug, PartialEq, bitcode::Encode, bitcode::Decode)]
pub struct PhotonMap {
    tree: KdTree,
    photons: Vec<Photon>,
    /// Nearest photons used per estimate.
    pub k: u32,
    /// Maximum gather radius.
    pub max_radius: f32,
    /// Light paths launched (the flux normaliser).
    pub paths: u64,
    /// Photon tracing time, seconds.
    pub trace_s: f64,
    /// kd-tree build time, seconds.
    pub build_s: f64,
}

/// Default `r_max`: 2% of the scene-bounds diagonal.
pub fn default_max_radius(world: &World) -> f32 {
    let (lo, hi) = world.scene.bounds;
    let d = (hi - lo).length();
    if d.is_finite() && d > 0.0 {
        0.02 * d
    } else {
        1.0
    }
}

impl PhotonMap {
    /// Traces light paths until `target` caustic photons are stored (see the module doc).
    /// `stored(n)` is told the photons stored so far after every block of paths; `false` ends the
    /// tracing there (a deadline or a signal: fewer photons, normalised by the paths launched).
    pub fn build(
        world: &World,
        target: u64,
        k: u32,
        max_radius: Option<f32>,
        seed: u64,
        stored: &dyn Fn(u64) -> bool,
    ) -> PhotonMap {
        let t0 = Instant::now();
        let (verts, paths) =
            particle::collect_caustic_points(world, Emission::Cosine, target, seed, stream::PHOTON, stored);
        let items: Vec<([f32; 3], Photon)> = verts
            .iter()
            .map(|v| {
                let ph = Photon { n: v.n.to_array(), w_in: v.w_in.to_array(), flux: v.beta.to_array() };
                (v.p.to_array(), ph)
            })
            .collect();
        let trace_s = t0.elapsed().as_secs_f64();
        let t1 = Instant::now();
        let (points, photons): (Vec<[f32; 3]>, Vec<Photon>) = items.into_iter().unzip();
        let tree = KdTree::build(&points);
        let build_s = t1.elapsed().as_secs_f64();
        let max_radius = max_radius.filter(|r| r.is_finite() && *r > 0.0).unwrap_or_else(|| default_max_radius(world));
        PhotonMap { tree, photons, k: k.max(1), max_radius, paths, trace_s, build_s }
    }

    /// Number of stored photons.
    pub fn len(&self) -> usize {
        self.photons.len()
    }

    /// True when no photon is stored.
    pub fn is_empty(&self) -> bool {
        self.photons.is_empty()
    }

    /// Checks internal consistency after decoding (ids in range, finite parameters).
    pub fn validate(&self) -> Result<(), String> {
        if self.tree.len() != self.photons.len() {
            return Err(format!("photon map: {} tree points but {} photons", self.tree.len(), self.photons.len()));
        }
        if self.tree.items().any(|(id, _)| id as usize >= self.photons.len()) {
            return Err("photon map: photon id out of range".into());
        }
        if !(self.max_radius > 0.0 && self.max_radius.is_finite()) || self.k == 0 {
            return Err("photon map: bad k or max radius".into());
        }
        Ok(())
    }

    /// The cone-filtered radiance estimate `L_c(x → wo)` (spec §6); `buf` is gather scratch.
    pub fn radiance(&self, x: &ShadingPoint, m: &Material, wo: Vec3, buf: &mut Vec<(f32, u32)>) -> Rgb {
        if self.photons.is_empty() {
            return Rgb::ZERO;
        }
        let nx = if x.ng.dot(wo) >= 0.0 { x.ng } else { -x.ng };
        {
            let rmax2 = self.max_radius * self.max_radius;
            self.tree.k_nearest_within(x.p.to_array(), self.k as usize, rmax2, buf);
            if buf.is_empty() {
                return Rgb::ZERO;
            }
            let r2 = if buf.len() == self.k as usize { buf[buf.len() - 1].0 } else { rmax2 };
            if r2 <= 0.0 {
                return Rgb::ZERO;
            }
            let r = r2.sqrt();
            let mut sum = Rgb::ZERO;
            for &(d2, id) in buf.iter() {
                let ph = &self.photons[id as usize];
                let w_in = Vec3::from(ph.w_in);
                if Vec3::from(ph.n).dot(nx) < NORMAL_COS || w_in.dot(nx) <= 0.0 {
                    continue;
                }
                let f = bsdf::eval(m, x, wo, w_in, Mode::Radiance);
                // [Jen01] cone filter w_p = 1 − d_p/(k_c·r)
                let w = 1.0 - d2.sqrt() / (CONE_K * r);
                sum += f * Vec3::from(ph.flux) * w.max(0.0);
            }
            // normalisation C·π·r², C = 1 − 2/(3k_c)
            sum / ((1.0 - 2.0 / (3.0 * CONE_K)) * PI * r2)
        }
    }
}

impl CausticEstimator for PhotonMap {
    fn name(&self) -> &'static str {
        "photon-map"
    }
    fn estimate(&self, _: &World, q: &ShadingQuery, ctx: &mut Context, _: &dyn Recurse) -> Rgb {
        let t0 = ctx.profile.start(Phase::PhotonQuery);
        let l = self.radiance(q.x, q.m, q.wo, &mut ctx.knn);
        ctx.profile.record(Phase::PhotonQuery, t0);
        l
    }
    fn stats(&self, _: &Profile) -> serde_json::Value {
        serde_json::json!({
            "photons_stored": self.photons.len(),
            "photon_paths": self.paths,
            "gather_k": self.k,
            "max_radius": self.max_radius,
            "cone_k": CONE_K,
            "photon_trace_s": self.trace_s,
            "kdtree_build_s": self.build_s,
        })
    }
}
