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
    /// rank 0 (built, encoded, decoded) and one on every other rank of the node. `pt-cf` with light
    /// paths: its per-pass splat image (12 bytes per pixel) on every rank.
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
        // pt-cf's light paths: a dense splat image per pass (3 f32 per pixel) on every rank
        let splats = if self.method == Method::PtCf && self.args.ptcf.light_paths != Some(0) { 12 * local } else { 0 };
        let film_total = film_total.saturating_add(pixels.saturating_mul(splats));
        let need = film_total.saturating_add(product.saturating_mul(2 + local));
        let (w, h) = self.resolution;
        let what =
            format!("a {w}x{h} film of {:.1} GiB per copy; preprocess product {:.1} GiB", gib(film), gib(product));
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
