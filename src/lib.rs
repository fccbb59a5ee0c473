//! `forecast`: unbiased global illumination with Caustic Forecasting
//! (Budge, Anderson, Joy 2008, "[BAJ08]").
//!
//! Data flow (and module order):
//! ```text
//! scene (TOML, OBJ) → accel::World (CWBVH) → Method::preprocess (rank 0; caustic maps)
//!   → distributed broadcast → per pass or pass group: Integrator::begin_pass (IWS point lights) → render::render_passes
//!   → render::film::Film sums → distributed reduce → image_io (EXR, PNG) + JSON report
//! ```
//! Methods: `pt` (reference), `iws`, `iws-pm`, `iws-cf`; see `integrators` and ARCHITECTURE.md.
#![warn(missing_docs)]

pub mod accel;
pub mod atomic_io;
pub mod bench;
pub mod bsdf;
pub mod cf;
pub mod chart;
pub mod checkpoint;
pub mod cli;
pub mod compare;
pub mod distributed;
pub mod image_io;
pub mod integrators;
pub mod interrupt;
pub mod math;
pub mod metrics;
pub mod output;
pub mod param_limits;
pub mod pipeline;
pub mod profile;
pub mod progress;
pub mod render;
pub mod sampling;
pub mod scene;
pub mod scenegen;
pub mod spatial;
pub mod stats;
pub mod transport;
