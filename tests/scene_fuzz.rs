//! Scene-parser robustness (issue #9): a fixed-seed mutation corpus of the shipped scenes
//! (scenes/*.toml, scenes/stability/*.toml, tests/scenes/*.toml) must never panic in
//! `scene::load_str` + `World::build`, and each case must finish within `CASE_BOUND_S`.
//!
//! Mutations (1 to 3 per case, seeded by the case index): byte replacements with TOML
//! punctuation, digits and letters; numbers swapped for extreme values (1e39, −0, nan, inf,
//! 3.4e38, 1e19, huge integers, the extent limit and just above it); line swaps, deletions and
//! duplications. Mesh paths are redirected to a tiny OBJ so that a case costs micro- to
//! milliseconds; every case is a pure function of (corpus, case index).
//!
//! Bound: an unmutated shipped scene (with the tiny mesh) loads and builds in well under 10 ms;
//! `CASE_BOUND_S` = 2 s leaves 200× for the slowest mutant on a loaded 2-core machine, while the
//! hangs this guards against (a FIFO, a quadratic build) take minutes or forever.

mod common;

use common::{root, tmp_dir};
use forecast::accel::World;
use forecast::sampling::rng::{stream, Rng};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Cases in CI; `SCENE_FUZZ_CASES=N` runs more (a deeper local search, same seeds).
const CASES: usize = 5000;
const CASE_BOUND_S: f64 = 2.0;

const EXTREMES: &[&str] = &[
    "1e39",
    "-1e39",
    "-0",
    "-0.0",
    "nan",
    "-nan",
    "inf",
    "-inf",
    "3.4e38",
    "-3.4e38",
    "1e19",
    "1e30",
    "1e-45",
    "0",
    "0.0",
    "-1",
    "4294967295",
    "4294967296",
    "18446744073709551615",
    "99999999999999999999999",
    "1e12",
    "1.000001e12",
];

const BYTES: &[u8] = b"[]{}=\",.#\n -+0123456789eEnaifx_";

fn corpus() -> Vec<(String, String)> {
    let mut out = Vec::new();
    for dir in ["scenes", "scenes/stability", "tests/scenes"] {
        let mut files: Vec<PathBuf> = std::fs::read_dir(root().join(dir))
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|x| x == "toml"))
            .collect();
        files.sort();
        for p in files {
            let src = std::fs::read_to_string(&p).unwrap();
            // redirect every mesh to the tiny stand-in
            let src: String =
                src.lines()
                    .map(|l| {
                        if l.trim_start().starts_with("file") {
                            "file = \"tiny.obj\"".to_string()
                        } else {
                            l.to_string()
                        }
                    })
                    .collect::<Vec<_>>()
                    .join("\n");
            out.push((p.file_name().unwrap().to_string_lossy().into_owned(), src + "\n"));
        }
    }
    assert!(out.len() >= 10, "corpus too small: {}", out.len());
    out
}

fn pick(rng: &mut Rng, n: usize) -> usize {
    (rng.next_u32() as usize) % n.max(1)
}

/// Byte offsets of the numbers (and `true`/`false`/`nan`/`inf` words) in `src`.
fn number_spans(src: &str) -> Vec<(usize, usize)> {
    let b = src.as_bytes();
    let mut spans = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let starts = b[i].is_ascii_digit()
            || ((b[i] == b'-' || b[i] == b'+') && b.get(i + 1).is_some_and(|c| c.is_ascii_digit()));
        let word_start = i == 0 || !(b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_' || b[i - 1] == b'"');
        if starts && word_start {
            let mut j = i + 1;
            while j < b.len() && (b[j].is_ascii_alphanumeric() || b"._+-".contains(&b[j])) {
                j += 1;
            }
            spans.push((i, j));
            i = j;
        } else {
            i += 1;
        }
    }
    spans
}

fn mutate(src: &str, rng: &mut Rng) -> String {
    let mut s = src.to_string();
    for _ in 0..1 + pick(rng, 3) {
        match pick(rng, 5) {
            0 => {
                // byte replacement (ASCII only, so the text stays UTF-8)
                let b: Vec<usize> = s.char_indices().filter(|(_, c)| c.is_ascii()).map(|(i, _)| i).collect();
                if let Some(&i) = b.get(pick(rng, b.len())) {
                    let c = BYTES[pick(rng, BYTES.len())] as char;
                    s.replace_range(i..i + 1, &c.to_string());
                }
            }
            1 | 2 => {
                let spans = number_spans(&s);
                if let Some(&(i, j)) = spans.get(pick(rng, spans.len())) {
                    s.replace_range(i..j, EXTREMES[pick(rng, EXTREMES.len())]);
                }
            }
            _ => {
                let mut lines: Vec<String> = s.lines().map(str::to_string).collect();
                let (a, b) = (pick(rng, lines.len()), pick(rng, lines.len()));
                match pick(rng, 3) {
                    0 => lines.swap(a, b),
                    1 => {
                        lines.remove(a);
                    }
                    _ => {
                        let l = lines[a].clone();
                        lines.insert(b, l);
                    }
                }
                s = lines.join("\n") + "\n";
            }
        }
    }
    s
}

/// Loads and builds; Err(panic message) on a panic.
fn run_case(src: &str, dir: &Path) -> Result<bool, String> {
    catch_unwind(AssertUnwindSafe(|| match forecast::scene::load_str(src, "fuzz.toml", dir) {
        Ok(scene) => World::build(scene).is_ok(),
        Err(e) => {
            assert!(!e.message.is_empty() && e.file == "fuzz.toml", "error without a message: {e:?}");
            false
        }
    }))
    .map_err(|p| {
        p.downcast_ref::<String>()
            .cloned()
            .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
            .unwrap_or_default()
    })
}

#[test]
fn mutated_shipped_scenes_never_panic_or_hang() {
    let dir = tmp_dir("scene-fuzz");
    std::fs::write(dir.join("tiny.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 4\n")
        .unwrap();
    let corpus = corpus();
    // the unmutated corpus loads (else the mutants would test nothing but the first error)
    for (name, src) in &corpus {
        assert_eq!(run_case(src, &dir), Ok(true), "{name} does not load unmutated");
    }
    let (mut failures, mut slow, mut loaded) = (Vec::new(), Vec::new(), 0usize);
    let cases = std::env::var("SCENE_FUZZ_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(CASES);
    let mut worst = 0.0f64;
    let started = Instant::now();
    for case in 0..cases {
        let mut rng = Rng::keyed(0x5eed, stream::MISC, case as u64, 0);
        let (name, src) = &corpus[case % corpus.len()];
        let m = mutate(src, &mut rng);
        let t = Instant::now();
        let r = run_case(&m, &dir);
        let dt = t.elapsed().as_secs_f64();
        worst = worst.max(dt);
        match r {
            Ok(ok) => loaded += ok as usize,
            Err(msg) => failures.push(format!("case {case} ({name}): panic: {msg}\n--- mutant ---\n{m}")),
        }
        if dt > CASE_BOUND_S {
            slow.push(format!("case {case} ({name}): {dt:.2} s"));
        }
    }
    eprintln!(
        "scene fuzz: {cases} cases, {loaded} loaded and built, worst {worst:.4} s, total {:.2} s",
        started.elapsed().as_secs_f64()
    );
    assert!(failures.is_empty(), "{} panic(s); first:\n{}", failures.len(), failures[0]);
    assert!(slow.is_empty(), "cases over {CASE_BOUND_S} s: {slow:?}");
    // the corpus must exercise both paths
    assert!(loaded > cases / 10 && loaded < cases, "{loaded} of {cases} mutants loaded");
}
