//! PLY meshes (Stanford polygon files): ASCII, binary little and big endian, with or without
//! per-vertex normals (`nx ny nz`). Faces with more than three vertices are split into a fan,
//! as Mitsuba does; elements other than `vertex` and `face` are read and skipped.
//!
//! Hand-written rather than `ply-rs` (last release 2019, no line numbers in its errors): every
//! error names the file and the header line, the body line (ASCII) or the byte offset (binary).
//! Texture coordinates are per vertex, under Mitsuba's three names (`u`, `v`; `texture_u`,
//! `texture_v`; `s`, `t`; a vertex element with only one of a pair has none, as in Mitsuba), and
//! must be finite; a face list of per-corner ones (`texcoord`, MeshLab's) is refused, as Mitsuba
//! refuses it.
//!
//! Invariants: face indices are checked against the vertex count; a body cut short is an error,
//! never a panic; a mesh without faces is an error.

use crate::math::{Vec2, Vec3};
use std::path::Path;

pub use super::mesh::IndexedMesh;

#[derive(Clone, Copy, PartialEq)]
enum Format {
    Ascii,
    BinaryLe,
    BinaryBe,
}

#[derive(Clone, Copy)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(s: &str) -> Option<Scalar> {
        Some(match s {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }
    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }
}

struct Property {
    name: String,
    /// `Some(count type)` for list properties.
    list: Option<Scalar>,
    ty: Scalar,
}

struct Element {
    name: String,
    count: usize,
    props: Vec<Property>,
}

/// Reads the body of a PLY file value by value; ASCII row by row, one row a line.
struct Body<'a> {
    bytes: &'a [u8],
    pos: usize,
    format: Format,
    /// ASCII: the line of the row being read (of `pos` between rows).
    line: usize,
    /// ASCII: the end of the row being read (its line's `\n` or the end of the file).
    row_end: usize,
}

