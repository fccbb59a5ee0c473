//! Math vocabulary shared by every module: glam re-exports, `Rgb`, luminance, an orthonormal
//! shading `Frame`, the FNV-1a hash (scene and mesh content hashes) and the Gauss–Legendre rule.
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

/// Nodes and weights of the `n`-point Gauss–Legendre rule on [−1, 1], ascending (Mitsuba's
/// `quad::gauss_legendre`: Newton's method on P_n from Chebyshev guesses, in f64, stored as
/// f32).
pub fn gauss_legendre(n: usize) -> (Vec<f32>, Vec<f32>) {
    assert!(n >= 1);
    // (P_l(x), P_l'(x)) by the three-term recurrence (Mitsuba's `math::legendre_pd`)
    let legendre_pd = |l: usize, x: f64| -> (f64, f64) {
        match l {
            0 => (1.0, 0.0),
            1 => (x, 1.0),
            _ => {
                let (mut l_pp, mut l_p, mut d_pp, mut d_p) = (1.0, x, 0.0, 1.0);
                let (mut k0, mut k1, mut k2) = (3.0, 2.0, 1.0);
                let (mut l_cur, mut d_cur) = (0.0, 0.0);
                for _ in 2..=l {
                    l_cur = (k0 * x * l_p - k2 * l_pp) / k1;
                    d_cur = d_pp + k0 * l_p;
                    (l_pp, l_p, d_pp, d_p) = (l_p, l_cur, d_p, d_cur);
                    k2 = k1;
                    k0 += 2.0;
                    k1 += 1.0;
                }
                (l_cur, d_cur)
            }
        }
    };
    let mut nodes = vec![0.0f32; n];
    let mut weights = vec![0.0f32; n];
    let last = n - 1;
    if last == 0 {
        weights[0] = 2.0;
        return (nodes, weights);
    }
    for i in 0..n / 2 {
        let mut x = -((2 * i + 1) as f64 / (2 * n) as f64 * std::f64::consts::PI).cos();
        for it in 0.. {
            assert!(it < 20, "gauss_legendre({n}): Newton did not converge");
            let (p, dp) = legendre_pd(n, x);
            let step = p / dp;
            x -= step;
            if step.abs() <= 4.0 * x.abs() * f64::EPSILON {
                break;
            }
        }
        let dp = legendre_pd(n, x).1;
        let w = (2.0 / ((1.0 - x * x) * dp * dp)) as f32;
        (weights[i], weights[last - i]) = (w, w);
        (nodes[i], nodes[last - i]) = (x as f32, -x as f32);
    }
    if n % 2 == 1 {
        let dp = legendre_pd(n, 0.0).1;
        weights[n / 2] = (2.0 / (dp * dp)) as f32;
        nodes[n / 2] = 0.0;
    }
    (nodes, weights)
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

    #[test]
    fn gauss_legendre_integrates_polynomials() {
        let (x, w) = gauss_legendre(2);
        assert!((x[1] - (1.0f32 / 3.0).sqrt()).abs() < 1e-7 && x[0] == -x[1] && w == vec![1.0, 1.0]);
        for n in [5usize, 32, 128] {
            let (x, w) = gauss_legendre(n);
            assert!(x.windows(2).all(|p| p[0] < p[1]), "n = {n}: nodes not ascending");
            // exact for degree ≤ 2n − 1: ∫x^k over [−1, 1] = 2/(k + 1) for even k, 0 for odd
            for k in 0..(2 * n).min(40) {
                let got: f64 = x.iter().zip(&w).map(|(&x, &w)| w as f64 * (x as f64).powi(k as i32)).sum();
                let want = if k % 2 == 0 { 2.0 / (k + 1) as f64 } else { 0.0 };
                assert!((got - want).abs() < 2e-6, "n = {n}, k = {k}: {got} vs {want}");
            }
        }
    }
}
