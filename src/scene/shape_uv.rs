//! The texture coordinates and ∂p/∂u of every primitive ([`Scene::uv_at`]), as Mitsuba 3's shapes
//! give them. Meshes (and `rectangle`, `cube`) interpolate their per-vertex UVs, spheres are
//! analytic (both in `surface`). Mitsuba's `disk` and `cylinder` are analytic shapes that forecast
//! tessellates; interpolating per-vertex UVs over the triangles would not be Mitsuba's
//! parametrisation (the disk's r is not linear over a fan triangle, and both have a seam in φ), so
//! their triangles carry a [`ShapeUv`] instead: the shape's map from world space to its local
//! frame, where uv and ∂p/∂u are Mitsuba's formulas of the hit point:
//!
//! - `disk` (disk.cpp): the unit disk at z = 0; u = r, v = φ/2π in [0, 1), ∂p/∂u =
//!   `to_world`·(cos φ, sin φ, 0) (zero at the centre).
//! - `cylinder` (cylinder.cpp): the unit cylinder around +z from z = 0 to 1, mapped by `to_world` ·
//!   translate(p0) · frame(p1 − p0) · scale(r, r, |p1 − p0|); u = φ/2π in [0, 1), v = z, ∂p/∂u =
//!   `to_world`·2π(−sin φ, cos φ, 0), the hit point first projected radially onto the analytic
//!   cylinder (as Mitsuba's `FollowShape` branch does).
//!
//! Invariants: a hit on the tessellation lies within r(1 − cos(π/N)) = 1.9e-5 r of the analytic
//! surface (`mitsuba::SEGMENTS`), so uv differs from Mitsuba's at the same ray by at most that
//! distance's tangential part over the parametrisation's scale (`tests/shape_uvs.rs` holds it to
//! Mitsuba's own values); the disk's hits lie on its plane, so its uv is exact to rounding. The
//! records cost a hit nothing unless its material is textured or normal-mapped (`Scene::shade`
//! asks for uv only then). A shape's triangles are consecutive primitive ids (the builder adds them
//! in order), so the records are kept as sorted primitive ranges.

use super::{surface, Scene};
use crate::math::{Vec2, Vec3};
use glam::{DAffine3, DMat4, DVec3};
use std::f64::consts::TAU;

/// Which of Mitsuba's analytic parametrisations a tessellated shape has.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShapeKind {
    /// Mitsuba's `disk`: (r, φ/2π).
    Disk,
    /// Mitsuba's `cylinder`: (φ/2π, z).
    Cylinder,
}

/// One shape's parametrisation: its kind and its local frame.
#[derive(Clone, Debug, PartialEq)]
pub struct ShapeUv {
    /// The parametrisation.
    pub kind: ShapeKind,
    /// World space → the shape's local frame (the inverse of `to_world`).
    to_local: DAffine3,
    /// Local → world, for ∂p/∂u.
    to_world: DAffine3,
}

impl ShapeUv {
    /// The parametrisation `kind` of a shape whose local frame `to_world` maps to world space;
    /// `None` when `to_world` is not invertible (the shape then has no area either).
    pub fn new(kind: ShapeKind, to_world: DMat4) -> Option<ShapeUv> {
        let to_world = DAffine3::from_mat4(to_world);
        let det = to_world.matrix3.determinant();
        if !(det.is_finite() && det != 0.0) {
            return None;
        }
        let to_local = to_world.inverse();
        to_local.is_finite().then_some(ShapeUv { kind, to_local, to_world })
    }

    /// The shape's `to_world`: Mitsuba's `disk`, or `cylinder` with its default `p0`, `p1` and
    /// `radius`, under this matrix is the shape this parametrisation belongs to.
    pub fn to_world(&self) -> DMat4 {
        DMat4::from(self.to_world)
    }

    /// The direction of Mitsuba's normal (`flip_normals` false) at the world-space point `p`: the
    /// local (0, 0, 1) of the disk, (x, y, 0) of the cylinder, mapped as a normal (the inverse
    /// transpose of `to_world`); not normalised.
    pub fn normal_at(&self, p: Vec3) -> Vec3 {
        let n = match self.kind {
            ShapeKind::Disk => DVec3::Z,
            ShapeKind::Cylinder => {
                let q = self.to_local.transform_point3(p.as_dvec3());
                DVec3::new(q.x, q.y, 0.0)
            }
        };
        (self.to_local.matrix3.transpose() * n).as_vec3()
    }

    /// Mitsuba's uv and ∂p/∂u at the world-space point `p` of the shape.
    pub fn at(&self, p: Vec3) -> (Vec2, Vec3) {
        let q = self.to_local.transform_point3(p.as_dvec3());
        let r = q.x.hypot(q.y);
        let inv_r = if r > 0.0 { 1.0 / r } else { 0.0 };
        let (cos, sin) = (q.x * inv_r, q.y * inv_r);
        let mut phi = q.y.atan2(q.x) / TAU;
        if phi < 0.0 {
            phi += 1.0;
        }
        let (uv, dpdu) = match self.kind {
            ShapeKind::Disk => ((r, phi), DVec3::new(cos, sin, 0.0)),
            ShapeKind::Cylinder => ((phi, q.z), DVec3::new(-sin, cos, 0.0) * TAU),
        };
        let dpdu = self.to_world.transform_vector3(dpdu);
        (Vec2::new(uv.0 as f32, uv.1 as f32), dpdu.as_vec3())
    }
}

