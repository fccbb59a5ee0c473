//! Caustic Forecasting [BAJ08 §3.2]: the preprocess products (caustic points, clusters, the
//! cluster map and per-cluster forecast maps) and the photon-driven direction tables.
//!
//! Built once per run on rank 0 and broadcast as one bitcode buffer; never refreshed per pass.

pub mod bins;
pub mod caustic_point;
pub mod cluster;
pub mod cluster_map;
pub mod direction_table;
pub mod estimator;
pub mod forecast_map;
pub mod mixture;
pub mod share;
pub mod splat;
pub mod subset_grid;
pub mod table_cache;
pub mod view;
