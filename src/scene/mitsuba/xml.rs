//! Mitsuba XML → an owned element tree (the only code that touches `roxmltree`), with the
//! document's `<default>` values (overridden by `-D name=value`) substituted for `$name` in every
//! attribute, and the camelCase parameter names of Mitsuba 0.5/0.6 (`toWorld`, `intIOR`,
//! `sampleCount`, ...) upgraded to Mitsuba 3's snake_case, as Mitsuba 3's own upgrade does.
//!
//! Invariants: every node keeps its 1-based source line; an unresolved `$name` or malformed XML is
//! an error with the line, never a panic; elements nest at most `MAX_NESTING` deep; line numbers
//! cost a binary search each (linear-time loading).

use std::collections::BTreeMap;

/// One XML element.
#[derive(Clone, Debug)]
pub(super) struct Node {
    /// Tag name (`shape`, `float`, ...).
    pub tag: String,
    /// Attributes after substitution (`name` values in snake_case).
    pub attrs: Vec<(String, String)>,
    /// 1-based line of the start tag.
    pub line: usize,
    /// Child elements.
    pub children: Vec<Node>,
}

impl Node {
    /// An attribute's value.
    pub fn attr(&self, k: &str) -> Option<&str> {
        self.attrs.iter().find(|(a, _)| a == k).map(|(_, v)| v.as_str())
    }
    /// The `name` attribute ("" when absent).
    pub fn name(&self) -> &str {
        self.attr("name").unwrap_or("")
    }
    /// The `type` attribute ("" when absent).
    pub fn ty(&self) -> &str {
        self.attr("type").unwrap_or("")
    }
}

/// camelCase → snake_case (`toWorld` → `to_world`, `intIOR` → `int_ior`); snake_case is unchanged.
pub(super) fn snake(name: &str) -> String {
    let mut out = String::with_capacity(name.len() + 4);
    let mut prev_lower = false;
    for c in name.chars() {
        if c.is_ascii_uppercase() && prev_lower {
            out.push('_');
        }
        prev_lower = c.is_ascii_lowercase() || c.is_ascii_digit();
        out.push(c.to_ascii_lowercase());
    }
    out
}

/// The deepest element nesting accepted (`<scene>` is depth 1). Real scenes nest a handful
/// (scene, shape, bsdf, twosided's bsdf, a parameter); the tree is built and read recursively, so
/// without a limit 10,000 nested elements overflowed the stack.
pub(super) const MAX_NESTING: usize = 64;

/// A parsed document: the root `<scene>`, its version, and the substitution values in force.
pub(super) type Parsed = (Node, String, BTreeMap<String, String>);

/// Parses the document.
pub(super) fn parse(src: &str, defines: &[(String, String)]) -> Result<Parsed, (usize, String)> {
    let doc = roxmltree::Document::parse(src).map_err(|e| (e.pos().row as usize, format!("malformed XML: {e}")))?;
    let root = doc.root_element();
    // line starts once, then a binary search per node: linear in the document (roxmltree's
    // `text_pos_at` scans from the start, quadratic over every node)
    let starts: Vec<usize> = std::iter::once(0).chain(src.match_indices('\n').map(|(i, _)| i + 1)).collect();
    let line = |n: roxmltree::Node| starts.partition_point(|&s| s <= n.range().start);
    if root.tag_name().name() != "scene" {
        return Err((line(root), format!("the root element is `<{}>`, expected `<scene>`", root.tag_name().name())));
    }
    let version = root.attribute("version").unwrap_or("3.0.0").to_string();
    // <default name=.. value=..> at the top level, then the command line's -D on top
    let mut vars: BTreeMap<String, String> = BTreeMap::new();
    for c in root.children().filter(|c| c.is_element() && c.tag_name().name() == "default") {
        let (Some(n), Some(v)) = (c.attribute("name"), c.attribute("value")) else {
            return Err((line(c), "`<default>` needs `name` and `value`".into()));
        };
        vars.entry(n.to_string()).or_insert_with(|| v.to_string());
    }
    for (k, v) in defines {
        vars.insert(k.clone(), v.clone());
    }
    fn build(
        n: roxmltree::Node,
        vars: &BTreeMap<String, String>,
        line: &dyn Fn(roxmltree::Node) -> usize,
        depth: usize,
    ) -> Result<Node, (usize, String)> {
        let l = line(n);
        if depth > MAX_NESTING {
            return Err((l, format!("elements nested more than {MAX_NESTING} deep (a Mitsuba scene needs a handful)")));
        }
        let mut attrs = Vec::new();
        for a in n.attributes() {
            let mut v = substitute(a.value(), vars).map_err(|m| (l, m))?;
            if a.name() == "name" {
                v = snake(&v);
            }
            attrs.push((a.name().to_string(), v));
        }
        let children = n
            .children()
            .filter(|c| c.is_element())
            .map(|c| build(c, vars, line, depth + 1))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Node { tag: n.tag_name().name().to_string(), attrs, line: l, children })
    }
    // ids name one element each: a second one would silently replace the first
    let mut ids: BTreeMap<&str, usize> = BTreeMap::new();
    for n in root.descendants().filter(|n| n.is_element() && n.tag_name().name() != "ref") {
        if let Some(id) = n.attribute("id") {
            if let Some(first) = ids.insert(id, line(n)) {
                return Err((line(n), format!("id `{id}` is defined twice (first on line {first})")));
            }
        }
    }
    let node = build(root, &vars, &line, 1)?;
    Ok((node, version, vars))
}

/// Replaces `$name` by its value (longest defined name first); an undefined `$name` is an error.
fn substitute(s: &str, vars: &BTreeMap<String, String>) -> Result<String, String> {
    if !s.contains('$') {
        return Ok(s.to_string());
    }
    let mut out = String::new();
    let mut rest = s;
    while let Some(i) = rest.find('$') {
        out.push_str(&rest[..i]);
        let after = &rest[i + 1..];
        let end = after.find(|c: char| !(c.is_ascii_alphanumeric() || c == '_')).unwrap_or(after.len());
        let name = &after[..end];
        let v = vars.get(name).ok_or_else(|| {
            format!("`${name}` is not defined (add `<default name=\"{name}\" value=\"...\"/>` or `-D {name}=...`)")
        })?;
        out.push_str(v);
        rest = &after[end..];
    }
    out.push_str(rest);
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn camel_case_upgrade_and_substitution() {
        assert_eq!(snake("toWorld"), "to_world");
        assert_eq!(snake("intIOR"), "int_ior");
        assert_eq!(snake("sampleCount"), "sample_count");
        assert_eq!(snake("face_normals"), "face_normals");
        let src = "<scene version=\"0.6.0\">\n<default name=\"spp\" value=\"8\"/>\n<x name=\"sampleCount\" value=\"$spp\"/></scene>";
        let (n, v, _) = parse(src, &[]).unwrap();
        assert_eq!(v, "0.6.0");
        assert_eq!(n.children[1].attr("value"), Some("8"));
        assert_eq!(n.children[1].name(), "sample_count");
        assert_eq!(n.children[1].line, 3);
        let (n, _, _) = parse(src, &[("spp".into(), "32".into())]).unwrap();
        assert_eq!(n.children[1].attr("value"), Some("32"));
        let e = parse("<scene>\n<x value=\"$nope\"/></scene>", &[]).unwrap_err();
        assert_eq!(e.0, 2);
    }
}
