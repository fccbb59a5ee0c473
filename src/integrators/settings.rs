//! The render settings every method reads: the path-vertex safety cap (`--max-depth`), the
//! pixel sampler's emission split (`--emission-split`, `render::pixel`), the ray-tracing back
//! end (`--accel`, `accel::AccelKind`) and the camera streams' sampler (`--sampler`,
//! `sampling::qmc`). They are not a method's
//! options: every method accepts them, and the JSON report records them for every method.
//!
//! Invariants: `max_depth` is `None` only before the pipeline resolves it against the scene's
//! `render.max_depth` (direct callers get [`MAX_VERTICES`]); `1 <= emission_split <=
//! MAX_EMISSION_SPLIT` (clap checks the flag; the pixel sampler clamps API values).

use super::MethodError;
use crate::accel::AccelKind;
use crate::sampling::qmc::SamplerKind;
use crate::transport::particle::MAX_VERTICES;

/// The most camera rays per pixel sample (`--emission-split`; `render::pixel` clamps to it).
pub const MAX_EMISSION_SPLIT: u32 = 64;

/// Settings shared by every method (not a method's options).
#[derive(clap::Args, Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct RenderSettings {
    /// Safety cap on path vertices (default: the scene's [render] max_depth, else 64).
    #[arg(long, value_name = "N")]
    pub max_depth: Option<u32>,
    /// Camera rays per pixel sample where a light's edge is in view: they average the light seen
    /// directly or through mirrors and glass (unbiased; 1 = off, at most 64).
    // The edge pixels are found by a probe before pass 0 (`render::pixel`); one of the rays
    // carries the rest of the estimate. The default is by measurement.
    #[arg(long, value_name = "K", default_value_t = 64, value_parser = clap::value_parser!(u32).range(1..=MAX_EMISSION_SPLIT as i64))]
    pub emission_split: u32,
    /// Ray-tracing back end.
    // `AccelKind::Embree` is a hidden value in a build without the `embree` feature: it parses
    // there, and `validate` refuses it with the rebuild hint.
    #[arg(long, value_name = "BACKEND", value_enum, default_value_t = AccelKind::Wide)]
    pub accel: AccelKind,
    /// The camera paths' random numbers across passes: independent (the variance layer is exact)
    /// or sobol (each pixel's first samples stratified over its passes: lower error, a variance
    /// layer that over-states it); both unbiased, see docs/sampling.md.
    #[arg(long, value_enum, default_value_t = SamplerKind::Independent)]
    pub sampler: SamplerKind,
}

impl RenderSettings {
    /// The cap in use (the pipeline resolves `None` to the scene's; direct callers get 64).
    pub fn cap(&self) -> u32 {
        self.max_depth.unwrap_or(MAX_VERTICES)
    }

    /// The limits of `crate::param_limits` (the scene's `render.max_depth` has the same).
    pub fn validate(&self) -> Result<(), MethodError> {
        self.accel.check().map_err(MethodError::Backend)?;
        self.max_depth
            .map_or(Ok(()), |d| MethodError::check_limit(&crate::param_limits::MAX_DEPTH, "--max-depth", d.into()))
    }
}
