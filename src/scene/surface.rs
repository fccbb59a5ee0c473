//! What a scene material adds to its BSDF's parameters: the sides it scatters from (Mitsuba's
//! `twosided`). [`super::Scene::shade`] resolves a hit into the `Material` and `ShadingPoint`
//! every method works with.
//!
//! Invariants: a one-sided BSDF is black where the given direction `wo` lies behind the geometric
//! normal (Mitsuba's rule: its BSDFs are one-sided unless wrapped in `twosided`; the dielectrics
//! scatter from both sides by nature); a two-sided one is the same BSDF on both sides.

use crate::bsdf::Material;

/// A scene material's surface properties beside its BSDF parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Surface {
    /// Scatters from both sides of the surface: Mitsuba's `twosided`, every TOML material unless
    /// it says `twosided = false`, and the dielectrics always.
    pub two_sided: bool,
}

impl Surface {
    /// Both sides.
    pub const TWO_SIDED: Surface = Surface { two_sided: true };

    /// One side, unless `m` scatters from both sides by nature (a dielectric).
    pub fn one_sided(m: &Material) -> Surface {
        Surface { two_sided: m.is_two_sided_by_nature() }
    }
}
