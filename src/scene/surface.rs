//! What a scene material adds to its BSDF's parameters: the sides it scatters from (Mitsuba's
//! `twosided`), the textures that set its parameters at each point, the normal map or bump map
//! that tilts its shading frame (`normalmap`, `bumpmap`), and whether its BSDF needs the shading
//! tangent (an anisotropic roughness). [`super::Scene::shade`] resolves a hit into the `Material`
//! and `ShadingPoint` every method works with ([`Surface::shading_point`]); the surface
//! parametrisation it needs is here too (Mitsuba's `uv`, `dp_du` and `dp_dv` of triangles and
//! spheres: [`triangle_uv`], [`triangle_dpdv`], [`sphere_uv`], [`sphere_dpdv`]).
//!
//! The shading frame is Mitsuba's `sh_frame` (interaction.h `initialize_sh_frame`): the shading
//! normal, and `s` = ∂p/∂u made orthogonal to it (Gram–Schmidt), or `coordinate_system(n)` where
//! ∂p/∂u is zero. A map replaces it by the frame of its own `frame()`:
//! - `normalmap` (normalmap.cpp): n = 2·rgb − 1 in the shading frame, mirrored about the normal
//!   where `wo` would lie on different sides of it and of the untilted normal
//!   (`flip_invalid_normals`); `s` = the shading frame's `s` made orthogonal to n.
//! - `bumpmap` (bumpmap.cpp): with the height texture's gradient g = `scale`·∇(u,v) (Mitsuba's
//!   `eval_1_grad`), ∂p/∂u' = ∂p/∂u + n (g_u − n·∂p/∂u) and ∂p/∂v' likewise, n' = ∂p/∂u' ×
//!   ∂p/∂v' normalised and turned to the geometric normal's side, taken into the shading frame and
//!   flipped as the normal map's; `s` = ∂p/∂u made orthogonal to n' with ∂p/∂u's **world**
//!   components read as shading-frame coordinates (Mitsuba's `frame()` mixes the two spaces
//!   there; only an anisotropic BSDF under a bump map sees it, and Mitsuba is the spec).
//! - Nested in `twosided` (twosided(normalmap(..)), twosided(bumpmap(..))), a map seen from
//!   behind sees `wo` mirrored through the surface, as Mitsuba's `twosided` flips the local z
//!   before the map's `frame()` runs; so the tilt is the front's mirrored. Around `twosided`
//!   (normalmap(twosided(..))) the map sees `wo` itself.
//!
//! Invariants: a one-sided BSDF is black where the given direction `wo` lies behind the geometric
//! normal (Mitsuba's rule: its BSDFs are one-sided unless wrapped in `twosided`; the dielectrics
//! scatter from both sides by nature); a two-sided one is the same BSDF on both sides. A surface
//! with no textures, no map and an isotropic BSDF resolves to its material as stored, with the
//! shading point as hit (`ShadingPoint::n0 == ns`, no tangent). The tangent `ShadingPoint::s`
//! is set only where the BSDF is anisotropic ([`Surface::anisotropic`]): an isotropic BSDF keeps
//! `Frame::from_normal(ns)`, so its images do not change with the tangent (bit for bit), and a
//! map's tilted normal is computed the same way with or without it.

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
    /// A bump map (Mitsuba's `bumpmap`); never together with `normalmap`.
    pub bumpmap: Option<BumpMap>,
    /// The map (`normalmap` or `bumpmap`) is nested in Mitsuba's `twosided`
    /// (twosided(normalmap(..))): seen from behind it tilts the frame as from the front, mirrored
    /// through the surface. False for a map around `twosided` (normalmap(twosided(..))).
    pub map_in_twosided: bool,
    /// The BSDF's roughness is anisotropic (`alpha_u` ≠ `alpha_v`): its local frame needs the
    /// shading tangent (`ShadingPoint::s`).
    pub anisotropic: bool,
}

