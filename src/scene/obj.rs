//! OBJ meshes via tobj (the only module that touches tobj): triangulated positions and, for
//! smooth shading, per-vertex normals (the file's `vn`, else area-weighted vertex normals), and
//! texture coordinates (`vt`, v flipped as Mitsuba's `flip_tex_coords`).
//!
//! Before tobj reads a file, [`scan`] checks every statement in file order and names the first
//! bad one by its line: a `v`, `vt` or `vn` whose numbers do not parse (a `vt` needs two, both
//! finite), a face corner with an index that is zero, unparsable, negative or past the
//! statements before its line. Negative (relative) indices are refused as Mitsuba 3's OBJ loader
//! refuses them (it reads an index with `strtoul`, so `-1` becomes 2^32 − 1 and fails its
//! range check: "reference to invalid vertex 4294967295!"), here with the index as written. A
//! `vt` index is checked whether or not the file has any `vt` (tobj would ignore it where there
//! is none; Mitsuba refuses it).
//!
//! Texture coordinates: a mesh has UVs when any face corner names a `vt` (Mitsuba 3's rule);
//! corners without one then read (0, 0), as Mitsuba 3 since 3.9.1 defines them (3.9.1 left them
//! uninitialised). `vt` statements that no face uses give no UVs.
//!
//! Invariants: degenerate faces are returned as-is; the caller skips them with a warning. The
//! returned mesh's `uvs`, when present, are finite and one per position.

use crate::math::{Vec2, Vec3};
use std::borrow::Cow;
use std::path::Path;

use super::mesh::{IndexedMesh, Mesh};

/// Loads an OBJ file as the TOML loader's flat `Mesh` (`Mesh::from_indexed`); errors are
/// messages that name the file.
pub fn load_mesh(path: &Path, smooth: bool) -> Result<Mesh, String> {
    Ok(Mesh::from_indexed(&load_indexed(path)?, smooth))
}

/// Loads an OBJ file as one indexed mesh (all objects merged; a vertex per distinct
/// position/normal/uv index triple, as Mitsuba's OBJ loader keys them). Errors name the file
/// (a regular file only: a FIFO would block).
pub fn load_indexed(path: &Path) -> Result<IndexedMesh, String> {
    super::limits::check_regular_file(path, "OBJ")?;
    let bytes = std::fs::read(path).map_err(|e| format!("cannot read OBJ `{}`: {e}", path.display()))?;
    parse(&bytes).map_err(|m| format!("OBJ `{}`: {m}", path.display()))
}

/// Parses OBJ bytes (see the module header); errors name the line where there is one.
pub fn parse(bytes: &[u8]) -> Result<IndexedMesh, String> {
    let bytes_hash = crate::math::fnv1a(0xcbf2_9ce4_8422_2325, bytes);
    let text = String::from_utf8_lossy(bytes);
    let found = scan(&text)?;
    let text = prepared(text, &found);
    let opts = tobj::LoadOptions { triangulate: true, single_index: true, ..Default::default() };
    let mut reader = std::io::BufReader::new(text.as_bytes());
    let (models, _) = tobj::load_obj_buf(&mut reader, &opts, |_| Err(tobj::LoadError::OpenFileFailed))
        .map_err(|e| format!("cannot parse: {e}"))?;
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
                return Err("face index out of range".into());
            }
            faces.push([base + f[0], base + f[1], base + f[2]]);
        }
    }
    if faces.is_empty() {
        return Err("no faces".into());
    }
    let normals = (all_normals && normals.len() == positions.len()).then_some(normals);
    let uvs = (found.uv_corners > 0 && all_uvs && uvs.len() == positions.len()).then_some(uvs);
    Ok(IndexedMesh { positions, normals, uvs, faces, bytes_hash })
}

/// What [`scan`] learnt of a file beyond its being well formed.
struct Scan {
    /// Face corners that name a `vt`, and corners that name none.
    uv_corners: usize,
    bare_corners: usize,
    /// A statement followed by a `#` comment on its line (tobj would read the comment as data).
    trailing_comments: bool,
}

/// The keyword of a statement line and its words, the comment after `#` removed.
fn statement(raw: &str) -> (Option<&str>, std::str::SplitAsciiWhitespace<'_>, bool) {
    let (line, comment) = match raw.find('#') {
        Some(i) => (&raw[..i], true),
        None => (raw, false),
    };
    let mut w = line.split_ascii_whitespace();
    let kw = w.next();
    (kw, w, comment && kw.is_some())
}