impl Body<'_> {
    fn read(&mut self, ty: Scalar) -> Result<f64, String> {
        if self.format == Format::Ascii {
            return self.read_ascii();
        }
        let n = ty.size();
        let Some(b) = self.bytes.get(self.pos..self.pos + n) else {
            return Err(format!("binary body cut short at byte {} (needs {n} more byte(s))", self.pos));
        };
        self.pos += n;
        let mut a = [0u8; 8];
        a[..n].copy_from_slice(b);
        if self.format == Format::BinaryBe {
            a[..n].reverse();
        }
        Ok(match ty {
            Scalar::I8 => a[0] as i8 as f64,
            Scalar::U8 => a[0] as f64,
            Scalar::I16 => i16::from_le_bytes([a[0], a[1]]) as f64,
            Scalar::U16 => u16::from_le_bytes([a[0], a[1]]) as f64,
            Scalar::I32 => i32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
            Scalar::U32 => u32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
            Scalar::F32 => f32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
            Scalar::F64 => f64::from_le_bytes(a),
        })
    }

    /// Skips white space inside the ASCII row.
    fn skip_ws(&mut self) {
        while self.pos < self.row_end && self.bytes[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
    }

    fn read_ascii(&mut self) -> Result<f64, String> {
        self.skip_ws();
        let start = self.pos;
        while self.pos < self.row_end && !self.bytes[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        if start == self.pos {
            return Err(format!("line {}: the line ends before this value (a line holds one row)", self.line));
        }
        let tok = String::from_utf8_lossy(&self.bytes[start..self.pos]);
        tok.parse::<f64>().map_err(|_| format!("line {}: `{tok}` is not a number", self.line))
    }

    /// The end of the line starting at `from` (its `\n`, or the end of the file).
    fn line_end(&self, from: usize) -> usize {
        self.bytes[from..].iter().position(|&b| b == b'\n').map_or(self.bytes.len(), |i| from + i)
    }

    /// ASCII: moves to the next non-blank line, the row of element `el` to read.
    fn begin_row(&mut self, el: &Element) -> Result<(), String> {
        if self.format != Format::Ascii {
            return Ok(());
        }
        loop {
            if self.pos >= self.bytes.len() {
                return Err(format!("line {}: file ends before the rows of element `{}` end", self.line, el.name));
            }
            let end = self.line_end(self.pos);
            if self.bytes[self.pos..end].iter().any(|c| !c.is_ascii_whitespace()) {
                self.row_end = end;
                return Ok(());
            }
            (self.pos, self.line) = (end + 1, self.line + 1);
        }
    }

    /// ASCII: the row of `el` read, its line must hold nothing more; moves past it.
    fn end_row(&mut self, el: &Element) -> Result<(), String> {
        if self.format != Format::Ascii {
            return Ok(());
        }
        self.skip_ws();
        if self.pos < self.row_end {
            let extra = String::from_utf8_lossy(&self.bytes[self.pos..self.row_end]);
            let last = el.props.last().map_or("", |p| p.name.as_str());
            return Err(format!(
                "line {}: element `{}`: extra values `{}` after its last property `{last}` (a line holds exactly one row)",
                self.line,
                el.name,
                extra.trim()
            ));
        }
        (self.pos, self.line) = (self.row_end + 1, self.line + 1);
        Ok(())
    }

    /// ASCII: anything but white space after the last element's rows is an error.
    fn check_end(&mut self) -> Result<(), String> {
        while self.format == Format::Ascii && self.pos < self.bytes.len() {
            let end = self.line_end(self.pos);
            let rest = String::from_utf8_lossy(&self.bytes[self.pos..end]);
            if !rest.trim().is_empty() {
                return Err(format!("line {}: `{}` after the last element's rows", self.line, rest.trim()));
            }
            (self.pos, self.line) = (end + 1, self.line + 1);
        }
        Ok(())
    }

    /// Where the row being read starts: its line (ASCII) or byte offset (binary), for `describe`.
    fn at(&mut self) -> usize {
        match self.format {
            Format::Ascii => self.line,
            _ => self.pos,
        }
    }

    /// `line N` or `byte N` of an `at`.
    fn describe(&self, at: usize) -> String {
        match self.format {
            Format::Ascii => format!("line {at}"),
            _ => format!("byte {at}"),
        }
    }

    /// The fewest bytes a value of `ty` takes: its size in binary, one character and a
    /// separator in ASCII (the last value of the file may lack its separator: `left` adds 1).
    fn min_bytes(&self, ty: Scalar) -> usize {
        match self.format {
            Format::Ascii => 2,
            _ => ty.size(),
        }
    }

    /// Bytes left to read (+1 for ASCII's last value without a separator).
    fn left(&self) -> usize {
        self.bytes.len().saturating_sub(self.pos) + (self.format == Format::Ascii) as usize
    }

    /// Refuses an element whose rows cannot fit in the bytes left (each property takes at least
    /// `min_bytes`, a list at least its length's), before any row is read.
    fn check_rows(&self, el: &Element) -> Result<(), String> {
        let row: usize = el.props.iter().map(|p| self.min_bytes(p.list.unwrap_or(p.ty))).sum();
        let left = self.left();
        if el.count.checked_mul(row).is_none_or(|need| need > left) {
            return Err(format!(
                "body cut short at byte {}: element `{}` declares {} rows, but the {left} byte(s) left hold at most {} (at least {row} byte(s) per row)",
                self.pos,
                el.name,
                el.count,
                left / row.max(1)
            ));
        }
        Ok(())
    }

    /// A list's length: a whole number in [0, 1e6] whose items fit in the bytes left.
    fn list_len(&mut self, count_ty: Scalar, ty: Scalar) -> Result<usize, String> {
        let at = self.at();
        let n = self.read(count_ty)?;
        if !(n.fract() == 0.0 && (0.0..=1e6).contains(&n)) {
            return Err(format!("{}: bad list length {n} (a whole number in [0, 1e6])", self.describe(at)));
        }
        let n = n as usize;
        if n * self.min_bytes(ty) > self.left() {
            let (need, left) = (n * self.min_bytes(ty), self.left());
            return Err(format!(
                "{}: body cut short at byte {}: a list of {n} values needs {need} byte(s), {left} left",
                self.describe(at),
                self.pos
            ));
        }
        Ok(n)
    }
}

/// Parses the header: (format, elements, body offset, header line count).
fn parse_header(bytes: &[u8]) -> Result<(Format, Vec<Element>, usize, usize), String> {
    let mut pos = 0usize;
    let mut line_no = 0usize;
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        let Some(len) = bytes[pos..].iter().position(|&b| b == b'\n') else {
            return Err(format!("line {}: header has no `end_header`", line_no + 1));
        };
        line_no += 1;
        let line = String::from_utf8_lossy(&bytes[pos..pos + len]).trim().to_string();
        pos += len + 1;
        let w: Vec<&str> = line.split_whitespace().collect();
        let bad = |m: &str| Err(format!("line {line_no}: {m}: `{line}`"));
        match w.first().copied() {
            _ if line_no == 1 => {
                if line != "ply" {
                    return bad("not a PLY file (the first line must be `ply`)");
                }
            }
            Some("format") => {
                format = Some(match w.get(1).copied() {
                    Some("ascii") => Format::Ascii,
                    Some("binary_little_endian") => Format::BinaryLe,
                    Some("binary_big_endian") => Format::BinaryBe,
                    _ => return bad("unknown format"),
                })
            }
            Some("comment") | Some("obj_info") | None => {}
            Some("element") => {
                let (Some(name), Some(Ok(count))) = (w.get(1), w.get(2).map(|c| c.parse::<usize>())) else {
                    return bad("expected `element NAME COUNT`");
                };
                if matches!(*name, "vertex" | "face") && elements.iter().any(|e| e.name == *name) {
                    return bad(&format!("a second `element {name}` (a mesh has one vertex and one face element)"));
                }
                elements.push(Element { name: name.to_string(), count, props: Vec::new() });
            }
            Some("property") => {
                let Some(el) = elements.last_mut() else { return bad("property before any element") };
                let prop = if w.get(1) == Some(&"list") {
                    match (w.get(2).and_then(|t| Scalar::parse(t)), w.get(3).and_then(|t| Scalar::parse(t)), w.get(4)) {
                        (Some(Scalar::F32 | Scalar::F64), _, _) => {
                            return bad("a list's count type must be an integer type")
                        }
                        (Some(_), Some(_), Some(n)) if el.name == "face" && n.starts_with("texcoord") => {
                            // MeshLab's per-corner ("wedge") UVs: Mitsuba 3 refuses the second list
                            return bad(&format!(
                                "face property `{n}` holds texture coordinates per face corner; Mitsuba 3 reads them only per vertex (`u`, `v`; `texture_u`, `texture_v`; or `s`, `t`)"
                            ));
                        }
                        (Some(c), Some(t), Some(n)) => Property { name: n.to_string(), list: Some(c), ty: t },
                        _ => return bad("expected `property list COUNT_TYPE TYPE NAME`"),
                    }
                } else {
                    match (w.get(1).and_then(|t| Scalar::parse(t)), w.get(2)) {
                        (Some(t), Some(n)) => Property { name: n.to_string(), list: None, ty: t },
                        _ => return bad("expected `property TYPE NAME`"),
                    }
                };
                el.props.push(prop);
            }
            Some("end_header") => break,
            Some(_) => return bad("unknown header line"),
        }
    }
    let format = format.ok_or_else(|| "header has no `format` line".to_string())?;
    Ok((format, elements, pos, line_no))
}