/// Mitsuba's `bumpmap`: a height texture and its gradient's multiplier.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BumpMap {
    /// The height texture (its `eval_1_grad`), an index into `Scene::textures`.
    pub texture: u32,
    /// `scale` (default 1).
    pub scale: f32,
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
    /// Both sides, constant parameters (an isotropic BSDF: see [`Surface::of`]).
    pub const TWO_SIDED: Surface = Surface {
        two_sided: true,
        textures: Vec::new(),
        normalmap: None,
        bumpmap: None,
        map_in_twosided: false,
        anisotropic: false,
    };

    /// The surface of BSDF `m` on both sides, constant parameters; `anisotropic` as `m` is.
    pub fn of(m: &Material) -> Surface {
        Surface { anisotropic: is_anisotropic(m), ..Surface::TWO_SIDED }
    }

    /// One side, unless `m` scatters from both sides by nature (a dielectric); `anisotropic` as
    /// `m` is.
    pub fn one_sided(m: &Material) -> Surface {
        Surface { two_sided: m.is_two_sided_by_nature(), ..Surface::of(m) }
    }

    /// True when the material and its shading point are the hit's at every point: no texture, no
    /// map, an isotropic BSDF (no tangent needed).
    #[inline(always)]
    pub fn is_constant(&self) -> bool {
        self.textures.is_empty() && self.normalmap.is_none() && self.bumpmap.is_none() && !self.anisotropic
    }

    /// True when the surface has a normal or bump map.
    #[inline]
    pub fn has_map(&self) -> bool {
        self.normalmap.is_some() || self.bumpmap.is_some()
    }

    /// The shading point of hit `sp` (seen from `wo`) on this surface, at texture coordinates
    /// `uv` with ∂p/∂u `dpdu` (∂p/∂v from `dpdv`, asked only for a bump map): tilted by the
    /// normal or bump map, with the tangent where the BSDF is anisotropic (the module docs).
    pub fn shading_point(
        &self,
        sp: ShadingPoint,
        (uv, dpdu): (Vec2, Vec3),
        dpdv: impl FnOnce() -> Vec3,
        textures: &[Texture],
        wo: Vec3,
    ) -> ShadingPoint {
        let f = shading_frame(sp.ns, dpdu);
        let tilted = if let Some(t) = self.normalmap {
            normal_mapped(sp, &f, textures[t as usize].eval(uv), wo, self.map_in_twosided)
        } else if let Some(b) = self.bumpmap {
            let grad = textures[b.texture as usize].eval_1_grad(uv) * b.scale;
            bump_mapped(sp, &f, (dpdu, dpdv()), grad, wo, self.map_in_twosided)
        } else {
            Tilted { sp, s: f.s }
        };
        if !self.anisotropic {
            return tilted.sp;
        }
        ShadingPoint { s: tilted.s, ..tilted.sp }
    }

    /// Prefetches the texels `material_at` and `shading_point` at `uv` read: each parameter's
    /// texture and the normal or bump map's ([`Texture::prefetch`]). No effect on any value.
    #[inline]
    pub fn prefetch(&self, textures: &[Texture], uv: Vec2) {
        for t in &self.textures {
            textures[t.texture as usize].prefetch(uv);
        }
        if let Some(t) = self.normalmap.or(self.bumpmap.map(|b| b.texture)) {
            textures[t as usize].prefetch(uv);
        }
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

impl super::Scene {
    /// ∂p/∂v at the hit `sp` of primitive `prim` whose ∂p/∂u is `dpdu` (a bump map's second
    /// tangent): Mitsuba's for triangles ([`triangle_dpdv`]) and spheres ([`sphere_dpdv`]). The
    /// tessellated `disk` and `cylinder` (`Scene::shape_uvs`) record their ∂p/∂u only: there it is
    /// `ns × ∂p/∂u`, which has the direction of Mitsuba's ∂p/∂v (both shapes' are orthogonal to
    /// ∂p/∂u) but not its length (a bump map's slope along v on them is not Mitsuba's).
    pub(super) fn dpdv_at(&self, prim: u32, sp: ShadingPoint, dpdu: Vec3) -> Vec3 {
        if self.shape_uvs.get(prim).is_some() {
            return sp.ns.cross(dpdu);
        }
        if prim < self.ntri() {
            triangle_dpdv(&self.triangles[prim as usize])
        } else {
            sphere_dpdv(&self.spheres[(prim - self.ntri()) as usize], sp.p)
        }
    }
}

/// True for a BSDF whose local frame needs the tangent: an anisotropic microfacet roughness.
pub fn is_anisotropic(m: &Material) -> bool {
    match m {
        Material::RoughConductor(c) => !c.distribution.is_isotropic(),
        Material::RoughDielectric(d) => !d.distribution.is_isotropic(),
        _ => false,
    }
}

/// The texture coordinates and ∂p/∂u of a point `p` of triangle `t`, as Mitsuba's meshes give
/// them: interpolated UVs where the mesh has them, else the barycentric coordinates (b1, b2)
/// with ∂p/∂u = p1 − p0; where the UVs are degenerate (zero area), ∂p/∂u is the first tangent of
/// `coordinate_system(ng)` (`Frame::from_normal`), as Mitsuba's.
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
    let dpdu = if det != 0.0 { (e1 * duv1.y - e2 * duv0.y) * (1.0 / det) } else { Frame::from_normal(t.ng).s };
    (uv[0] + duv0 * b1 + duv1 * b2, dpdu)
}

