//! Math vocabulary shared by every module: glam re-exports, `Rgb`, luminance, an orthonormal
//! shading `Frame` and the FNV-1a hash (scene and mesh content hashes).
//!
//! Invariants: `Frame` is right-handed and orthonormal; `to_local(n) == (0,0,1)`. Local directions
//! have `z = cos θ` against the frame normal.

pub use glam::{Mat3, Mat4, Vec2, Vec3, Vec3A};

/// Linear RGB radiance, flux or reflectance.
pub type Rgb = Vec3;

/// π.
pub const PI: f32 = std::f32::consts::PI;
/// 1/π.
pub const INV_PI: f32 = std::f32::consts::FRAC_1_PI;

/// Rec. 709 luminance of a linear RGB value.
#[inline]
pub fn luminance(c: Rgb) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// An orthonormal basis (s, t, n) around a unit normal `n`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// First tangent.
    pub s: Vec3,
    /// Second tangent.
    pub t: Vec3,
    /// Normal (local +z).
    pub n: Vec3,
}

impl Frame {
    /// Builds a frame around the unit normal `n` (Duff et al. 2017, branchless ONB).
    #[inline]
    pub fn from_normal(n: Vec3) -> Self {
        let sign = 1.0f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let s = Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let t = Vec3::new(b, sign + n.y * n.y * a, -n.y);
        Frame { s, t, n }
    }
    /// World → local (z along the normal).
    #[inline]
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }
    /// Local → world.
    #[inline]
    pub fn to_world(&self, v: Vec3) -> Vec3 {
        self.s * v.x + self.t * v.y + self.n * v.z
    }
}

/// Mirror reflection of `w` about `n` (both pointing away from the surface).
#[inline]
pub fn reflect(w: Vec3, n: Vec3) -> Vec3 {
    2.0 * w.dot(n) * n - w
}

/// FNV-1a over bytes, continuing from `h` (start from `0xcbf2_9ce4_8422_2325`).
pub fn fnv1a(mut h: u64, bytes: &[u8]) -> u64 {
    for &b in bytes {
        h ^= b as u64;
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    h
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_is_orthonormal_for_many_normals() {
        for i in 0..1000 {
            let a = i as f32 * 0.731;
            let z = (i as f32 / 999.0) * 2.0 - 1.0;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let n = Vec3::new(r * a.cos(), r * a.sin(), z).normalize();
            let f = Frame::from_normal(n);
            assert!((f.s.length() - 1.0).abs() < 1e-4 && (f.t.length() - 1.0).abs() < 1e-4);
            assert!(f.s.dot(f.t).abs() < 1e-4 && f.s.dot(n).abs() < 1e-4 && f.t.dot(n).abs() < 1e-4);
            assert!((f.s.cross(f.t) - n).length() < 1e-3, "right-handed");
            let v = Vec3::new(0.3, -0.5, 0.8).normalize();
            assert!((f.to_world(f.to_local(v)) - v).length() < 1e-5);
        }
    }
}
