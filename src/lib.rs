//! `forecast`: unbiased global illumination with Caustic Forecasting (Budge, Anderson, Joy
//! 2008, "BAJ08"). Methods (`--method`, one folder each under `integrators`): `pt` (path
//! tracing, the reference), `iws` (Illumination by Weak Singularities, KK04), `iws-pm` (IWS + a
//! caustic photon map, biased), `iws-cf` (IWS + Caustic Forecasting, the paper's, unbiased) and
//! `pt-cf` (`pt` guided by the forecast tables, with light paths; unbiased), and `auto`, which
//! picks one from the scene.
//!
//! The layout, data flow and layers: `ARCHITECTURE.md`; every file, one line each (the one module
//! map): `docs/modules.md`; derivations: `docs/methods/`.
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
pub mod texture;
pub mod transport;