/// ∂p/∂v of triangle `t` (the same at every point), as Mitsuba's meshes give it: from the UVs
/// where the mesh has them (`coordinate_system(ng)`'s second tangent where they are degenerate),
/// else p2 − p0.
pub fn triangle_dpdv(t: &Triangle) -> Vec3 {
    let (e1, e2) = (t.p[1] - t.p[0], t.p[2] - t.p[0]);
    let Some(uv) = t.uv else { return e2 };
    let (duv0, duv1) = (uv[1] - uv[0], uv[2] - uv[0]);
    let det = duv0.x * duv1.y - duv0.y * duv1.x;
    if det == 0.0 {
        return Frame::from_normal(t.ng).t;
    }
    (e2 * duv0.x - e1 * duv1.x) * (1.0 / det)
}

/// The point `p` of sphere `s` in its own frame (`Sphere::axes`), on the unit sphere.
fn sphere_local(s: &Sphere, p: Vec3) -> Vec3 {
    let d = p - s.center;
    Vec3::new(d.dot(s.axes[0]), d.dot(s.axes[1]), d.dot(s.axes[2])) / s.radius
}

/// The texture coordinates and ∂p/∂u of a point `p` of sphere `s`, as Mitsuba's `sphere`:
/// u = φ/2π, v = θ/π in the sphere's own frame (`Sphere::axes`).
pub fn sphere_uv(s: &Sphere, p: Vec3) -> (Vec2, Vec3) {
    let local = sphere_local(s, p);
    let theta = local.z.clamp(-1.0, 1.0).acos();
    let mut phi = local.y.atan2(local.x);
    if phi < 0.0 {
        phi += 2.0 * PI;
    }
    let dpdu_local = Vec3::new(-local.y, local.x, 0.0) * (2.0 * PI * s.radius);
    let dpdu = s.axes[0] * dpdu_local.x + s.axes[1] * dpdu_local.y;
    (Vec2::new(phi / (2.0 * PI), theta / PI), dpdu)
}

/// ∂p/∂v at a point `p` of sphere `s`, as Mitsuba's `sphere`: π·r·(z cos φ, z sin φ, −r_xy) in
/// its own frame (r_xy = √(x² + y²)), π·r·(1, 0, 0) at the poles.
pub fn sphere_dpdv(s: &Sphere, p: Vec3) -> Vec3 {
    let local = sphere_local(s, p);
    let rd = (local.x * local.x + local.y * local.y).sqrt();
    let d = if rd == 0.0 { Vec3::X } else { Vec3::new(local.z * local.x / rd, local.z * local.y / rd, -rd) }
        * (PI * s.radius);
    s.axes[0] * d.x + s.axes[1] * d.y + s.axes[2] * d.z
}

