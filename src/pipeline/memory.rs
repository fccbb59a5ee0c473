//! The up-front memory estimate of a render (`Plan::memory_estimate`), checked against the
//! available memory in `RenderJob::resolve` before any work.
//!
//! Invariants: a lower bound (films and preprocess products only), saturating, never panicking.

use super::Plan;
use crate::integrators::Method;
use crate::scene::Scene;

impl Plan {
    /// Bytes this render needs on this node, at least, and of what (refused up front when they
    /// exceed the available memory). Film: 7 f64 per pixel (`render::film::STRIDE`), held by every
    /// rank, plus on rank 0 the reduced sums and the final copy (and with checkpoints or a resume
    /// the checkpoint's film, its clone and its encoding), plus the images (mean, variance, EXR,
    /// PNG: ≈ 64 bytes per pixel). Preprocess product: stored photons (`iws-pm`, ≈ 64 bytes each)
    /// or forecast photons (`iws-cf`, `pt-cf`, ≈ 128 bytes with their clusters and maps), three copies on
    /// rank 0 (built, encoded, decoded) and one on every other rank of the node. The camera values
    /// of a pass group (`render::pass_group_limit` passes for `pt` and `pt-cf`, else one; 12 bytes
    /// per pixel and pass) and, for `pt-cf` with light paths, one splat image per pass of the
    /// group (as much again), on every rank. The scene's decoded images, on every rank of the
    /// node.
    pub fn memory_estimate(&self, scene: &Scene, checkpoints: bool) -> (u64, String) {
        let pixels = self.resolution.0 as u64 * self.resolution.1 as u64;
        let film = pixels.saturating_mul((crate::render::film::STRIDE * 8) as u64);
        let local = local_ranks() as u64;
        let copies = if checkpoints { 6 } else { 3 };
        let product = match self.method {
            Method::IwsPm => self.args.pm.photons.saturating_mul(64),
            // pt-cf builds the same forecast from the same options (`--forecast-photons`)
            Method::IwsCf | Method::PtCf => {
                self.args.cf.forecast_photons.or(scene.forecast_photons).unwrap_or(200_000).saturating_mul(128)
            }
            _ => 0,
        };
        let film_total = film.saturating_mul(copies + local - 1).saturating_add(pixels.saturating_mul(64));
        // a pass group's camera values and pt-cf's splat images (3 f32 per pixel and pass) per rank
        let (w, h) = (self.resolution.0 as usize, self.resolution.1 as usize);
        let group = match self.method {
            Method::Pt | Method::PtCf => crate::render::pass_group_limit(w, h) as u64,
            _ => 1,
        };
        let splats = self.method == Method::PtCf && self.args.ptcf.light_paths != Some(0);
        let per_pass = 12 * local * if splats { 2 } else { 1 };
        let film_total = film_total.saturating_add(pixels.saturating_mul(per_pass * group));
        // every rank of the node holds the scene's decoded images
        let textures = scene.texture_bytes().saturating_mul(local);
        let need = film_total.saturating_add(product.saturating_mul(2 + local)).saturating_add(textures);
        let (w, h) = self.resolution;
        let mut what =
            format!("a {w}x{h} film of {:.1} GiB per copy; preprocess product {:.1} GiB", gib(film), gib(product));
        if textures > 0 {
            what += &format!("; textures {:.2} GiB", gib(textures));
        }
        (need, what)
    }
}

fn gib(bytes: u64) -> f64 {
    bytes as f64 / (1u64 << 30) as f64
}

/// Ranks on this node (MPICH's `MPI_LOCALNRANKS`, Open MPI's `OMPI_COMM_WORLD_LOCAL_SIZE`; 1).
pub(super) fn local_ranks() -> usize {
    ["MPI_LOCALNRANKS", "OMPI_COMM_WORLD_LOCAL_SIZE"]
        .iter()
        .find_map(|v| std::env::var(v).ok()?.parse::<usize>().ok())
        .unwrap_or(1)
        .max(1)
}
