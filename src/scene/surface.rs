//! What a scene material adds to its BSDF's parameters: the sides it scatters from (Mitsuba's
//! `twosided`), the textures that set its parameters at each point, and the normal map that tilts
//! its shading normal (`normalmap`). [`super::Scene::shade`] resolves a hit into the `Material`
//! and `ShadingPoint` every method works with; the surface parametrisation it needs is here too
//! ([`uv_at`]: Mitsuba's `uv` and `dp_du` for triangles and spheres).
//!
//! Invariants: a one-sided BSDF is black where the given direction `wo` lies behind the geometric
//! normal (Mitsuba's rule: its BSDFs are one-sided unless wrapped in `twosided`; the dielectrics
//! scatter from both sides by nature); a two-sided one is the same BSDF on both sides. A surface
//! with no textures and no normal map resolves to its material as stored, with the shading point
//! as hit (`ShadingPoint::n0 == ns`).

use super::{Sphere, Triangle};
use crate::bsdf::{Material, ShadingPoint, Slot};
use crate::math::{Frame, Vec2, Vec3, PI};
use crate::texture::Texture;

/// A scene material's surface properties beside its BSDF parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct Surface {
    /// Scatters from both sides of the surface: Mitsuba's `twosided`, every TOML material unless
    /// it says `twosided = false`, and the dielectrics always.
    pub two_sided: bool,
    /// Textures that set parameters of the material at each point.
    pub textures: Vec<SlotTexture>,
    /// The texture of a tangent-space normal map (Mitsuba's `normalmap`, its `normalmap`
    /// parameter), an index into `Scene::textures`.
    pub normalmap: Option<u32>,
}

/// A texture that sets one parameter of a material.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SlotTexture {
    /// The parameter.
    pub slot: Slot,
    /// Index into `Scene::textures`.
    pub texture: u32,
}

impl Surface {
    /// Both sides, constant parameters.
    pub const TWO_SIDED: Surface = Surface { two_sided: true, textures: Vec::new(), normalmap: None };

    /// One side, unless `m` scatters from both sides by nature (a dielectric).
    pub fn one_sided(m: &Material) -> Surface {
        Surface { two_sided: m.is_two_sided_by_nature(), ..Surface::TWO_SIDED }
    }

    /// True when the material is the same at every point (no texture, no normal map).
    #[inline(always)]
    pub fn is_constant(&self) -> bool {
        self.textures.is_empty() && self.normalmap.is_none()
    }

    /// The material `base` at a point of texture coordinates `uv`, its textured parameters looked
    /// up in `textures`.
    pub fn material_at(&self, base: &Material, textures: &[Texture], uv: Vec2) -> Material {
        let mut m = *base;
        for t in &self.textures {
            let tex = &textures[t.texture as usize];
            let v = if t.slot.is_monochrome() { Vec3::splat(tex.eval_1(uv)) } else { tex.eval(uv) };
            m.set(t.slot, v);
        }
        m
    }
}

/// The texture coordinates and ∂p/∂u of a point `p` of triangle `t`, as Mitsuba's meshes give
/// them: interpolated UVs where the mesh has them, else the barycentric coordinates (b1, b2)
/// with ∂p/∂u = p1 − p0.
pub fn triangle_uv(t: &Triangle, p: Vec3) -> (Vec2, Vec3) {
    let (e1, e2, v) = (t.p[1] - t.p[0], t.p[2] - t.p[0], p - t.p[0]);
    let (d00, d01, d11) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let (d20, d21) = (v.dot(e1), v.dot(e2));
    let den = d00 * d11 - d01 * d01;
    let inv = if den != 0.0 { 1.0 / den } else { 0.0 };
    let (b1, b2) = ((d11 * d20 - d01 * d21) * inv, (d00 * d21 - d01 * d20) * inv);
    let Some(uv) = t.uv else { return (Vec2::new(b1, b2), e1) };
    let (duv0, duv1) = (uv[1] - uv[0], uv[2] - uv[0]);
    let det = duv0.x * duv1.y - duv0.y * duv1.x;
    let inv_det = if det != 0.0 { 1.0 / det } else { 0.0 };
    (uv[0] + duv0 * b1 + duv1 * b2, (e1 * duv1.y - e2 * duv0.y) * inv_det)
}

/// The texture coordinates and ∂p/∂u of a point `p` of sphere `s`, as Mitsuba's `sphere`:
/// u = φ/2π, v = θ/π in the sphere's own frame (`Sphere::axes`).
pub fn sphere_uv(s: &Sphere, p: Vec3) -> (Vec2, Vec3) {
    let d = p - s.center;
    let local = Vec3::new(d.dot(s.axes[0]), d.dot(s.axes[1]), d.dot(s.axes[2])) / s.radius;
    let theta = local.z.clamp(-1.0, 1.0).acos();
    let mut phi = local.y.atan2(local.x);
    if phi < 0.0 {
        phi += 2.0 * PI;
    }
    let dpdu_local = Vec3::new(-local.y, local.x, 0.0) * (2.0 * PI * s.radius);
    let dpdu = s.axes[0] * dpdu_local.x + s.axes[1] * dpdu_local.y;
    (Vec2::new(phi / (2.0 * PI), theta / PI), dpdu)
}

/// The shading frame around `n` with its tangent along `dpdu` (Gram–Schmidt), Mitsuba's
/// `sh_frame`; any tangent where `dpdu` is parallel to `n` or zero.
pub fn shading_frame(n: Vec3, dpdu: Vec3) -> Frame {
    let s = dpdu - n * n.dot(dpdu);
    let len = s.length();
    let tiny = 1e-12 * dpdu.length().max(1e-30);
    if !len.is_finite() || len.partial_cmp(&tiny) != Some(std::cmp::Ordering::Greater) {
        return Frame::from_normal(n);
    }
    let s = s / len;
    Frame { s, t: n.cross(s), n }
}

/// `sp` with its shading normal tilted by a tangent-space normal map of value `rgb` in the
/// frame `f` (Mitsuba's `normalmap`: n = 2·rgb − 1, mirrored about the normal where it would
/// face away from `wo` as the untilted normal does, `flip_invalid_normals`). `n0` keeps the
/// untilted normal for the shadowing term.
pub fn tilt(sp: ShadingPoint, f: &Frame, rgb: Vec3, wo: Vec3) -> ShadingPoint {
    let mut n = rgb * 2.0 - Vec3::ONE;
    let wl = f.to_local(wo);
    if wl.z * wl.dot(n) <= 0.0 {
        n = Vec3::new(-n.x, -n.y, n.z);
    }
    let n = n.normalize_or_zero();
    if n == Vec3::ZERO {
        return sp;
    }
    ShadingPoint { ns: f.to_world(n).normalize(), n0: f.n, ..sp }
}
