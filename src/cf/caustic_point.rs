//! Caustic points ("forecasters", [BAJ08 §3.2] Preprocessing; spec §3 photon shooting): the record
//! stored at every non-specular light-path hit whose immediately preceding vertex was Dirac.
//!
//! Invariants: `n` is the geometric normal flipped to the lit side (so `wi·n > 0` for a valid record);
//! `wi` is unit length and points from `p` back toward where the light came from; `power` is the RGB
//! flux Φ = β_path / N_emitted (luminance of it is the energy used by clustering).

use crate::math::{luminance, Rgb, Vec3};

/// One stored caustic point. Plain arrays so that it is `Copy`, compact and bitcode-serializable.
#[derive(Clone, Copy, Debug, PartialEq, bitcode::Encode, bitcode::Decode)]
pub struct CausticPoint {
    /// Hit position.
    pub p: [f32; 3],
    /// Geometric normal, flipped to the lit side.
    pub n: [f32; 3],
    /// Unit direction from `p` back toward where the light came from.
    pub wi: [f32; 3],
    /// RGB flux Φ = β / N_emitted.
    pub power: [f32; 3],
}

impl CausticPoint {
    /// Builds a record from glam vectors.
    pub fn new(p: Vec3, n: Vec3, wi: Vec3, power: Rgb) -> Self {
        CausticPoint { p: p.to_array(), n: n.to_array(), wi: wi.to_array(), power: power.to_array() }
    }
    /// Position.
    #[inline]
    pub fn pos(&self) -> Vec3 {
        Vec3::from_array(self.p)
    }
    /// Geometric normal (lit side).
    #[inline]
    pub fn normal(&self) -> Vec3 {
        Vec3::from_array(self.n)
    }
    /// Incident direction (toward the light).
    #[inline]
    pub fn wi(&self) -> Vec3 {
        Vec3::from_array(self.wi)
    }
    /// RGB flux.
    #[inline]
    pub fn flux(&self) -> Rgb {
        Vec3::from_array(self.power)
    }
    /// Rec.709 luminance of the flux (the energy used by clustering and table weights).
    #[inline]
    pub fn energy(&self) -> f32 {
        luminance(self.flux())
    }
    /// True when every field is finite (non-finite records are ignored by clustering).
    #[inline]
    pub fn is_finite(&self) -> bool {
        self.p.iter().chain(&self.n).chain(&self.wi).chain(&self.power).all(|c| c.is_finite())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn accessors_round_trip() {
        let c = CausticPoint::new(Vec3::X, Vec3::Y, Vec3::Z, Vec3::new(1.0, 1.0, 1.0));
        assert_eq!(c.pos(), Vec3::X);
        assert_eq!(c.normal(), Vec3::Y);
        assert_eq!(c.wi(), Vec3::Z);
        assert!((c.energy() - 1.0).abs() < 1e-6);
        assert!(c.is_finite());
        let bytes = bitcode::encode(&c);
        assert_eq!(bitcode::decode::<CausticPoint>(&bytes).unwrap(), c);
    }
}
