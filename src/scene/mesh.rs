//! The mesh types the file readers (`obj`, `ply`) produce and the loaders consume: an indexed
//! mesh as stored in a file, and the flat per-triangle `Mesh` of the TOML loader. The lowest of
//! the mesh modules: `obj` and `ply` import it, it imports neither.
//!
//! Invariants: `IndexedMesh::normals` and `uvs`, when present, have one entry per position;
//! every face index is below `positions.len()` (the readers check these).

use crate::math::{Vec2, Vec3};

/// An indexed triangle mesh as stored in a file (OBJ or PLY).
#[derive(Clone, Debug)]
pub struct IndexedMesh {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Per-vertex normals, when the file has them.
    pub normals: Option<Vec<Vec3>>,
    /// Per-vertex texture coordinates, when the file has them (as written: OBJ's `v` flip is
    /// the Mitsuba reader's `flip_tex_coords`).
    pub uvs: Option<Vec<Vec2>>,
    /// Triangles (indices into `positions`).
    pub faces: Vec<[u32; 3]>,
    /// Hash of the file bytes (scene hashing).
    pub bytes_hash: u64,
}

/// A loaded triangle mesh (the TOML loader's form).
pub struct Mesh {
    /// Triangle vertex positions.
    pub triangles: Vec<[Vec3; 3]>,
    /// Per-triangle vertex normals (smooth meshes only).
    pub normals: Option<Vec<[Vec3; 3]>>,
    /// Per-triangle texture coordinates (meshes with UVs).
    pub uvs: Option<Vec<[Vec2; 3]>>,
    /// Hash of the file bytes (scene hashing).
    pub bytes_hash: u64,
}

impl Mesh {
    /// Triangles of `m` and, for smooth shading, its normals or area-weighted vertex normals.
    pub fn from_indexed(m: &IndexedMesh, smooth: bool) -> Mesh {
        let p = |f: &[u32; 3]| f.map(|i| m.positions[i as usize]);
        let file_normals = m.normals.clone().filter(|n| n.len() == m.positions.len());
        let vn = smooth.then(|| file_normals.unwrap_or_else(|| area_weighted_normals(m)));
        Mesh {
            triangles: m.faces.iter().map(p).collect(),
            normals: vn.map(|vn| m.faces.iter().map(|f| f.map(|i| vn[i as usize])).collect()),
            uvs: m.uvs.as_ref().map(|t| m.faces.iter().map(|f| f.map(|i| t[i as usize])).collect()),
            bytes_hash: m.bytes_hash,
        }
    }
}

/// Area-weighted vertex normals (unnormalised sums of face cross products).
pub fn area_weighted_normals(m: &IndexedMesh) -> Vec<Vec3> {
    let mut vn = vec![Vec3::ZERO; m.positions.len()];
    for f in &m.faces {
        let [a, b, c] = f.map(|i| m.positions[i as usize]);
        let n = (b - a).cross(c - a);
        f.iter().for_each(|&i| vn[i as usize] += n);
    }
    vn
}