/// The shading frame around `n` with its tangent along `dpdu` (Gram–Schmidt), Mitsuba's
/// `sh_frame`; `coordinate_system(n)` (`Frame::from_normal`) where `dpdu` is parallel to `n`
/// or zero.
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

/// A shading point tilted by a map, and the tangent of the map's frame (unit, orthogonal to its
/// normal; zero where Mitsuba's would be undefined).
struct Tilted {
    sp: ShadingPoint,
    s: Vec3,
}

/// `v` with its component along the unit `n` removed, normalised; zero where nothing is left.
fn orthogonal_unit(v: Vec3, n: Vec3) -> Vec3 {
    (v - n * n.dot(v)).normalize_or_zero()
}

/// The frame a map's local normal `n` lives in, and `wo` as the map sees it in the shading frame
/// `f`: as it is, or for a map nested in `twosided` seen from behind, mirrored through the
/// surface (Mitsuba's `twosided` flips the local z first), the local frame then mapped to the
/// world by `f` turned half a turn about its normal (so that the tilted normal, flipped to
/// `wo`'s side by the BSDF's frame, is the mirror image of the front's).
fn map_space(f: &Frame, wo: Vec3, in_twosided: bool) -> (Frame, Vec3) {
    let wl = f.to_local(wo);
    if in_twosided && wl.z < 0.0 {
        (Frame { s: -f.s, t: -f.t, n: f.n }, Vec3::new(wl.x, wl.y, -wl.z))
    } else {
        (*f, wl)
    }
}

/// Mitsuba's `flip_invalid_normals`: the local normal `n` mirrored about the frame's normal where
/// `wl` lies on different sides of it and of the frame's normal.
#[inline]
fn flip_invalid(n: Vec3, wl: Vec3) -> Vec3 {
    if wl.z * wl.dot(n) <= 0.0 {
        Vec3::new(-n.x, -n.y, n.z)
    } else {
        n
    }
}

/// `sp` with its shading normal tilted by a tangent-space normal map of value `rgb` in the
/// shading frame `f` (Mitsuba's `normalmap`: n = 2·rgb − 1, flipped by `flip_invalid`), and
/// the map frame's tangent (the shading frame's `s` made orthogonal to n). `n0` keeps the
/// untilted normal for the shadowing term.
fn normal_mapped(sp: ShadingPoint, f: &Frame, rgb: Vec3, wo: Vec3, in_twosided: bool) -> Tilted {
    let (fw, wl) = map_space(f, wo, in_twosided);
    let n = flip_invalid(rgb * 2.0 - Vec3::ONE, wl).normalize_or_zero();
    if n == Vec3::ZERO {
        return Tilted { sp, s: f.s };
    }
    let s = fw.to_world(orthogonal_unit(Vec3::X, n));
    Tilted { sp: ShadingPoint { ns: fw.to_world(n).normalize(), n0: f.n, ..sp }, s }
}

