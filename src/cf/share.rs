//! The caustic share of a kept cluster: its indirect irradiance split into the part the forecast
//! tables aim at (light through Dirac vertices, `E_c`) and the rest (`E_d`). `pt-cf` guides by it
//! (`c_k = max(c, 1 − s)`, unguided below `--guide-min-share`). Measured in the preprocess
//! (`integrators::iws_cf::share`), broadcast with the CF product. (`iws-cf`'s uses of it,
//! `--split-rule share` and `--table-min-share`, were retired: `results/rejected/`.)
//!
//! Invariants: any value only steers pdfs and sample counts that are functions of the vertex, so
//! no value can bias an image; `share()` is in [0, 1], 0 when nothing was measured.

/// Irradiance at a kept cluster's caustic points from indirect light, split by path type: what
/// a continuation at a point there estimates (NEE or the point lights take the direct light).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, bitcode::Encode, bitcode::Decode)]
pub struct CausticShare {
    /// `E_c`: the cluster's forecast-photon flux over its area (light that reached it through
    /// Dirac vertices, which the photons find however small the light's image is).
    pub caustic: f32,
    /// `E_c` as the cosine gather sees it (a check of `caustic`; not used: a gather misses
    /// caustics of small lights seen through curved glass, which photons do not).
    pub caustic_gather: f32,
    /// `E_d`: light whose path has a non-Dirac vertex before the point, by the cosine gather.
    pub other: f32,
}

impl CausticShare {
    /// The caustic share `s = E_c/(E_c + E_d)` (0 when both vanish).
    pub fn share(&self) -> f32 {
        let t = self.caustic + self.other;
        if t > 0.0 && t.is_finite() {
            self.caustic / t
        } else {
            0.0
        }
    }
}

/// `v` if it is a share in [0, 1] (NaN is not): the check of `--guide-min-share`.
pub fn min_share(v: f32) -> Result<f32, String> {
    if (0.0..=1.0).contains(&v) {
        Ok(v)
    } else {
        Err(format!("{v} is not a share in [0, 1]"))
    }
}

/// Parses a [`min_share`] (the CLI's value parser).
pub fn parse_min_share(s: &str) -> Result<f32, String> {
    min_share(s.trim().parse().map_err(|e| format!("`{s}` is not a number: {e}"))?)
}