/// Loads a PLY file; errors name the file and the line or byte offset.
pub fn load_indexed(path: &Path) -> Result<IndexedMesh, String> {
    super::limits::check_regular_file(path, "PLY")?; // a FIFO would block
    let bytes = std::fs::read(path).map_err(|e| format!("cannot read PLY `{}`: {e}", path.display()))?;
    parse(&bytes).map_err(|m| format!("PLY `{}`: {m}", path.display()))
}

/// Parses PLY bytes. Work and memory are bounded by the file: every element's row count is
/// checked against the bytes left before its rows are read (`check_rows`), every list's length
/// likewise, and faces are checked as they are read (a 20 MB file of empty faces fails at the
/// first one instead of storing them all).
pub fn parse(bytes: &[u8]) -> Result<IndexedMesh, String> {
    let bytes_hash = crate::math::fnv1a(0xcbf2_9ce4_8422_2325, bytes);
    let (format, elements, start, header_lines) = parse_header(bytes)?;
    let mut body = Body { bytes, pos: start, format, line: header_lines + 1, row_end: start };
    let mut positions: Vec<Vec3> = Vec::new();
    let mut normals = Vec::new();
    let mut uvs = Vec::new();
    let (mut has_normals, mut has_uvs) = (false, false);
    let mut vertex_read = false;
    let mut faces: Vec<[u32; 3]> = Vec::new();
    let mut vals = Vec::new();
    for el in &elements {
        let (xyz, nxyz, uv, face_list) = columns(el)?;
        if el.name == "vertex" {
            has_normals = nxyz.iter().all(|c| c.is_some());
            has_uvs = uv.iter().all(|c| c.is_some());
        }
        if el.props.is_empty() {
            continue; // rows of no properties occupy no bytes: nothing to read, whatever the count
        }
        body.check_rows(el)?;
        // the vertex count, when the vertex element came first (face indices are checked as read)
        let nv = vertex_read.then_some(positions.len());
        for _ in 0..el.count {
            body.begin_row(el)?;
            let at = body.at();
            read_row(&mut body, el, (face_list, nv), &mut vals, &mut faces)?;
            body.end_row(el)?;
            if el.name == "vertex" {
                let v = |c: [Option<usize>; 3]| c.map(|c| c.map_or(0.0, |c| vals[c] as f32));
                positions.push(Vec3::from_array(v(xyz)));
                if has_normals {
                    normals.push(Vec3::from_array(v(nxyz)));
                }
                if has_uvs {
                    let t = uv.map(|c| c.map_or(0.0, |c| vals[c] as f32));
                    if !t.iter().all(|x| x.is_finite()) {
                        let (row, k) = (body.describe(at), positions.len());
                        return Err(format!("{row}: vertex {k}: texture coordinates {t:?} are not finite"));
                    }
                    uvs.push(Vec2::from_array(t));
                }
            }
        }
        vertex_read |= el.name == "vertex";
    }
    body.check_end()?;
    // faces read before the vertex element: their indices are checked now
    let nv = positions.len();
    if let Some((k, i)) =
        faces.iter().enumerate().find_map(|(k, f)| f.iter().find(|&&i| i as usize >= nv).map(|&i| (k, i)))
    {
        return Err(format!("triangle {}: face index {i} out of range (the file has {nv} vertices)", k + 1));
    }
    if faces.is_empty() {
        return Err("no faces".into());
    }
    Ok(IndexedMesh {
        positions,
        normals: has_normals.then_some(normals),
        uvs: has_uvs.then_some(uvs),
        faces,
        bytes_hash,
    })
}