/// Checks every statement in file order (see the module header): the first bad one as
/// `line N: `kw` statement: what: `the line``.
fn scan(text: &str) -> Result<Scan, String> {
    let mut counts = [0usize; 3]; // v, vt, vn
    let mut found = Scan { uv_corners: 0, bare_corners: 0, trailing_comments: false };
    for (i, raw) in text.lines().enumerate() {
        let (kw, mut w, comment) = statement(raw);
        let Some(kw) = kw else { continue };
        found.trailing_comments |= comment;
        let bad = |m: String| Err(format!("line {}: `{kw}` statement: {m}: `{}`", i + 1, raw.trim()));
        let (slot, need, what) = match kw {
            "v" => (0, 3, "position"),
            "vt" => (1, 2, "texture coordinate"),
            "vn" => (2, 3, "normal"),
            "f" | "l" | "p" => {
                for t in w {
                    match corner(t, &counts) {
                        Ok(true) => found.uv_corners += 1,
                        Ok(false) => found.bare_corners += 1,
                        Err(m) => return bad(m),
                    }
                }
                continue;
            }
            _ => continue,
        };
        let (mut read, mut finite) = (0, true);
        for x in w.by_ref().take(need).map(str::parse::<f32>) {
            let Ok(x) = x else { break };
            (read, finite) = (read + 1, finite && x.is_finite());
        }
        if read < need {
            return bad(format!("{what} parse error (needs {need} numbers)"));
        }
        if slot == 1 && !finite {
            return bad("texture coordinate is not finite".into());
        }
        counts[slot] += 1;
    }
    Ok(found)
}

/// Checks one `v/vt/vn` corner of a face against the statements before its line; whether it
/// names a `vt`.
fn corner(t: &str, counts: &[usize; 3]) -> Result<bool, String> {
    let (mut parts, mut n) = ([""; 3], 0);
    for part in t.split('/') {
        if n == 3 {
            return Err(format!("`{t}` has more than three `/`-separated indices"));
        }
        (parts[n], n) = (part, n + 1);
    }
    if parts[0].is_empty() {
        return Err(format!("`{t}` has no position index"));
    }
    for (k, part) in parts.iter().enumerate() {
        if part.is_empty() {
            continue;
        }
        let what = ["v", "vt", "vn"][k];
        let n = counts[k];
        let Ok(i) = part.parse::<i64>() else { return Err(format!("`{part}` is not an index")) };
        if i == 0 {
            return Err(format!("face {what} index 0 (OBJ indices start at 1)"));
        }
        if i < 0 {
            return Err(format!(
                "face {what} index {i} is relative (negative): Mitsuba 3 refuses relative indices, write the absolute index"
            ));
        }
        if i as u64 > n as u64 {
            return Err(format!("face {what} index {i} out of range ({n} `{what}` before this line)"));
        }
    }
    Ok(!parts[1].is_empty())
}

/// The text tobj reads: `text` itself, unless it has comments after statements (removed) or
/// faces with UVs on some corners only (a first `vt 0 1`, (0, 0) once flipped, for the bare
/// corners, every `vt` index, all absolute after [`scan`], moved up by one).
fn prepared<'a>(text: Cow<'a, str>, found: &Scan) -> Cow<'a, str> {
    let partial = found.uv_corners > 0 && found.bare_corners > 0;
    if !partial && !found.trailing_comments {
        return text;
    }
    let mut out = String::with_capacity(text.len() + text.len() / 8 + 8);
    if partial {
        out.push_str("vt 0 1\n");
    }
    for raw in text.lines() {
        let (kw, w, _) = statement(raw);
        match kw {
            Some(kw @ ("f" | "l" | "p")) if partial => {
                out.push_str(kw);
                for t in w {
                    let mut parts = t.split('/');
                    let (v, vt, vn) = (parts.next().unwrap_or(""), parts.next().unwrap_or(""), parts.next());
                    let vt = match vt.parse::<i64>() {
                        Ok(i) if i > 0 => i + 1,
                        Ok(i) => i,
                        Err(_) => 1,
                    };
                    out.push_str(&format!(" {v}/{vt}"));
                    if let Some(vn) = vn {
                        out.push_str(&format!("/{vn}"));
                    }
                }
            }
            Some(kw) => {
                out.push_str(kw);
                w.for_each(|t| {
                    out.push(' ');
                    out.push_str(t);
                });
            }
            None => {}
        }
        out.push('\n');
    }
    Cow::Owned(out)
}
