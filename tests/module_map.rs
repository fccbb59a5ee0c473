//! The one module map, `docs/modules.md`, against the files under `src/`.
//!
//! The page's convention (stated on the page): every `.rs` file under `src/` (a module: a file,
//! or a folder's `mod.rs`) is written in backticks as its path below `src/` (`math.rs`,
//! `cf/mod.rs`, `integrators/pt/vertex.rs`); any backticked name ending in `.rs` is such a path,
//! or, beginning with `tests/`, a path from the repository root; and any `src/….rs` written
//! anywhere on the page, backticked or not, is a path from the repository root. The test fails on
//! a file under `src/` the page does not name, and on a name on the page that is not a file.
//!
//! It reads only the repository (`CARGO_MANIFEST_DIR`).

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Every `.rs` file below `dir`, as its path below `dir` with `/` separators.
fn rust_files(dir: &Path, below: &str, out: &mut BTreeSet<String>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("reading {}: {e}", dir.display()))
        .map(|e| e.expect("a directory entry").path())
        .collect();
    entries.sort();
    for path in entries {
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        let rel = if below.is_empty() { name.clone() } else { format!("{below}/{name}") };
        if path.is_dir() {
            rust_files(&path, &rel, out);
        } else if name.ends_with(".rs") {
            out.insert(rel);
        }
    }
}

/// The backticked spans of `text` (inline code, one line each).
fn backticked(text: &str) -> Vec<&str> {
    text.lines().flat_map(|line| line.split('`').skip(1).step_by(2)).collect()
}

/// Every `src/….rs` written in `text`, backticked or not.
fn src_paths(text: &str) -> Vec<&str> {
    let is_path_char = |c: char| c.is_ascii_alphanumeric() || c == '_' || c == '/' || c == '.' || c == '-';
    let mut found = Vec::new();
    for (i, _) in text.match_indices("src/") {
        if i > 0 && is_path_char(text[..i].chars().next_back().unwrap()) {
            continue; // part of a longer path (`../src/`, `foo_src/`)
        }
        let end = text[i..].find(|c: char| !is_path_char(c)).map_or(text.len(), |n| i + n);
        let token = text[i..end].trim_end_matches('.');
        if token.ends_with(".rs") {
            found.push(token);
        }
    }
    found
}

#[test]
fn every_module_is_on_the_map_and_every_name_on_it_is_a_file() {
    let root = root();
    let page = std::fs::read_to_string(root.join("docs/modules.md")).expect("docs/modules.md");

    let mut files = BTreeSet::new();
    rust_files(&root.join("src"), "", &mut files);
    assert!(files.contains("lib.rs"), "src/ should hold lib.rs");

    let mut named = BTreeSet::new();
    let mut not_files = Vec::new();
    for span in backticked(&page) {
        let span = span.trim();
        // A name: a path ending in `.rs` with a stem (not the bare word `.rs` in prose).
        let is_name = span.len() > ".rs".len()
            && span.ends_with(".rs")
            && !span.starts_with('.')
            && span.chars().all(|c| c.is_ascii_alphanumeric() || "_/.-".contains(c));
        if !is_name {
            continue;
        }
        let from_root = span.starts_with("src/") || span.starts_with("tests/");
        let path = if from_root { root.join(span) } else { root.join("src").join(span) };
        if !path.is_file() {
            not_files.push(span.to_string());
        } else if let Some(below_src) = span.strip_prefix("src/") {
            named.insert(below_src.to_string());
        } else if !from_root {
            named.insert(span.to_string());
        }
    }
    for path in src_paths(&page) {
        if !root.join(path).is_file() {
            not_files.push(path.to_string());
        }
    }

    let missing: Vec<_> = files.difference(&named).collect();
    assert!(
        missing.is_empty(),
        "docs/modules.md does not name these files under src/ (write each in backticks as its \
         path below src/, in its module's row): {missing:?}"
    );
    assert!(
        not_files.is_empty(),
        "docs/modules.md names files that do not exist (paths below src/, or tests/… and src/… \
         from the repository root): {not_files:?}"
    );
}

#[test]
fn the_page_convention_is_read_as_stated() {
    assert_eq!(backticked("a `math.rs` and `cf/mod.rs`, not ``"), ["math.rs", "cf/mod.rs", ""]);
    assert_eq!(
        src_paths("see src/cf/mod.rs. and `src/lib.rs`, not ../src/x.rs or src/cf/"),
        ["src/cf/mod.rs", "src/lib.rs"]
    );
}