/// Reads one row of `el` into `vals` (a list's value: 0), its faces (the element's list `face`
/// of the `(face list, vertex count)`) into `faces`; errors name the element and the property.
fn read_row(
    body: &mut Body,
    el: &Element,
    (face_list, nv): (Option<usize>, Option<usize>),
    vals: &mut Vec<f64>,
    faces: &mut Vec<[u32; 3]>,
) -> Result<(), String> {
    vals.clear();
    let at = body.at();
    for (k, p) in el.props.iter().enumerate() {
        let ctx = |m: String| format!("{m} (element `{}`, property `{}`)", el.name, p.name);
        vals.push(0.0);
        let Some(ct) = p.list else {
            vals[k] = body.read(p.ty).map_err(ctx)?;
            continue;
        };
        let n = body.list_len(ct, p.ty).map_err(ctx)?;
        let is_face = el.name == "face" && Some(k) == face_list;
        if is_face && n < 3 {
            return Err(format!("{}: face with {n} vertices (a face needs at least 3)", body.describe(at)));
        }
        let mut poly = Vec::with_capacity(if is_face { n } else { 0 });
        for _ in 0..n {
            let i = body.read(p.ty).map_err(ctx)?;
            if is_face {
                poly.push(face_index(i, nv).map_err(|m| format!("{}: {m}", body.describe(at)))?);
            }
        }
        // a fan, as Mitsuba splits polygons
        faces.extend((1..poly.len().saturating_sub(1)).map(|j| [poly[0], poly[j], poly[j + 1]]));
    }
    Ok(())
}

/// An element's x, y, z and nx, ny, nz columns and its face list (`vertex` needs x, y, z;
/// `face` needs `vertex_indices`).
type Columns = ([Option<usize>; 3], [Option<usize>; 3], [Option<usize>; 2], Option<usize>);

fn columns(el: &Element) -> Result<Columns, String> {
    let col = |n: &str| el.props.iter().position(|p| p.name == n && p.list.is_none());
    let (xyz, nxyz) = ([col("x"), col("y"), col("z")], [col("nx"), col("ny"), col("nz")]);
    // texture coordinates under Mitsuba's three names
    let uv = [["u", "v"], ["texture_u", "texture_v"], ["s", "t"]]
        .map(|[a, b]| [col(a), col(b)])
        .into_iter()
        .find(|c| c.iter().all(|c| c.is_some()))
        .unwrap_or([None, None]);
    if el.name == "vertex" && xyz.iter().any(|c| c.is_none()) {
        return Err("element `vertex` needs float properties x, y, z".into());
    }
    let face_list = el.props.iter().position(|p| p.list.is_some() && p.name.starts_with("vertex_ind"));
    if el.name == "face" && face_list.is_none() {
        return Err("element `face` needs a list property `vertex_indices`".into());
    }
    Ok((xyz, nxyz, uv, face_list))
}

