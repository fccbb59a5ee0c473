//! OBJ meshes via tobj (the only module that touches tobj): triangulated positions and, for
//! smooth shading, per-vertex normals (the file's `vn`, else area-weighted vertex normals), and
//! texture coordinates (`vt`).
//!
//! Invariants: degenerate faces are returned as-is; the caller skips them with a warning.

use crate::math::{Vec2, Vec3};
use std::path::Path;

use super::mesh::{IndexedMesh, Mesh};

/// Loads an OBJ file as the TOML loader's flat `Mesh` (`Mesh::from_indexed`); errors are
/// messages that name the file.
pub fn load_mesh(path: &Path, smooth: bool) -> Result<Mesh, String> {
    Ok(Mesh::from_indexed(&load_indexed(path)?, smooth))
}

/// Loads an OBJ file as one indexed mesh (all objects merged; a vertex per distinct
/// position/normal/uv index triple, as Mitsuba's OBJ loader keys them).
pub fn load_indexed(path: &Path) -> Result<IndexedMesh, String> {
    let (models, bytes_hash) = read_models(path)?;
    let (mut positions, mut normals, mut faces) = (Vec::new(), Vec::new(), Vec::new());
    let mut uvs = Vec::new();
    let (mut all_normals, mut all_uvs) = (true, true);
    for m in &models {
        let mesh = &m.mesh;
        let base = positions.len() as u32;
        let nv = mesh.positions.len() / 3;
        positions.extend(mesh.positions.chunks_exact(3).map(|s| Vec3::new(s[0], s[1], s[2])));
        all_normals &= mesh.normals.len() == mesh.positions.len() && !mesh.normals.is_empty();
        normals.extend(mesh.normals.chunks_exact(3).map(|s| Vec3::new(s[0], s[1], s[2])));
        all_uvs &= mesh.texcoords.len() == 2 * nv && nv > 0;
        // `vt` has its origin at the bottom left, an image at the top left: v is flipped (Mitsuba's
        // `flip_tex_coords`, default true)
        uvs.extend(mesh.texcoords.chunks_exact(2).map(|s| Vec2::new(s[0], 1.0 - s[1])));
        for f in mesh.indices.chunks_exact(3) {
            if f.iter().any(|&i| i as usize >= nv) {
                return Err(format!("OBJ `{}`: face index out of range", path.display()));
            }
            faces.push([base + f[0], base + f[1], base + f[2]]);
        }
    }
    if faces.is_empty() {
        return Err(format!("OBJ `{}` has no faces", path.display()));
    }
    let normals = (all_normals && normals.len() == positions.len()).then_some(normals);
    let uvs = (all_uvs && uvs.len() == positions.len()).then_some(uvs);
    if let Some(k) = uvs.iter().flatten().position(|t| !t.is_finite()) {
        return Err(format!("OBJ `{}`: texture coordinate {} is not finite", path.display(), k + 1));
    }
    Ok(IndexedMesh { positions, normals, uvs, faces, bytes_hash })
}

/// Reads and parses an OBJ file (a regular file only: a FIFO would block), triangulated with one
/// index per vertex; returns its models and the hash of its bytes.
fn read_models(path: &Path) -> Result<(Vec<tobj::Model>, u64), String> {
    super::limits::check_regular_file(path, "OBJ")?;
    let bytes = std::fs::read(path).map_err(|e| format!("cannot read OBJ `{}`: {e}", path.display()))?;
    let bytes_hash = crate::math::fnv1a(0xcbf2_9ce4_8422_2325, &bytes);
    let opts = tobj::LoadOptions { triangulate: true, single_index: true, ..Default::default() };
    let mut reader = std::io::BufReader::new(&bytes[..]);
    let (models, _) =
        tobj::load_obj_buf(&mut reader, &opts, |_| Err(tobj::LoadError::OpenFileFailed)).map_err(|e| {
            // tobj names no line: find the first statement at fault ourselves
            let at = first_bad_line(&bytes).unwrap_or_else(|| format!("{e}"));
            format!("cannot parse OBJ `{}`: {at}", path.display())
        })?;
    Ok((models, bytes_hash))
}

/// The first `v`/`vn`/`vt` line whose numbers do not parse, or `f`/`l`/`p` line with an index
/// that is zero, unparsable or past the vertices defined before it, as `line N: `f`: ...`.
fn first_bad_line(bytes: &[u8]) -> Option<String> {
    let text = String::from_utf8_lossy(bytes);
    let mut counts = [0usize; 3]; // v, vt, vn
    for (i, raw) in text.lines().enumerate() {
        let line = raw.split('#').next().unwrap_or("");
        let mut w = line.split_whitespace();
        let Some(kw) = w.next() else { continue };
        let bad = |m: String| Some(format!("line {}: `{kw}` statement: {m}: `{}`", i + 1, raw.trim()));
        let need = match kw {
            "v" => (0, 3, "position"),
            "vt" => (1, 1, "texture coordinate"),
            "vn" => (2, 3, "normal"),
            "f" | "l" | "p" => {
                if let Some(m) = w.find_map(|t| bad_face_vertex(t, &counts)) {
                    return bad(m);
                }
                continue;
            }
            _ => continue,
        };
        let nums: Vec<&str> = w.take(need.1).collect();
        if nums.len() < need.1 || nums.iter().any(|t| t.parse::<f32>().is_err()) {
            return bad(format!("{} parse error (needs {} numbers)", need.2, need.1));
        }
        counts[need.0] += 1;
    }
    None
}

/// What is wrong with one `v/vt/vn` reference of a face, given the counts defined so far.
fn bad_face_vertex(t: &str, counts: &[usize; 3]) -> Option<String> {
    for (k, part) in t.split('/').enumerate().take(3) {
        if part.is_empty() {
            continue;
        }
        let what = ["v", "vt", "vn"][k];
        let n = counts[k];
        let Ok(i) = part.parse::<i64>() else { return Some(format!("`{part}` is not an index")) };
        if i == 0 {
            return Some(format!("face {what} index 0 (OBJ indices start at 1)"));
        }
        if i.unsigned_abs() > n as u64 {
            return Some(format!("face {what} index {i} out of range ({n} `{what}` before this line)"));
        }
    }
    None
}
