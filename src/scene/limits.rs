//! Scene limits: the extent every primitive, the camera and the lights must lie in, the largest
//! light values, and the non-regular-file refusal shared
//! by the scene and mesh readers.
//!
//! `MAX_RADIANCE = 1e15` per channel for an emitter, `MAX_INTENSITY = 1e9` for a point light:
//! the film's variance layer is f32 (max 3.4e38), so a sample's value must stay below ≈ 1e19 for
//! its square to be finite; 1e15 leaves a factor 1e4 for path weights (MIS, roulette, splitting,
//! IWS compensation), and a point light of 1e9 gives at most 1e15 at 1 mm (I/d²), the smallest
//! feature these scenes are meant for. Above them, a render's `var.*` layer turned to ∞ (1e25)
//! and samples became non-finite (3e38).
//!
//! `MAX_EXTENT = 1e12`: every primitive's bounding box (triangle vertices, sphere centre ± radius,
//! mesh vertices after the transform) must lie in the cube |coordinate| ≤ 1e12. Derivation, in f32
//! (max 3.4e38): a box in the cube has half-area ≤ 3·(2e12)² = 1.2e25; the BVH builder's SAH cost
//! sums half-areas over at most 2·2³² nodes with weights of a few units (≈ 1e11 in all), ≤ 1.2e36,
//! 300× below f32::MAX; for rays from inside the cube, ray–sphere products (|o − c|², r²) stay
//! below 3·(2e12)² ≈ 1.2e25, a triangle's e₁ × e₂ below 8e24 per component (its length is taken
//! scaled, `make_triangle`), and the ray–triangle numerator (e₁ × e₂)·(v₀ − o) below 5e37.
//! Beyond it, surface areas or cost sums overflow to ∞ and obvhs panics. (f32 spacing at 1e12 is
//! 2¹⁷ units, so such scenes are useless to render, but they fail cleanly or work.)

use crate::math::Vec3;
use std::path::Path;

/// The largest |coordinate| any primitive's bounds, the camera or a light may have.
pub const MAX_EXTENT: f32 = 1e12;

/// The largest radiance per channel an emitter may have (see the module docs).
pub const MAX_RADIANCE: f32 = 1e15;

/// The largest intensity per channel a point light may have (see the module docs).
pub const MAX_INTENSITY: f32 = 1e9;

/// `None` when every channel of `v` is finite and in [0, max], else the message for `key`.
pub fn light_value_error(key: &str, v: Vec3, max: f32) -> Option<String> {
    let ok = v.is_finite() && v.min_element() >= 0.0 && v.max_element() <= max;
    (!ok).then(|| format!("{key} must be finite, non-negative and at most {max:e} per channel (see scenes/README.md)"))
}

/// True when `p` is finite and every |coordinate| ≤ `MAX_EXTENT`.
#[inline]
pub fn within_extent(p: Vec3) -> bool {
    p.is_finite() && p.abs().max_element() <= MAX_EXTENT
}

/// The message for a point outside the extent limit.
pub(super) fn extent_message(what: &str, p: Vec3) -> String {
    format!(
        "{what} {:?} lies outside the scene extent limit |coordinate| <= {MAX_EXTENT:e} (see scenes/README.md)",
        p.to_array()
    )
}

/// Refuses paths that are not regular files (FIFOs, devices, directories) before opening them:
/// reading a FIFO blocks forever. `what` names the file kind in the message.
pub(super) fn check_regular_file(path: &Path, what: &str) -> Result<(), String> {
    crate::atomic_io::require_regular(path).map_err(|e| format!("cannot read {what} `{}`: {e}", path.display()))
}