/// A face index read as `i`: a whole number in `[0, nv)` (`nv` once known, else `[0, 2³²)`).
fn face_index(i: f64, nv: Option<usize>) -> Result<u32, String> {
    let limit = nv.map_or(u32::MAX as f64, |n| n as f64);
    if i < 0.0 || i.fract() != 0.0 || i >= limit {
        let n = nv.map_or("up to 2^32".to_string(), |n| n.to_string());
        return Err(format!("face index {i} out of range (the file has {n} vertices)"));
    }
    Ok(i as u32)
}

/// Writes a binary little-endian PLY (float positions, optional float normals and `u`, `v`,
/// uchar/uint faces).
pub fn write_binary(mesh: &IndexedMesh) -> Vec<u8> {
    let mut h = format!("ply\nformat binary_little_endian 1.0\nelement vertex {}\n", mesh.positions.len());
    h.push_str("property float x\nproperty float y\nproperty float z\n");
    if mesh.normals.is_some() {
        h.push_str("property float nx\nproperty float ny\nproperty float nz\n");
    }
    if mesh.uvs.is_some() {
        h.push_str("property float u\nproperty float v\n");
    }
    h.push_str(&format!("element face {}\nproperty list uchar uint vertex_indices\nend_header\n", mesh.faces.len()));
    let mut out = h.into_bytes();
    for (i, p) in mesh.positions.iter().enumerate() {
        let mut put = |v: Vec3| v.to_array().iter().for_each(|x| out.extend_from_slice(&x.to_le_bytes()));
        put(*p);
        if let Some(n) = &mesh.normals {
            put(n[i]);
        }
        if let Some(t) = &mesh.uvs {
            t[i].to_array().iter().for_each(|x| out.extend_from_slice(&x.to_le_bytes()));
        }
    }
    for f in &mesh.faces {
        out.push(3);
        f.iter().for_each(|i| out.extend_from_slice(&i.to_le_bytes()));
    }
    out
}

/// A PLY mesh as the TOML loader's `Mesh`: triangles and, for smooth shading, the file's normals
/// or area-weighted vertex normals (the same rule as OBJ).
pub fn load_mesh(path: &Path, smooth: bool) -> Result<super::mesh::Mesh, String> {
    Ok(super::mesh::Mesh::from_indexed(&load_indexed(path)?, smooth))
}

#[cfg(test)]
mod tests {
    use super::*;

    const ASCII: &str = "ply\nformat ascii 1.0\ncomment x\nelement vertex 4\nproperty float x\nproperty float y\n\
property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n";

    #[test]
    fn ascii_quad_is_a_fan_and_binary_round_trips() {
        let m = parse(ASCII.as_bytes()).unwrap();
        assert_eq!(m.faces, vec![[0, 1, 2], [0, 2, 3]]);
        assert!(m.normals.is_none());
        let m2 = IndexedMesh { normals: Some(vec![Vec3::Z; 4]), ..m.clone() };
        let back = parse(&write_binary(&m2)).unwrap();
        assert_eq!(back.positions, m2.positions);
        assert_eq!(back.normals, m2.normals);
        assert_eq!(back.faces, m2.faces);
    }

    #[test]
    fn big_endian_and_errors() {
        let mut b = b"ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty double x\nproperty double y\n\
property double z\nelement face 1\nproperty list uchar ushort vertex_indices\nend_header\n"
            .to_vec();
        for v in [[0.0f64, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 3.0, 0.5]] {
            v.iter().for_each(|x| b.extend_from_slice(&x.to_be_bytes()));
        }
        b.push(3);
        [0u16, 1, 2].iter().for_each(|i| b.extend_from_slice(&i.to_be_bytes()));
        let m = parse(&b).unwrap();
        assert_eq!(m.positions[2], Vec3::new(0.0, 3.0, 0.5));
        let e = parse(&b[..b.len() - 1]).err().unwrap();
        assert!(e.contains("cut short at byte"), "{e}");
        let e = parse(ASCII.replace("4 0 1 2 3", "3 0 1 7").as_bytes()).err().unwrap();
        assert!(e.contains("line 15") && e.contains("index 7 out of range"), "{e}");
    }
}