/// `sp` with its shading normal tilted by a bump map whose height has the gradient `grad`
/// (`scale` included) in uv, on a surface with ∂p/∂u and ∂p/∂v `dp`, in the shading frame `f`
/// (Mitsuba's `bumpmap`, the module docs), and the bump frame's tangent. Where the perturbed
/// tangents are parallel (no normal), the point is left as it is.
fn bump_mapped(
    sp: ShadingPoint,
    f: &Frame,
    (dpdu, dpdv): (Vec3, Vec3),
    grad: Vec2,
    wo: Vec3,
    in_twosided: bool,
) -> Tilted {
    let n = f.n;
    let du = dpdu + n * (grad.x - n.dot(dpdu));
    let dv = dpdv + n * (grad.y - n.dot(dpdv));
    let nb = du.cross(dv).normalize_or_zero();
    if nb == Vec3::ZERO {
        return Tilted { sp, s: f.s };
    }
    let nb = if sp.ng.dot(nb) < 0.0 { -nb } else { nb };
    let (fw, wl) = map_space(f, wo, in_twosided);
    let nl = flip_invalid(f.to_local(nb), wl);
    // Mitsuba's bump frame's s: ∂p/∂u's world components against the local normal
    let s = fw.to_world(orthogonal_unit(dpdu, nl));
    Tilted { sp: ShadingPoint { ns: fw.to_world(nl).normalize(), n0: f.n, ..sp }, s }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bsdf::microfacet::{MicrofacetDistribution, MicrofacetKind};
    use crate::bsdf::roughconductor::RoughConductor;
    use crate::bsdf::{self, Mode};
    use crate::scene::NO_EMITTER;

    fn close(a: Vec3, b: Vec3, tol: f32) -> bool {
        (a - b).abs().max_element() <= tol * b.abs().max_element().max(1.0)
    }

    fn triangle(p: [Vec3; 3], uv: Option<[Vec2; 3]>) -> Triangle {
        let ng = (p[1] - p[0]).cross(p[2] - p[0]).normalize();
        Triangle { p, n: None, uv, ng, area: 1.0, material: 0, emitter: NO_EMITTER }
    }

    /// A triangle's ∂p/∂u and ∂p/∂v map its UV edges onto its edges (p is affine in uv), as
    /// Mitsuba's mesh computes them; without UVs they are its edges from p0; with degenerate UVs
    /// `coordinate_system(ng)`.
    #[test]
    fn triangle_tangents_are_mitsubas() {
        let p = [Vec3::new(0.3, -0.2, 1.0), Vec3::new(1.4, 0.5, 0.7), Vec3::new(-0.1, 1.2, 0.4)];
        let uv = [Vec2::new(0.1, 0.2), Vec2::new(0.9, 0.35), Vec2::new(0.25, 1.1)];
        let t = triangle(p, Some(uv));
        let (at, dpdu) = triangle_uv(&t, p[0] * 0.2 + p[1] * 0.5 + p[2] * 0.3);
        assert!((at - (uv[0] * 0.2 + uv[1] * 0.5 + uv[2] * 0.3)).length() < 1e-5);
        let dpdv = triangle_dpdv(&t);
        for k in 1..3 {
            let (duv, dp) = (uv[k] - uv[0], p[k] - p[0]);
            assert!(close(dpdu * duv.x + dpdv * duv.y, dp, 1e-5), "edge {k}");
        }
        let bare = triangle(p, None);
        assert_eq!((triangle_uv(&bare, p[0]).1, triangle_dpdv(&bare)), (p[1] - p[0], p[2] - p[0]));
        let flat = triangle(p, Some([Vec2::ZERO, Vec2::X, Vec2::new(2.0, 0.0)]));
        let f = Frame::from_normal(flat.ng);
        assert_eq!((triangle_uv(&flat, p[1]).1, triangle_dpdv(&flat)), (f.s, f.t));
    }

    /// A sphere's ∂p/∂u and ∂p/∂v are the derivatives of Mitsuba's parametrisation, p = c + r·R
    /// (sin θ cos φ, sin θ sin φ, cos θ) with φ = 2πu, θ = πv, in its own frame `R`; and its
    /// uv reads back.
    #[test]
    fn sphere_tangents_are_the_derivatives() {
        let r = 0.7;
        let a = Frame::from_normal(Vec3::new(0.3, -0.5, 0.8).normalize());
        let s = Sphere {
            center: Vec3::new(0.2, 1.0, -0.4),
            radius: r,
            inward: false,
            axes: [a.s, a.t, a.n],
            material: 0,
            emitter: NO_EMITTER,
        };
        let world = |v: Vec3| a.s * v.x + a.t * v.y + a.n * v.z;
        for (u, v) in [(0.1, 0.3), (0.45, 0.8), (0.7, 0.05), (0.93, 0.52)] {
            let (phi, theta) = (2.0 * PI * u, PI * v);
            let (st, ct, sp, cp) = (theta.sin(), theta.cos(), phi.sin(), phi.cos());
            let p = s.center + world(Vec3::new(st * cp, st * sp, ct)) * r;
            let (uv, dpdu) = sphere_uv(&s, p);
            assert!((uv - Vec2::new(u, v)).length() < 1e-5, "{uv} vs {u}, {v}");
            let want_u = world(Vec3::new(-st * sp, st * cp, 0.0)) * (2.0 * PI * r);
            let want_v = world(Vec3::new(ct * cp, ct * sp, -st)) * (PI * r);
            assert!(close(dpdu, want_u, 1e-5) && close(sphere_dpdv(&s, p), want_v, 1e-5), "{u}, {v}");
        }
        // exactly at a pole (in an axis-aligned frame): ∂p/∂u is zero and ∂p/∂v Mitsuba's
        // π·r·(1, 0, 0)
        let s = Sphere { axes: [Vec3::X, Vec3::Y, Vec3::Z], ..s };
        let pole = s.center + Vec3::Z * r;
        assert_eq!(sphere_uv(&s, pole).1, Vec3::ZERO);
        assert!(close(sphere_dpdv(&s, pole), Vec3::X * (PI * r), 1e-6));
    }

    /// A flat point facing +z, ∂p/∂u = (2, 0, 0), ∂p/∂v = (0, 3, 0).
    fn flat() -> (ShadingPoint, Frame, (Vec3, Vec3)) {
        let sp = ShadingPoint::new(Vec3::ZERO, Vec3::Z, Vec3::Z);
        let dp = (Vec3::new(2.0, 0.0, 0.0), Vec3::new(0.0, 3.0, 0.0));
        (sp, shading_frame(Vec3::Z, dp.0), dp)
    }

    /// Mitsuba's bump normal on a flat surface: ∂p/∂u' × ∂p/∂v' with the slopes added along the
    /// normal, (−g_u·|∂p/∂v|, −g_v·|∂p/∂u|, |∂p/∂u|·|∂p/∂v|) normalised; zero slopes leave the
    /// normal; the frame's tangent is unit and orthogonal to it.
    #[test]
    fn bump_normals_are_the_height_fields() {
        let (sp, f, dp) = flat();
        let wo = Vec3::new(0.2, -0.3, 0.9).normalize();
        let t = bump_mapped(sp, &f, dp, Vec2::ZERO, wo, false);
        assert!(close(t.sp.ns, Vec3::Z, 1e-6) && t.sp.n0 == Vec3::Z);
        for g in [Vec2::new(0.5, -0.25), Vec2::new(-3.0, 1.5), Vec2::new(0.0, 4.0)] {
            let t = bump_mapped(sp, &f, dp, g, wo, false);
            let want = Vec3::new(-g.x * 3.0, -g.y * 2.0, 6.0).normalize();
            assert!(close(t.sp.ns, want, 1e-6), "{g}: {} vs {want}", t.sp.ns);
            assert!((t.s.length() - 1.0).abs() < 1e-5 && t.s.dot(t.sp.ns).abs() < 1e-5, "{g}: s {}", t.s);
        }
    }

    /// A map nested in `twosided` seen from behind is the front's seen from the mirrored
    /// direction, mirrored back through the surface: in the shading frame, the stored normal (on
    /// the front side, flipped by the BSDF's frame) and the tangent have their tangential parts
    /// negated. A map around `twosided` sees the real direction.
    #[test]
    fn twosided_mirrors_a_map_seen_from_behind() {
        let (sp, f, dp) = flat();
        let back = Vec3::new(0.3, 0.5, -0.6).normalize();
        let mirrored = Vec3::new(back.x, back.y, -back.z);
        let r = |v: Vec3| Vec3::new(-v.x, -v.y, v.z);
        let g = Vec2::new(0.7, -1.1);
        let (bump_back, bump_front) =
            (bump_mapped(sp, &f, dp, g, back, true), bump_mapped(sp, &f, dp, g, mirrored, false));
        let rgb = Vec3::new(0.75, 0.35, 0.8);
        let (nm_back, nm_front) = (normal_mapped(sp, &f, rgb, back, true), normal_mapped(sp, &f, rgb, mirrored, false));
        for (b, fr) in [(bump_back, bump_front), (nm_back, nm_front)] {
            assert!(close(b.sp.ns, r(fr.sp.ns), 1e-6), "{} vs {}", b.sp.ns, fr.sp.ns);
            assert!(close(b.s, r(fr.s), 1e-6));
        }
        // around twosided, from behind: the map's own normal, as from the front
        let outside = normal_mapped(sp, &f, rgb, back, false);
        assert!(close(outside.sp.ns, (rgb * 2.0 - Vec3::ONE).normalize(), 1e-6));
    }

    fn aniso(au: f32, av: f32) -> Material {
        Material::RoughConductor(RoughConductor {
            distribution: MicrofacetDistribution::new(MicrofacetKind::Ggx, au, av, true),
            eta: Vec3::new(0.2, 0.92, 1.1),
            k: Vec3::new(3.9, 2.45, 2.2),
            specular_reflectance: Vec3::ONE,
        })
    }

    /// The BSDF's frame takes the tangent: an anisotropic BSDF with its tangent turned a quarter
    /// turn about the normal is the same BSDF with alpha_u and alpha_v swapped; without a tangent
    /// (an isotropic surface) `shading_point` leaves it zero, with one it is unit and orthogonal
    /// to the (tilted) normal.
    #[test]
    fn the_local_frame_is_oriented_by_the_tangent() {
        let n = Vec3::new(0.2, 0.3, 0.9).normalize();
        let f = shading_frame(n, Vec3::new(1.0, 0.4, -0.2));
        let at = |s: Vec3| ShadingPoint { s, ..ShadingPoint::new(Vec3::ZERO, n, n) };
        let (wo, wi) = (Vec3::new(0.5, -0.2, 0.8).normalize(), Vec3::new(-0.3, 0.6, 0.7).normalize());
        let a = bsdf::eval(&aniso(0.05, 0.4), &at(f.s), wo, wi, Mode::Radiance);
        let b = bsdf::eval(&aniso(0.4, 0.05), &at(f.t), wo, wi, Mode::Radiance);
        let c = bsdf::eval(&aniso(0.05, 0.4), &at(f.t), wo, wi, Mode::Radiance);
        assert!(close(a, b, 1e-4) && !close(a, c, 0.1), "{a} {b} {c}");

        let sp = ShadingPoint::new(Vec3::ZERO, n, n);
        let uvd = (Vec2::new(0.3, 0.6), Vec3::new(1.0, 0.4, -0.2));
        let textures = [Texture::Constant(Vec3::new(0.6, 0.45, 0.9))];
        let dpdv = || n.cross(uvd.1);
        let iso = Surface::of(&Material::Diffuse { albedo: Vec3::ONE });
        assert!(iso.is_constant());
        assert_eq!(iso.shading_point(sp, uvd, dpdv, &textures, wo).s, Vec3::ZERO);
        let mapped = Surface { normalmap: Some(0), ..iso.clone() };
        assert_eq!(mapped.shading_point(sp, uvd, dpdv, &textures, wo).s, Vec3::ZERO);
        let an = Surface::of(&aniso(0.05, 0.4));
        assert!(an.anisotropic && !an.is_constant());
        for s in [
            an.clone(),
            Surface { normalmap: Some(0), ..an.clone() },
            Surface { bumpmap: Some(BumpMap { texture: 0, scale: 1.0 }), ..an.clone() },
        ] {
            let p = s.shading_point(sp, uvd, dpdv, &textures, wo);
            assert!((p.s.length() - 1.0).abs() < 1e-5 && p.s.dot(p.ns).abs() < 1e-5, "{s:?}: {p:?}");
        }
        // no map: Mitsuba's sh_frame.s
        assert!(close(an.shading_point(sp, uvd, dpdv, &textures, wo).s, f.s, 1e-6));
    }
}
