//! The point lights of one IWS pass (spec §2): one per emitter vertex and per non-specular
//! light-path vertex of `N` light paths from the shared particle tracer (stream `VPL`, keyed by
//! the pass), with power `W0·Le`, `W0·I` or `β/N`.

use crate::accel::World;
use crate::math::{Rgb, Vec3};
use crate::sampling::rng::stream;
use crate::scene::Material;
use crate::transport::particle::{self, Emission, EmitterVertex, LightPaths, ParticleVisitor, SurfaceVertex};

/// What a point light is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum VplKind {
    /// On an area emitter: profile `Le`, clamped.
    Area,
    /// A scene point light: intensity, never clamped.
    Point,
    /// At a non-specular light-path vertex: profile `f(y, ω_in, ·)`, clamped.
    Surface(Material),
}

/// One point light of a pass.
#[derive(Clone, Copy, Debug)]
pub struct Vpl {
    /// Position.
    pub p: Vec3,
    /// Geometric normal.
    pub ng: Vec3,
    /// Shading normal.
    pub ns: Vec3,
    /// Shading normal before a normal map (`ShadingPoint::n0`).
    pub n0: Vec3,
    /// Direction toward the previous light-path vertex.
    pub w_in: Vec3,
    /// `W0·Le`, `W0·I` or `β/N`.
    pub power: Rgb,
    /// Its emission profile.
    pub kind: VplKind,
}

struct VplCollector(Vec<Vpl>);

impl ParticleVisitor for VplCollector {
    fn emitter(&mut self, v: &EmitterVertex) {
        let kind = if v.point { VplKind::Point } else { VplKind::Area };
        self.0.push(Vpl { p: v.p, ng: v.n, ns: v.n, n0: v.n, w_in: v.n, power: v.emission * v.weight, kind });
    }
    fn surface(&mut self, v: &SurfaceVertex) -> bool {
        if !v.material.is_black() {
            let kind = VplKind::Surface(*v.material);
            self.0.push(Vpl { p: v.p, ng: v.ng, ns: v.ns, n0: v.n0, w_in: v.w_in, power: v.beta, kind });
        }
        true
    }
}

/// Refills `vpls` with the point lights of pass `pass` from `n_paths` light paths.
pub fn generate_vpls(world: &World, n_paths: u64, seed: u64, pass: u64, vpls: &mut Vec<Vpl>) {
    let mut c = VplCollector(std::mem::take(vpls));
    c.0.clear();
    let batch = LightPaths { emission: Emission::Cosine, n_paths, seed, stream_id: stream::VPL, pass };
    particle::trace_paths(world, &batch, &mut c);
    *vpls = c.0;
}
