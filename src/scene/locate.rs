//! Locating TOML errors in the scene text: the line and dotted key path (`shape[2].radius`,
//! `camera.fov`) of the value a deserialization error points at, found from the source text.
//!
//! The scene format is written one `key = value` per line under `[table]` / `[[array]]` headers
//! (scenes/README.md); a value spanning several lines (an array) belongs to the nearest `key =`
//! above it. Invariant: the returned line is at or before the error's own line.

/// `(is_array, name)` of a table header line (`[camera]`, `[[shape]]`, `[materials.white]`).
fn header(line: &str) -> Option<(bool, &str)> {
    let t = line.trim_start().strip_prefix('[')?;
    let arr = t.starts_with('[');
    let rest = t.trim_start_matches('[').trim_start();
    if !rest.starts_with(|c: char| c.is_ascii_alphabetic() || c == '_' || c == '"') {
        return None; // an array value such as `[0.0, 1.0],`
    }
    Some((arr, rest.split(']').next()?.trim()))
}

/// The key of a `key = value` line.
fn leading_key(line: &str) -> Option<&str> {
    let t = line.trim_start();
    let end = t.find(|c: char| !(c.is_ascii_alphanumeric() || "_-.\"".contains(c))).unwrap_or(t.len());
    (end > 0 && t[end..].trim_start().starts_with('=')).then(|| &t[..end])
}

/// 0-based index of the line that byte `offset` lies in (the last line past the end).
fn line_index(lines: &[&str], offset: usize) -> Option<usize> {
    let mut off = 0;
    for (i, l) in lines.iter().enumerate() {
        if off + l.len() > offset {
            return Some(i);
        }
        off += l.len();
    }
    lines.len().checked_sub(1)
}

/// 1-based line and dotted key path of the `key = value` that byte `offset` lies in.
pub(super) fn key_path_at(src: &str, offset: usize) -> Option<(usize, String)> {
    let lines: Vec<&str> = src.split_inclusive('\n').collect();
    let at = line_index(&lines, offset)?;
    let (ki, leaf) = (0..=at).rev().map_while(|i| header(lines[i]).is_none().then_some(i)).find_map(|i| {
        let k = leading_key(lines[i])?;
        Some((i, k))
    })?;
    let table = (0..ki).rev().find_map(|i| header(lines[i])).map(|(arr, name)| {
        if arr {
            let n = lines[..ki].iter().filter(|l| header(l) == Some((true, name))).count();
            format!("{name}[{}].", n - 1)
        } else {
            format!("{name}.")
        }
    });
    Some((ki + 1, format!("{}{leaf}", table.unwrap_or_default())))
}

/// toml's "duplicate key" at byte `offset` (the repeated key, in a header or a `key =` line):
/// its 1-based line, dotted path and message, naming the earlier definition's line when found.
pub(super) fn duplicate_at(src: &str, offset: usize) -> Option<(usize, String, String)> {
    let lines: Vec<&str> = src.split_inclusive('\n').collect();
    let at = line_index(&lines, offset)?;
    let first = |i: Option<usize>| i.map_or(String::new(), |i| format!(" (first at line {})", i + 1));
    if let Some((_, name)) = header(lines[at]) {
        let before = (0..at).find(|&i| header(lines[i]).is_some_and(|(_, n)| n == name));
        let m = format!("duplicate key: the table `{name}` is defined twice{}", first(before));
        return Some((at + 1, name.to_string(), m));
    }
    let (line, path) = key_path_at(src, offset)?;
    let leaf = leading_key(lines[line - 1])?;
    let top = (0..line - 1).rev().find(|&i| header(lines[i]).is_some()).map_or(0, |i| i + 1);
    let before = (top..line - 1).find(|&i| leading_key(lines[i]) == Some(leaf));
    Some((line, path.clone(), format!("duplicate key: `{path}` is given twice{}", first(before))))
}

/// The dotted path of the table whose header is on the line of byte `offset` (`shape[0]`,
/// `materials.white`): the table a "missing field" error's span starts at.
pub(super) fn table_at(src: &str, offset: usize) -> Option<String> {
    let lines: Vec<&str> = src.split_inclusive('\n').collect();
    let at = line_index(&lines, offset)?;
    let (arr, name) = header(lines[at])?;
    if !arr {
        return Some(name.to_string());
    }
    let n = lines[..at].iter().filter(|l| header(l) == Some((true, name))).count();
    Some(format!("{name}[{n}]"))
}

/// serde's unknown or missing field `key` (toml's span starting at byte `from`): the 1-based
/// line and the key's dotted path (`shape[0].type`, `camera.look_at`; a top-level key as is).
pub(super) fn field_at(src: &str, from: usize, key: &str, missing: bool) -> Option<(usize, String)> {
    if missing {
        let line = src[..from.min(src.len())].matches('\n').count() + 1;
        return Some((line, table_at(src, from).map_or(key.to_string(), |t| format!("{t}.{key}"))));
    }
    let line = key_line_after(src, from, key)?;
    let start: usize = src.split_inclusive('\n').take(line - 1).map(str::len).sum();
    let (_, path) = key_path_at(src, start)?;
    Some((line, path))
}

/// 1-based line of the first `key = …` at or after byte `from`.
pub(super) fn key_line_after(src: &str, from: usize, key: &str) -> Option<usize> {
    let mut off = 0usize;
    for (i, line) in src.split_inclusive('\n').enumerate() {
        let t = line.trim_start();
        if off + line.len() > from && t.starts_with(key) && t[key.len()..].trim_start().starts_with('=') {
            return Some(i + 1);
        }
        off += line.len();
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_key_paths() {
        let src = "[camera]\nfov = \"wide\"\n[[shape]]\ntype = \"quad\"\n[[shape]]\nradius = \"big\"\nu = [\n  1.0,\n  \"x\"]\n[materials.white]\nalbedo = 1\n";
        let at = |pat: &str| key_path_at(src, src.find(pat).unwrap());
        assert_eq!(at("\"wide\""), Some((2, "camera.fov".into())));
        assert_eq!(at("\"big\""), Some((6, "shape[1].radius".into())));
        assert_eq!(at("\"x\""), Some((7, "shape[1].u".into())));
        assert_eq!(at("1\n"), Some((11, "materials.white.albedo".into())));
    }
}
