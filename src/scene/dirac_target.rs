//! The spheres the targeted emission aims at (`transport::target`, [BAJ08 §3.2]): one per
//! Dirac object, merged down to at most `MAX_TARGETS`.
//!
//! An object is a connected set of Dirac triangles (sharing a vertex position, bit for bit), or
//! one Dirac analytic sphere. Its sphere is centred on its bounding box and reaches its farthest
//! vertex (for a ring or a cylinder, √2 smaller than the box's circumsphere). While there are
//! more than `MAX_TARGETS`, the pair whose enclosing sphere adds the least `Σ r²` (a cone's solid
//! angle is ≈ π r²/d² from afar) is merged. Past [`MAX_OBJECTS`] objects (triangle soup, shards)
//! the target is the one sphere around all of them ([`Scene::dirac_sphere`]).
//!
//! Invariants: every Dirac primitive lies inside one of the spheres (radii padded by
//! [`SPHERE_PAD`] against rounding); the result is a pure function of the scene.

use super::Scene;
use crate::math::Vec3;
use std::collections::HashMap;

/// Relative padding of the radii: the vertex that defines a radius lies on its sphere, and a
/// direction to it must stay inside the emission cone after f32 rounding.
pub const SPHERE_PAD: f32 = 1e-4;

/// The most target spheres (`transport::target::Targets` holds this many).
pub const MAX_TARGETS: usize = 8;

/// Objects beyond which the spheres are not merged pairwise (that costs O(n²) per merge).
pub const MAX_OBJECTS: usize = 256;

impl Scene {
    /// One sphere `(centre, radius)` holding every Dirac primitive, if any: the sphere of all of
    /// them as one object (centred on [`Scene::dirac_bounds`]' box, reaching the farthest vertex
    /// or sphere surface).
    pub fn dirac_sphere(&self) -> Option<(Vec3, f32)> {
        self.dirac_bounds()?;
        let dirac = |m: u32| self.materials[m as usize].is_dirac();
        let tri = self.triangles.iter().filter(|t| dirac(t.material)).flat_map(|t| t.p).map(|p| (p, 0.0));
        let sph = self.spheres.iter().filter(|s| dirac(s.material)).map(|s| (s.center, s.radius));
        Some(around(tri.chain(sph)))
    }

    /// The target spheres (at most `MAX_TARGETS`; empty without Dirac primitives): see the
    /// module docs.
    pub fn dirac_spheres(&self) -> Vec<(Vec3, f32)> {
        let mut objects = self.dirac_objects();
        if objects.len() > MAX_OBJECTS {
            return self.dirac_sphere().into_iter().collect();
        }
        while objects.len() > MAX_TARGETS {
            let mut best = (f32::INFINITY, 0, 1, (Vec3::ZERO, 0.0));
            for i in 0..objects.len() {
                for j in i + 1..objects.len() {
                    let m = enclose(objects[i], objects[j]);
                    let cost = m.1 * m.1 - objects[i].1 * objects[i].1 - objects[j].1 * objects[j].1;
                    if cost < best.0 {
                        best = (cost, i, j, m);
                    }
                }
            }
            let (_, i, j, m) = best;
            objects[i] = m;
            objects.swap_remove(j);
        }
        objects
    }

    /// The sphere of each Dirac object (padded), triangles' objects first, in order of their
    /// first triangle.
    fn dirac_objects(&self) -> Vec<(Vec3, f32)> {
        let dirac = |m: u32| self.materials[m as usize].is_dirac();
        let tris: Vec<usize> = (0..self.triangles.len()).filter(|&i| dirac(self.triangles[i].material)).collect();
        // union-find over the Dirac triangles, joined through shared vertex positions
        let mut parent: Vec<usize> = (0..tris.len()).collect();
        let mut first_at: HashMap<[u32; 3], usize> = HashMap::new();
        for (k, &t) in tris.iter().enumerate() {
            for p in self.triangles[t].p {
                let o = *first_at.entry(p.to_array().map(f32::to_bits)).or_insert(k);
                let (a, b) = (root(&mut parent, o), root(&mut parent, k));
                parent[a.max(b)] = a.min(b);
            }
        }
        let mut members: Vec<Vec<Vec3>> = Vec::new();
        let mut index: HashMap<usize, usize> = HashMap::new();
        for (k, &t) in tris.iter().enumerate() {
            let r = root(&mut parent, k);
            let i = *index.entry(r).or_insert_with(|| {
                members.push(Vec::new());
                members.len() - 1
            });
            members[i].extend(self.triangles[t].p);
        }
        let mut objects: Vec<(Vec3, f32)> = members.iter().map(|ps| around(ps.iter().map(|&p| (p, 0.0)))).collect();
        objects.extend(
            self.spheres.iter().filter(|s| dirac(s.material)).map(|s| around([(s.center, s.radius)].into_iter())),
        );
        objects
    }
}

/// The root of `i` (path halving).
fn root(parent: &mut [usize], mut i: usize) -> usize {
    while parent[i] != i {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    i
}

/// The padded sphere around balls `(centre, radius)`, centred on their bounding box.
fn around(balls: impl Iterator<Item = (Vec3, f32)> + Clone) -> (Vec3, f32) {
    let (lo, hi) =
        balls.clone().fold((Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)), |(lo, hi), (c, r)| {
            (lo.min(c - Vec3::splat(r)), hi.max(c + Vec3::splat(r)))
        });
    let c = 0.5 * (lo + hi);
    let r = balls.map(|(p, r)| p.distance(c) + r).fold(0.0f32, f32::max);
    (c, (r * (1.0 + SPHERE_PAD)).max(1e-6))
}

/// The smallest sphere holding spheres `a` and `b` (padded again: its centre is rounded).
fn enclose(a: (Vec3, f32), b: (Vec3, f32)) -> (Vec3, f32) {
    let d = a.0.distance(b.0);
    if d + b.1 <= a.1 {
        return a;
    }
    if d + a.1 <= b.1 {
        return b;
    }
    let r = 0.5 * (d + a.1 + b.1);
    let c = a.0 + (b.0 - a.0) * ((r - a.1) / d);
    (c, r * (1.0 + SPHERE_PAD))
}