/// The primitives that carry a [`ShapeUv`]: sorted, disjoint ranges of triangle ids.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ShapeUvs {
    /// (first, end, parametrisation): triangles `first..end`.
    runs: Vec<(u32, u32, ShapeUv)>,
}

impl ShapeUvs {
    /// The ranges of the shapes in `shapes` (shape id, its parametrisation), given each
    /// triangle's shape id (`tri_shape`, a shape's triangles consecutive).
    pub(super) fn new(tri_shape: &[u32], shapes: &[(u32, ShapeUv)]) -> ShapeUvs {
        let mut runs = Vec::new();
        let mut first = 0;
        while first < tri_shape.len() {
            let s = tri_shape[first];
            let end = first + tri_shape[first..].iter().take_while(|&&t| t == s).count();
            if let Some((_, uv)) = shapes.iter().find(|(id, _)| *id == s) {
                runs.push((first as u32, end as u32, uv.clone()));
            }
            first = end;
        }
        ShapeUvs { runs }
    }

    /// The parametrisation of primitive `prim`, if it has one.
    #[inline]
    pub fn get(&self, prim: u32) -> Option<&ShapeUv> {
        self.run(prim).map(|r| r.2)
    }

    /// The shape primitive `prim` belongs to, if it has a parametrisation: its triangles
    /// `first..end` and the parametrisation.
    pub fn run(&self, prim: u32) -> Option<(u32, u32, &ShapeUv)> {
        let i = self.runs.partition_point(|r| r.1 <= prim);
        self.runs.get(i).filter(|r| r.0 <= prim).map(|r| (r.0, r.1, &r.2))
    }
}

impl Scene {
    /// The texture coordinates and ∂p/∂u of the point `p` of primitive `prim`, as Mitsuba gives
    /// them (see the module docs).
    pub fn uv_at(&self, prim: u32, p: Vec3) -> (Vec2, Vec3) {
        if let Some(s) = self.shape_uvs.get(prim) {
            return s.at(p);
        }
        if prim < self.ntri() {
            surface::triangle_uv(&self.triangles[prim as usize], p)
        } else {
            surface::sphere_uv(&self.spheres[(prim - self.ntri()) as usize], p)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_find_their_primitives() {
        let uv = ShapeUv::new(ShapeKind::Disk, DMat4::IDENTITY).unwrap();
        let cyl = ShapeUv::new(ShapeKind::Cylinder, DMat4::IDENTITY).unwrap();
        // shapes 0 (2 tris), 1 (3, a disk), 2 (1), 3 (2, a cylinder)
        let s = ShapeUvs::new(&[0, 0, 1, 1, 1, 2, 3, 3], &[(1, uv), (3, cyl)]);
        let kinds: Vec<_> = (0..10).map(|p| s.get(p).map(|u| u.kind)).collect();
        let (d, c) = (Some(ShapeKind::Disk), Some(ShapeKind::Cylinder));
        assert_eq!(kinds, [None, None, d, d, d, None, c, c, None, None]);
        assert_eq!(ShapeUvs::default().get(0), None);
    }

    #[test]
    fn singular_maps_have_no_parametrisation() {
        let flat = DMat4::from_scale(DVec3::new(1.0, 0.0, 1.0));
        assert!(ShapeUv::new(ShapeKind::Cylinder, flat).is_none());
        assert!(ShapeUv::new(ShapeKind::Disk, DMat4::from_scale(DVec3::splat(f64::NAN))).is_none());
    }

    #[test]
    fn local_formulas() {
        // the unit disk and cylinder: φ = 3π/2 → v (disk) or u (cylinder) = 0.75
        let d = ShapeUv::new(ShapeKind::Disk, DMat4::IDENTITY).unwrap();
        let (uv, dpdu) = d.at(Vec3::new(0.0, -0.5, 0.0));
        assert!((uv - Vec2::new(0.5, 0.75)).length() < 1e-7 && (dpdu - Vec3::new(0.0, -1.0, 0.0)).length() < 1e-7);
        assert_eq!(d.at(Vec3::ZERO), (Vec2::ZERO, Vec3::ZERO));
        let c = ShapeUv::new(ShapeKind::Cylinder, DMat4::from_scale(DVec3::new(2.0, 2.0, 3.0))).unwrap();
        // a point inside the analytic surface (on a chord) projects radially
        let (uv, dpdu) = c.at(Vec3::new(0.0, -1.99, 1.5));
        let tau = std::f32::consts::TAU;
        assert!((uv - Vec2::new(0.75, 0.5)).length() < 1e-7 && (dpdu - Vec3::new(2.0 * tau, 0.0, 0.0)).length() < 1e-5);
    }
}
