//! Where in a TOML scene file an error is: `Ctx` holds the file's text and its line starts, and
//! turns a toml span and a dotted key into a `SceneError` at the key's own line.
//!
//! Invariants: line numbers are 1-based and within the file; a key that is not found in its
//! entry's text gives the entry's first line, never a panic (spans past the end are clamped).

use crate::scene::spec::Origin;
use crate::scene::SceneError;

/// The TOML file being read: its name as reported, its text, and each line's start offset.
pub(super) struct Ctx<'a> {
    pub(super) file: String,
    pub(super) src: &'a str,
    /// Byte offset of each line's start (line numbers by binary search).
    pub(super) starts: Vec<usize>,
}

impl Ctx<'_> {
    pub(super) fn line_of(&self, offset: usize) -> usize {
        self.starts.partition_point(|&s| s <= offset.min(self.src.len()))
    }
    /// The origin of `key` inside the entry spanning `span`.
    pub(super) fn at(&self, span: std::ops::Range<usize>, key: &str) -> Origin {
        Origin::new(self.err(span, key, "").line, key)
    }
    /// Error at `key` inside the entry spanning `span` (finds the key's own line when present).
    pub(super) fn err(&self, span: std::ops::Range<usize>, key: &str, message: impl Into<String>) -> SceneError {
        // toml spans of a table cover only its header: search from the header to the next one
        let start = span.start.min(self.src.len());
        let body_start = self.src[start..].find('\n').map_or(self.src.len(), |i| start + i + 1);
        let mut end = self.src.len();
        let mut off = body_start;
        for line in self.src[body_start..].split_inclusive('\n') {
            if line.trim_start().starts_with('[') {
                end = off;
                break;
            }
            off += line.len();
        }
        let end = end.max(span.end.min(self.src.len()));
        self.err_between(start..end, key, message)
    }
    /// Error at `key` inside the value spanning `span`: within an inline table `{ ... }` its key
    /// is searched for there only; a table given under its own header as `err`.
    pub(super) fn err_in(&self, span: std::ops::Range<usize>, key: &str, message: impl Into<String>) -> SceneError {
        let inline = self.src.get(span.clone()).is_some_and(|t| t.starts_with('{'));
        if inline {
            return self.err_between(span, key, message);
        }
        self.err(span, key, message)
    }
    /// Error at the first `leaf =` of `key` in `range` (the range's start when there is none).
    pub(super) fn err_between(
        &self,
        range: std::ops::Range<usize>,
        key: &str,
        message: impl Into<String>,
    ) -> SceneError {
        let text = &self.src[range.clone()];
        let mut at = range.start;
        if !key.is_empty() {
            let leaf = key.rsplit('.').next().unwrap_or(key);
            let mut search = 0;
            while let Some(i) = text[search..].find(leaf) {
                let pos = search + i;
                let b = text.as_bytes();
                let before_ok = pos == 0 || !(b[pos - 1].is_ascii_alphanumeric() || b[pos - 1] == b'_');
                let rest = text[pos + leaf.len()..].trim_start();
                if before_ok && rest.starts_with('=') {
                    at = range.start + pos;
                    break;
                }
                search = pos + leaf.len();
            }
        }
        SceneError { file: self.file.clone(), line: self.line_of(at), key: key.to_string(), message: message.into() }
    }
}
