//! Parser robustness (issues #9, #31, #61, #63): fixed-seed mutation corpora of the TOML scenes
//! (scenes/*.toml, scenes/stability/*.toml, tests/scenes/*.toml), of Mitsuba XML scenes (the SMS
//! ring and `XML_BASE`, every shape and BSDF kind), of PLY meshes (ASCII and binary), of texture
//! images (PNG, JPEG, OpenEXR, Radiance HDR: tests/data/texture/ and tests/data/fuzz-images/,
//! read as a `bitmap` reflectance and normal map of a fixed XML scene), of OBJ meshes with UVs
//! (a textured, normal-mapped `obj` shape of a fixed XML scene), of rendered EXRs as `diff` and
//! `compare` read them (`image_io::read_exr` and its variance layers), of checkpoints (payloads
//! forged with a valid checksum, headers, lengths) and of command lines (`Cli::parse_checked_from`
//! and `render`'s job) must never panic, hang or abort, and each case must finish within
//! `CASE_BOUND_S` (a case past `HANG_S` + `HANG_CONFIRM_S` is a hang: the test fails naming the
//! mutant). An image, OBJ, EXR or checkpoint mutant that does not load must be an error that
//! names its file.
//!
//! `bash scripts/fuzz.sh SECONDS` runs every corpus for that long (new seeds, niced, one input at
//! a time; `FORECAST_FUZZ_SECS=N cargo test --release --test scene_fuzz -- --ignored` is its
//! in-process part) and prints, per parser, the inputs, panics, hangs and aborts (an abort ends
//! the process: the script counts it from the state file and goes on).
//! Images are cut short, have bytes overwritten, bits flipped in their first 64 bytes, runs of
//! bytes duplicated or removed, and header fields (sizes, PNG bit depth and colour type, JPEG
//! components, EXR windows and tiles) set to extremes, each format's own way (PNG's CRC kept
//! valid); OBJ meshes take the TOML mutations and indices past either end.
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
use std::sync::mpsc;
use std::time::{Duration, Instant};

/// Cases in CI; `SCENE_FUZZ_CASES=N` runs more (a deeper local search, same seeds).
const CASES: usize = 5000;
const CASE_BOUND_S: f64 = 2.0;
/// A case still running after this long is a hang (the worker is abandoned, the case reported).
const HANG_S: f64 = 10.0;
/// What a case past `HANG_S` gets more before it is a hang (a starved worker, not a hang).
const HANG_CONFIRM_S: f64 = 50.0;

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
    run_input(&Input::Toml(src.to_string()), dir)
}

/// One mutant of one of the five formats: a scene file (TOML, XML), a mesh read alone (PLY), or
/// a file a fixed XML scene reads (an image as its textures, an OBJ mesh with UVs as a shape).
#[derive(Clone)]
enum Input {
    Toml(String),
    Xml(String),
    Ply(Vec<u8>),
    /// The image's corpus name (its extension kept) and bytes.
    Image(String, Vec<u8>),
    Obj(Vec<u8>),
    /// An EXR as `diff` and `compare` read a rendered image (`image_io::read_exr` and its
    /// variance layers).
    Exr(Vec<u8>),
    /// A checkpoint file (`Checkpoint::from_bytes`).
    Ckpt(Vec<u8>),
    /// A command line (`Cli::parse_checked_from`, then `render`'s job).
    Cli(Vec<String>),
}

impl Input {
    fn show(&self) -> String {
        match self {
            Input::Toml(s) | Input::Xml(s) => s.chars().take(4000).collect(),
            Input::Ply(b) | Input::Obj(b) => String::from_utf8_lossy(&b[..b.len().min(4000)]).into_owned(),
            Input::Image(name, b) => format!("{name}, {} bytes: {:02x?}", b.len(), &b[..b.len().min(1500)]),
            Input::Exr(b) | Input::Ckpt(b) => format!("{} bytes: {:02x?}", b.len(), &b[..b.len().min(1500)]),
            Input::Cli(a) => format!("{a:?}"),
        }
    }
}

/// Writes a mutant the fixed scene `xml` reads (`$FILE` in it) under a name no other case
/// uses (an abandoned worker may still hold an earlier one), loads the scene: its error must
/// name that file. Returns the file's name and the load's result.
fn load_with_file(
    dir: &Path,
    name: &str,
    bytes: &[u8],
    xml: &str,
) -> (String, Result<forecast::scene::Scene, forecast::scene::SceneError>) {
    static NEXT: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let file = format!("m{}-{name}", NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed));
    std::fs::write(dir.join(&file), bytes).unwrap();
    let r = forecast::scene::mitsuba::load_str(&xml.replace("$FILE", &file), "fuzz.xml", dir, &[]);
    let _ = std::fs::remove_file(dir.join(&file));
    (file, r)
}

/// A scene around a mutated file: Ok(it built), or its error names the file (every other part
/// of the scene is valid).
fn built_or_names(r: Result<forecast::scene::Scene, forecast::scene::SceneError>, file: &str) -> bool {
    match r {
        Ok(scene) => World::build(scene).is_ok(),
        Err(e) => {
            assert!(e.file == "fuzz.xml" && e.line > 0 && e.message.contains(file), "error without the file: {e}");
            false
        }
    }
}

/// Loads (and builds) one input; Ok(loaded), Err(panic message) on a panic.
fn run_input(input: &Input, dir: &Path) -> Result<bool, String> {
    catch_unwind(AssertUnwindSafe(|| {
        let (r, file) = match input {
            Input::Toml(s) => (forecast::scene::load_str(s, "fuzz.toml", dir), "fuzz.toml"),
            Input::Xml(s) => (forecast::scene::mitsuba::load_str(s, "fuzz.xml", dir, &[]), "fuzz.xml"),
            Input::Image(name, b) => {
                let hdr = name.ends_with(".exr") || name.ends_with(".hdr");
                let xml = XML_IMAGE.replace("$REFLECTANCE", if hdr { REFLECTANCE_HDR } else { REFLECTANCE_LDR });
                let (f, r) = load_with_file(dir, name, b, &xml);
                return built_or_names(r, &f);
            }
            Input::Obj(b) => {
                let (f, r) = load_with_file(dir, "mesh.obj", b, XML_OBJ);
                return built_or_names(r, &f);
            }
            Input::Exr(b) => {
                static NEXT: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
                let file = dir.join(format!("m{}-out.exr", NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed)));
                std::fs::write(&file, b).unwrap();
                let r = forecast::image_io::read_exr(&file)
                    .and_then(|i| forecast::image_io::read_exr_variance(&file).map(|v| (i, v)));
                let _ = std::fs::remove_file(&file);
                return match r {
                    Ok((i, v)) => {
                        assert!(i.pixels.len() == i.width * i.height, "pixels of {}x{}", i.width, i.height);
                        assert!(v.is_none_or(|v| v.same_size(&i)), "variance of another size");
                        true
                    }
                    Err(e) => {
                        let name = file.file_name().unwrap().to_string_lossy().into_owned();
                        assert!(e.to_string().contains(&name), "EXR error without the file: {e}");
                        false
                    }
                };
            }
            Input::Ckpt(b) => {
                return match forecast::checkpoint::Checkpoint::from_bytes(b, Path::new("fuzz.ckpt")) {
                    Ok(_) => true,
                    Err(e) => {
                        assert!(e.to_string().contains("fuzz.ckpt"), "checkpoint error without the file: {e}");
                        false
                    }
                };
            }
            Input::Cli(args) => {
                return match forecast::cli::Cli::parse_checked_from(args) {
                    Ok(cli) => {
                        if let forecast::cli::Command::Render(a) = &cli.command {
                            let _ = a.job();
                        }
                        true
                    }
                    Err(e) => {
                        let _ = e.render().to_string();
                        false
                    }
                };
            }
            Input::Ply(b) => {
                return match forecast::scene::ply::parse(b) {
                    Ok(m) => {
                        assert!(m.faces.iter().flatten().all(|&i| (i as usize) < m.positions.len()), "bad index");
                        assert!(m.normals.as_ref().is_none_or(|n| n.len() == m.positions.len()), "short normals");
                        true
                    }
                    Err(e) => {
                        assert!(!e.is_empty(), "PLY error without a message");
                        false
                    }
                }
            }
        };
        match r {
            Ok(scene) => World::build(scene).is_ok(),
            Err(e) => {
                assert!(!e.message.is_empty() && e.file == file, "error without a message: {e:?}");
                false
            }
        }
    }))
    .map_err(|p| {
        p.downcast_ref::<String>()
            .cloned()
            .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
            .unwrap_or_default()
    })
}

/// Runs inputs on a worker thread, each with a deadline: a case past `HANG_S` is reported as
/// a hang and the worker abandoned (a new one takes the next case).
struct Runner {
    dir: PathBuf,
    tx: Option<mpsc::Sender<Input>>,
    rx: Option<mpsc::Receiver<Result<bool, String>>>,
}

enum Outcome {
    Done(Result<bool, String>, f64),
    Hang,
}

impl Runner {
    fn new(dir: &Path) -> Runner {
        Runner { dir: dir.to_path_buf(), tx: None, rx: None }
    }
    fn run(&mut self, input: Input) -> Outcome {
        if self.tx.is_none() {
            let (tx, wrx) = mpsc::channel::<Input>();
            let (wtx, rx) = mpsc::channel();
            let dir = self.dir.clone();
            std::thread::spawn(move || {
                for i in wrx {
                    if wtx.send(run_input(&i, &dir)).is_err() {
                        break;
                    }
                }
            });
            (self.tx, self.rx) = (Some(tx), Some(rx));
        }
        let t = Instant::now();
        self.tx.as_ref().unwrap().send(input).unwrap();
        let rx = self.rx.as_ref().unwrap();
        // past `HANG_S` of wall time, the case gets `HANG_CONFIRM_S` more: on a machine shared
        // with other builds a worker may be starved for seconds (a case of 0.2 s once took over
        // 10 s of wall time here), and such a case ends, over `CASE_BOUND_S`, as slow
        let r = rx.recv_timeout(Duration::from_secs_f64(HANG_S)).or_else(|e| match e {
            mpsc::RecvTimeoutError::Timeout => rx.recv_timeout(Duration::from_secs_f64(HANG_CONFIRM_S)),
            e => Err(e),
        });
        match r {
            Ok(r) => Outcome::Done(r, t.elapsed().as_secs_f64()),
            Err(_) => {
                (self.tx, self.rx) = (None, None);
                Outcome::Hang
            }
        }
    }
}

/// The fuzz directory: the tiny stand-in meshes every corpus points at.
fn fuzz_dir(name: &str) -> PathBuf {
    let dir = tmp_dir(name);
    std::fs::write(dir.join("tiny.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 4\n")
        .unwrap();
    std::fs::write(dir.join("tiny.ply"), PLY_ASCII).unwrap();
    std::fs::copy(root().join("tests/data/texture/rgb8.png"), dir.join("tex.png")).unwrap();
    dir
}

#[test]
fn mutated_shipped_scenes_never_panic_or_hang() {
    let dir = fuzz_dir("scene-fuzz");
    let corpus = corpus();
    // the unmutated corpus loads (else the mutants would test nothing but the first error)
    for (name, src) in &corpus {
        assert_eq!(run_case(src, &dir), Ok(true), "{name} does not load unmutated");
    }
    let cases = std::env::var("SCENE_FUZZ_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(CASES);
    let inputs = (0..cases).map(|case| {
        let mut rng = Rng::keyed(0x5eed, stream::MISC, case as u64, 0);
        let (name, src) = &corpus[case % corpus.len()];
        (name.clone(), Input::Toml(mutate(src, &mut rng)))
    });
    let loaded = fuzz("TOML", &dir, inputs);
    // the corpus must exercise both paths
    assert!(loaded > cases / 10 && loaded < cases, "{loaded} of {cases} mutants loaded");
}

/// Runs every input with its deadline; fails on a panic, a hang or a case over `CASE_BOUND_S`;
/// returns how many loaded (and built).
fn fuzz(what: &str, dir: &Path, inputs: impl Iterator<Item = (String, Input)>) -> usize {
    let mut runner = Runner::new(dir);
    let (mut failures, mut slow, mut loaded, mut n) = (Vec::new(), Vec::new(), 0usize, 0usize);
    let (mut worst, mut worst_case) = (0.0f64, String::new());
    let started = Instant::now();
    for (case, (name, input)) in inputs.enumerate() {
        n += 1;
        match runner.run(input.clone()) {
            Outcome::Done(Ok(ok), dt) => {
                loaded += ok as usize;
                if dt > worst {
                    (worst, worst_case) = (dt, format!("case {case}, {name}"));
                }
                if let Some(out) = std::env::var_os("SCENE_FUZZ_SLOW").filter(|_| dt > 0.05) {
                    // SCENE_FUZZ_SLOW=DIR keeps the slow mutants
                    eprintln!("{what} case {case} ({name}): {dt:.3} s");
                    if let Input::Image(_, b) | Input::Obj(b) | Input::Ply(b) = &input {
                        let _ = std::fs::write(Path::new(&out).join(format!("{case}-{name}")), b);
                    }
                }
                if dt > CASE_BOUND_S {
                    slow.push(format!("case {case} ({name}): {dt:.2} s"));
                }
            }
            Outcome::Done(Err(msg), _) => {
                failures.push(format!("case {case} ({name}): panic: {msg}\n--- mutant ---\n{}", input.show()))
            }
            Outcome::Hang => failures.push(format!(
                "case {case} ({name}): hang (> {} s)\n--- mutant ---\n{}",
                HANG_S + HANG_CONFIRM_S,
                input.show()
            )),
        }
    }
    eprintln!(
        "{what} fuzz: {n} cases, {loaded} loaded and built, worst {worst:.4} s ({worst_case}), total {:.2} s",
        started.elapsed().as_secs_f64()
    );
    assert!(failures.is_empty(), "{} panic(s) or hang(s); first:\n{}", failures.len(), failures[0]);
    assert!(slow.is_empty(), "cases over {CASE_BOUND_S} s: {slow:?}");
    loaded
}

// ---- Mitsuba XML ----

/// Cases in CI for XML and PLY each.
const CASES_XML: usize = 3000;
const CASES_PLY: usize = 3000;

/// A scene with every shape and BSDF kind the XML reader knows (meshes: the tiny stand-ins).
const XML_BASE: &str = r#"<scene version="3.0.0">
<default name="spp" value="4"/>
<default name="forecast_method" value="pt"/>
<integrator type="path"><integer name="max_depth" value="16"/></integrator>
<sensor type="perspective"><float name="fov" value="40"/><string name="fov_axis" value="y"/>
  <transform name="to_world"><lookat origin="0, 1, 3.88" target="0, 1, 0" up="0, 1, 0"/></transform>
  <sampler type="independent"><integer name="sample_count" value="$spp"/></sampler>
  <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="16"/></film>
</sensor>
<bsdf type="diffuse" id="white"><rgb name="reflectance" value="0.7, 0.7, 0.7"/></bsdf>
<bsdf type="twosided" id="two"><bsdf type="diffuse"><rgb name="reflectance" value="0.2"/></bsdf></bsdf>
<bsdf type="conductor" id="gold"><string name="material" value="Au"/></bsdf>
<bsdf type="dielectric" id="glass"><float name="int_ior" value="1.5"/></bsdf>
<shape type="rectangle"><transform name="to_world"><scale value="2"/><rotate x="1" angle="-90"/></transform><ref id="white"/></shape>
<shape type="cube"><transform name="to_world"><scale value="0.2"/><translate value="0.5 0.2 0"/></transform><ref id="two"/></shape>
<shape type="sphere"><point name="center" value="-0.5 0.3 0"/><float name="radius" value="0.3"/><ref id="glass"/></shape>
<shape type="disk"><transform name="to_world"><translate value="0 0.01 0.5"/></transform><ref id="gold"/></shape>
<shape type="cylinder"><point name="p0" value="0 0 -0.5"/><point name="p1" value="0 0.5 -0.5"/><float name="radius" value="0.1"/></shape>
<shape type="ply"><string name="filename" value="tiny.ply"/><transform name="to_world"><matrix value="0.5 0 0 0 0 0.5 0 0.5 0 0 0.5 0 0 0 0 1"/></transform></shape>
<shape type="obj"><string name="filename" value="tiny.obj"/><boolean name="face_normals" value="true"/></shape>
<shape type="rectangle"><transform name="to_world"><scale value="0.3"/><rotate x="1" angle="90"/><translate value="0 1.9 0"/></transform>
  <emitter type="area"><rgb name="radiance" value="10"/></emitter></shape>
<emitter type="point"><point name="position" x="0" y="1.5" z="1"/><rgb name="intensity" value="2"/></emitter>
</scene>
"#;

const XML_BYTES: &[u8] = b"<>/=\"' \n0123456789.-e,$&;!abc";
const XML_SNIPPETS: &[&str] = &[
    "<shape type=\"ply\"><string name=\"filename\" value=\"tiny.ply\"/></shape>",
    "<shape type=\"sphere\"><float name=\"radius\" value=\"1e19\"/></shape>",
    "<emitter type=\"point\"><point name=\"position\" value=\"0 5 0\"/><rgb name=\"intensity\" value=\"1e9\"/></emitter>",
    "<default name=\"forecast_photons\" value=\"4000000000\"/>",
    "<default name=\"forecast_roi_0\" value=\"0 0 8 8 r\"/>",
    "<transform name=\"to_world\"><scale value=\"0\"/></transform>",
    "<transform name=\"to_world\"><matrix value=\"1 0 0 0 0 1 0 0 0 0 1 0 0 0 1 0\"/></transform>",
    "<bsdf type=\"twosided\"><bsdf type=\"twosided\"><bsdf type=\"diffuse\"/></bsdf></bsdf>",
    "<integrator type=\"sppm\"><integer name=\"photonCount\" value=\"1000\"/></integrator>",
    "<ref id=\"white\"/>",
    "<bsdf type=\"diffuse\" id=\"white\"/>",
    "<![CDATA[x]]>",
    "<!-- c -->",
];
const XML_TYPES: &[&str] = &[
    "rectangle",
    "cube",
    "sphere",
    "disk",
    "cylinder",
    "obj",
    "ply",
    "diffuse",
    "conductor",
    "dielectric",
    "twosided",
    "area",
    "point",
    "path",
    "sppm",
    "",
];

fn xml_corpus() -> Vec<(String, String)> {
    let ring = std::fs::read_to_string(root().join("scenes/external/sms-ring/ring.xml")).unwrap();
    // (the ring's shapes are analytic: no mesh files)
    vec![("ring.xml".into(), ring), ("base.xml".into(), XML_BASE.to_string())]
}

fn mutate_xml(src: &str, rng: &mut Rng) -> String {
    let mut s = src.to_string();
    for _ in 0..1 + pick(rng, 3) {
        match pick(rng, 8) {
            0 => {
                let b: Vec<usize> = s.char_indices().filter(|(_, c)| c.is_ascii()).map(|(i, _)| i).collect();
                if let Some(&i) = b.get(pick(rng, b.len())) {
                    let c = XML_BYTES[pick(rng, XML_BYTES.len())] as char;
                    s.replace_range(i..i + 1, &c.to_string());
                }
            }
            1 | 2 => {
                let spans = number_spans(&s);
                if let Some(&(i, j)) = spans.get(pick(rng, spans.len())) {
                    s.replace_range(i..j, EXTREMES[pick(rng, EXTREMES.len())]);
                }
            }
            3 => {
                // a type="..." swapped
                let at: Vec<usize> = s.match_indices("type=\"").map(|(i, _)| i + 6).collect();
                if let Some(&i) = at.get(pick(rng, at.len())) {
                    let j = i + s[i..].find('"').unwrap_or(0);
                    s.replace_range(i..j, XML_TYPES[pick(rng, XML_TYPES.len())]);
                }
            }
            4 => {
                // a snippet inserted after a random '>'
                let at: Vec<usize> = s.match_indices('>').map(|(i, _)| i + 1).collect();
                if let Some(&i) = at.get(pick(rng, at.len())) {
                    s.insert_str(i, XML_SNIPPETS[pick(rng, XML_SNIPPETS.len())]);
                }
            }
            5 => {
                // deep nesting around a random point
                let at: Vec<usize> = s.match_indices('>').map(|(i, _)| i + 1).collect();
                if let Some(&i) = at.get(pick(rng, at.len())) {
                    let n = [10, 70, 2000][pick(rng, 3)];
                    s.insert_str(i, &format!("{}{}", "<bsdf type=\"twosided\">".repeat(n), "</bsdf>".repeat(n)));
                }
            }
            _ => s = line_op(&s, rng),
        }
    }
    s
}

/// A line swapped, deleted or duplicated.
fn line_op(s: &str, rng: &mut Rng) -> String {
    let mut lines: Vec<String> = s.lines().map(str::to_string).collect();
    if lines.is_empty() {
        return s.to_string();
    }
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
    lines.join("\n") + "\n"
}

fn xml_inputs(seed: u64, cases: usize) -> impl Iterator<Item = (String, Input)> {
    let corpus = xml_corpus();
    (0..cases).map(move |case| {
        let mut rng = Rng::keyed(seed, stream::MISC, case as u64, 1);
        let (name, src) = &corpus[case % corpus.len()];
        (name.clone(), Input::Xml(mutate_xml(src, &mut rng)))
    })
}

#[test]
fn mutated_xml_scenes_never_panic_or_hang() {
    let dir = fuzz_dir("scene-fuzz-xml");
    for (name, src) in xml_corpus() {
        assert_eq!(run_input(&Input::Xml(src), &dir), Ok(true), "{name} does not load unmutated");
    }
    let loaded = fuzz("XML", &dir, xml_inputs(0x5eed, CASES_XML));
    assert!(loaded > CASES_XML / 10 && loaded < CASES_XML, "{loaded} of {CASES_XML} mutants loaded");
}

// ---- PLY ----

const PLY_ASCII: &str = "ply\nformat ascii 1.0\ncomment tiny\nelement vertex 4\nproperty float x\nproperty float y\n\
property float z\nproperty float nx\nproperty float ny\nproperty float nz\nelement face 2\n\
property list uchar int vertex_indices\nend_header\n0 0 0 0 0 1\n1 0 0 0 0 1\n1 1 0 0 0 1\n0 1 0 0 0 1\n3 0 1 2\n4 0 2 3 1\n";

fn ply_corpus() -> Vec<(String, Vec<u8>)> {
    let m = forecast::scene::ply::parse(PLY_ASCII.as_bytes()).unwrap();
    let bin = forecast::scene::ply::write_binary(&m);
    let flat = forecast::scene::ply::write_binary(&forecast::scene::ply::IndexedMesh { normals: None, ..m });
    vec![("ascii.ply".into(), PLY_ASCII.as_bytes().to_vec()), ("binary.ply".into(), bin), ("flat.ply".into(), flat)]
}

const PLY_WORDS: &[&str] = &[
    "element vertex 3", "element face 1", "element junk 18446744073709551615", "property float x", "property float nx",
    "property list uchar int vertex_indices", "property list float int vertex_indices", "property list uint uint vertex_indices",
    "element vertex 1\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz",
    "format binary_big_endian 1.0", "format binary_little_endian 1.0", "format ascii 1.0", "end_header", "comment x",
];

fn mutate_ply(src: &[u8], rng: &mut Rng) -> Vec<u8> {
    let mut b = src.to_vec();
    let header_end = b.windows(10).position(|w| w == b"end_header").map_or(b.len(), |i| i + 11);
    for _ in 0..1 + pick(rng, 3) {
        match pick(rng, 6) {
            0 => {
                // any byte anywhere (binary bodies)
                for _ in 0..1 + pick(rng, 4) {
                    let i = pick(rng, b.len());
                    if i < b.len() {
                        b[i] = rng.next_u32() as u8;
                    }
                }
            }
            1 | 2 => {
                // a number in the text (header counts, ASCII values) → an extreme
                let s = String::from_utf8_lossy(&b).into_owned();
                let spans = number_spans(&s);
                if let Some(&(i, j)) = spans.get(pick(rng, spans.len())) {
                    if s.is_char_boundary(i) && s.is_char_boundary(j) && j <= b.len() {
                        b.splice(i..j, EXTREMES[pick(rng, EXTREMES.len())].bytes());
                    }
                }
            }
            3 => {
                // a header line replaced or inserted
                let lines: Vec<usize> = (0..header_end.min(b.len())).filter(|&i| i == 0 || b[i - 1] == b'\n').collect();
                if let Some(&i) = lines.get(pick(rng, lines.len())) {
                    let w = format!("{}\n", PLY_WORDS[pick(rng, PLY_WORDS.len())]);
                    if pick(rng, 2) == 0 {
                        let j = i + b[i..].iter().position(|&c| c == b'\n').map_or(0, |k| k + 1);
                        b.splice(i..j, w.bytes());
                    } else {
                        b.splice(i..i, w.bytes());
                    }
                }
            }
            4 => {
                let n = pick(rng, b.len() + 1);
                b.truncate(n);
            }
            _ => {
                // body bytes duplicated or removed
                let (i, n) = (pick(rng, b.len()), 1 + pick(rng, 16));
                if pick(rng, 2) == 0 {
                    let chunk: Vec<u8> = b[i..(i + n).min(b.len())].to_vec();
                    b.splice(i..i, chunk);
                } else {
                    b.drain(i..(i + n).min(b.len()));
                }
            }
        }
    }
    b
}

fn ply_inputs(seed: u64, cases: usize) -> impl Iterator<Item = (String, Input)> {
    let corpus = ply_corpus();
    (0..cases).map(move |case| {
        let mut rng = Rng::keyed(seed, stream::MISC, case as u64, 2);
        let (name, src) = &corpus[case % corpus.len()];
        (name.clone(), Input::Ply(mutate_ply(src, &mut rng)))
    })
}

#[test]
fn mutated_ply_meshes_never_panic_or_hang() {
    let dir = fuzz_dir("scene-fuzz-ply");
    for (name, b) in ply_corpus() {
        assert_eq!(run_input(&Input::Ply(b), &dir), Ok(true), "{name} does not load unmutated");
    }
    let loaded = fuzz("PLY", &dir, ply_inputs(0x5eed, CASES_PLY));
    assert!(loaded > CASES_PLY / 20 && loaded < CASES_PLY, "{loaded} of {CASES_PLY} mutants loaded");
}

// ---- images (the bitmap textures' decoders) and OBJ meshes with UVs (issue #61) ----

/// Cases in CI for images and OBJ meshes each (as many as XML and PLY).
const CASES_IMAGE: usize = 3000;
const CASES_OBJ: usize = 3000;

/// The scene an image mutant is read by: a rectangle (it has UVs) whose normal map reads the
/// image raw and whose diffuse reflectance (`$REFLECTANCE`) reads it as a colour where its values
/// are in [0, 1] (PNG, JPEG: `REFLECTANCE_LDR`; EXR and HDR hold larger ones: `REFLECTANCE_HDR`).
const XML_IMAGE: &str = r#"<scene version="3.0.0">
<sensor type="perspective"><float name="fov" value="40"/><transform name="to_world"><lookat origin="0, 0, 3" target="0, 0, 0" up="0, 1, 0"/></transform>
  <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film></sensor>
<shape type="rectangle">
  <bsdf type="normalmap">
    <texture name="normalmap" type="bitmap"><string name="filename" value="$FILE"/><boolean name="raw" value="true"/></texture>
    <bsdf type="diffuse">$REFLECTANCE</bsdf>
  </bsdf>
</shape>
<emitter type="point"><point name="position" x="0" y="0" z="2"/><rgb name="intensity" value="1"/></emitter>
</scene>
"#;
const REFLECTANCE_LDR: &str = r#"<texture name="reflectance" type="bitmap"><string name="filename" value="$FILE"/>
      <string name="filter_type" value="nearest"/></texture>"#;
const REFLECTANCE_HDR: &str = r#"<rgb name="reflectance" value="0.5"/>"#;

/// The scene an OBJ mutant is read by: the mesh with a bitmap reflectance under a normal map
/// (its UVs used), beside a rectangle (the scene is never empty).
const XML_OBJ: &str = r#"<scene version="3.0.0">
<sensor type="perspective"><float name="fov" value="40"/><transform name="to_world"><lookat origin="0, 0, 3" target="0, 0, 0" up="0, 1, 0"/></transform>
  <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film></sensor>
<shape type="rectangle"><transform name="to_world"><translate z="-1"/></transform></shape>
<shape type="obj"><string name="filename" value="$FILE"/>
  <bsdf type="normalmap">
    <texture name="normalmap" type="bitmap"><string name="filename" value="tex.png"/><boolean name="raw" value="true"/></texture>
    <bsdf type="diffuse"><texture name="reflectance" type="bitmap"><string name="filename" value="tex.png"/></texture></bsdf>
  </bsdf>
</shape>
<emitter type="point"><point name="position" x="0" y="0" z="2"/><rgb name="intensity" value="1"/></emitter>
</scene>
"#;

/// The committed images: tests/data/texture/ (8- and 16-bit PNG, grey PNG, RGB and Y EXR,
/// RGBE, baseline JPEG) and tests/data/fuzz-images/ (palette, RGBA, 16-bit grey and Adam7 PNG,
/// progressive and grey JPEG, ZIP, tiled PIZ and RLE EXR, run-length RGBE;
/// scripts/fuzz-images.py), a few hundred bytes each.
fn image_corpus() -> Vec<(String, Vec<u8>)> {
    let mut out = Vec::new();
    for dir in ["tests/data/texture", "tests/data/fuzz-images"] {
        let mut files: Vec<PathBuf> = std::fs::read_dir(root().join(dir))
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|x| ["png", "jpg", "exr", "hdr"].iter().any(|e| x == *e)))
            .collect();
        files.sort();
        out.extend(
            files.iter().map(|p| (p.file_name().unwrap().to_string_lossy().into_owned(), std::fs::read(p).unwrap())),
        );
    }
    assert!(out.len() >= 17, "image corpus too small: {}", out.len());
    out
}

/// Sizes a header edit writes (as the field's width allows): empty and tiny; 4096, 8192 and
/// 16384, whose products with each other claim 2^24 to 2^28 texels (16384² is the texel limit
/// itself); just past the limit's side (16385² > 2^28); 2^16 − 1, 2^16 and past them; the
/// integer extremes. A claim within the limit but past what the file can hold in its format is
/// refused from the header (`image_io::decode`'s claim bounds): before those, the JPEG decoder
/// filled what the header claimed (a 718-byte JPEG claiming 16384² decoded in 5.7 s and
/// 0.8 GB), so such claims had to be left out of this corpus.
const SIZES: &[i64] = &[0, 1, 2, 3, 4096, 8192, 16384, 16385, 65535, 65536, 100_000, 2_147_483_647, 4_294_967_295, -1];

/// One header field of the image set to an extreme: PNG's IHDR width, height, bit depth, colour
/// type or interlace method (its CRC kept valid, so the decoder reads the edit); JPEG's frame
/// height, width, both, or component count; Radiance's `-Y h +X w`; OpenEXR's data or display window
/// corners or tile size.
fn edit_header(b: &mut Vec<u8>, rng: &mut Rng) {
    let size = SIZES[pick(rng, SIZES.len())];
    if b.starts_with(b"\x89PNG") && b.len() >= 33 {
        let (at, v): (usize, Vec<u8>) = match pick(rng, 5) {
            k @ (0 | 1) => (16 + 4 * k, (size as u32).to_be_bytes().to_vec()),
            2 => (24, vec![[0, 1, 2, 3, 4, 8, 16, 32][pick(rng, 8)]]),
            3 => (25, vec![[0, 1, 2, 3, 4, 5, 6, 7][pick(rng, 8)]]),
            _ => (28, vec![[0, 1, 2][pick(rng, 3)]]),
        };
        b[at..at + v.len()].copy_from_slice(&v);
        let crc = crc32fast::hash(&b[12..29]);
        b[29..33].copy_from_slice(&crc.to_be_bytes());
    } else if b.starts_with(&[0xff, 0xd8]) {
        let sof = b.windows(2).position(|w| w[0] == 0xff && (0xc0..=0xc2).contains(&w[1]));
        if let Some(i) = sof.filter(|&i| i + 10 <= b.len()) {
            match pick(rng, 4) {
                k @ (0 | 1) => b[i + 5 + 2 * k..i + 7 + 2 * k].copy_from_slice(&(size as u16).to_be_bytes()),
                2 => {
                    // both sides: a claim of up to 2^32 texels
                    let other = SIZES[pick(rng, SIZES.len())] as u16;
                    b[i + 5..i + 9].copy_from_slice(&[(size as u16).to_be_bytes(), other.to_be_bytes()].concat());
                }
                _ => b[i + 9] = [0, 1, 2, 3, 4, 255][pick(rng, 6)],
            }
        }
    } else if b.starts_with(b"#?") {
        if let Some(i) = b.windows(3).position(|w| w == b"-Y ") {
            let end = i + b[i..].iter().position(|&c| c == b'\n').unwrap_or(b.len() - i);
            let line = String::from_utf8_lossy(&b[i..end]).into_owned();
            let mut w: Vec<String> = line.split(' ').map(str::to_string).collect();
            if w.len() == 4 {
                w[[1, 3][pick(rng, 2)]] = [size.to_string(), "99999999999".into(), "x".into()][pick(rng, 3)].clone();
                b.splice(i..end, w.join(" ").into_bytes());
            }
        }
    } else {
        let attr: &[u8] = [&b"dataWindow\0box2i\0"[..], b"displayWindow\0box2i\0", b"tiles\0tiledesc\0"][pick(rng, 3)];
        if let Some(i) = b.windows(attr.len()).position(|w| w == attr) {
            let at = i + attr.len() + 4 + 4 * pick(rng, if attr.starts_with(b"tiles") { 2 } else { 4 });
            if at + 4 <= b.len() {
                b[at..at + 4].copy_from_slice(&(size as i32).to_le_bytes());
            }
        }
    }
}

fn mutate_image(src: &[u8], rng: &mut Rng) -> Vec<u8> {
    let mut b = src.to_vec();
    for _ in 0..1 + pick(rng, 2) {
        match pick(rng, 6) {
            0 => {
                let n = pick(rng, b.len() + 1);
                b.truncate(n);
            }
            1 => {
                for _ in 0..1 + pick(rng, 4) {
                    let i = pick(rng, b.len());
                    if i < b.len() {
                        b[i] = rng.next_u32() as u8;
                    }
                }
            }
            2 | 3 => edit_header(&mut b, rng),
            4 => {
                // a bit flipped in the first 64 bytes (headers, chunk lengths)
                let i = pick(rng, b.len().min(64));
                if i < b.len() {
                    b[i] ^= 1 << pick(rng, 8);
                }
            }
            _ => {
                let (i, n) = (pick(rng, b.len()), 1 + pick(rng, 16));
                if pick(rng, 2) == 0 {
                    let chunk: Vec<u8> = b[i.min(b.len())..(i + n).min(b.len())].to_vec();
                    b.splice(i.min(b.len())..i.min(b.len()), chunk);
                } else {
                    b.drain(i.min(b.len())..(i + n).min(b.len()));
                }
            }
        }
    }
    b
}

fn image_inputs(seed: u64, cases: usize) -> impl Iterator<Item = (String, Input)> {
    let corpus = image_corpus();
    (0..cases).map(move |case| {
        let mut rng = Rng::keyed(seed, stream::MISC, case as u64, 4);
        let (name, src) = &corpus[case % corpus.len()];
        (name.clone(), Input::Image(name.clone(), mutate_image(src, &mut rng)))
    })
}

#[test]
fn mutated_images_never_panic_or_hang() {
    let dir = fuzz_dir("scene-fuzz-image");
    for (name, b) in image_corpus() {
        assert_eq!(run_input(&Input::Image(name.clone(), b), &dir), Ok(true), "{name} does not load unmutated");
    }
    // the corpus holds JPEG headers claiming 2^24 to 2^28 texels (the claims the decoder used to
    // fill, seconds each): `fuzz` holds each case to `CASE_BOUND_S`
    let claims = image_inputs(0x5eed, CASES_IMAGE)
        .filter(|(_, i)| {
            let Input::Image(_, b) = i else { return false };
            let sof = b.windows(2).position(|w| w[0] == 0xff && (0xc0..=0xc2).contains(&w[1]));
            let texels = sof.filter(|&i| b.starts_with(&[0xff, 0xd8]) && i + 9 <= b.len()).map(|i| {
                let h = u16::from_be_bytes([b[i + 5], b[i + 6]]) as u64;
                h * u16::from_be_bytes([b[i + 7], b[i + 8]]) as u64
            });
            texels.is_some_and(|t| (1 << 24..=1 << 28).contains(&t))
        })
        .count();
    eprintln!("{claims} JPEG mutants claim 2^24 to 2^28 texels");
    assert!(claims >= 5, "{claims} JPEG mutants claim 2^24 to 2^28 texels");
    let loaded = fuzz("image", &dir, image_inputs(0x5eed, CASES_IMAGE));
    assert!(loaded > CASES_IMAGE / 20 && loaded < CASES_IMAGE, "{loaded} of {CASES_IMAGE} mutants loaded");
}

/// OBJ meshes with UVs: the committed textured cube (per-face `vt` and `vn`) and a mesh of two
/// objects with corners without `vt`, `v//vn` corners, a quad, a `vt` with a third number and
/// comments after statements (relative, negative indices, which Mitsuba refuses, come from the
/// mutations).
fn obj_corpus() -> Vec<(String, Vec<u8>)> {
    let cube = std::fs::read(root().join("tests/scenes/mitsuba-plugins/box.obj")).unwrap();
    let mixed = "# two objects\no a\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\nvt 0 0\nvt 1 0 0\nvt 1 1\n\
vt 0 1 # last\nf 1/1/1 2/2/1 3/3/1 4/4/1\ng b\nv 0 0 1\nv 1 0 1\nv 0 1 1\nf 5/1 6/2 7\nf 5//1 6//1 7//1 # bare\n";
    vec![("box.obj".into(), cube), ("mixed.obj".into(), mixed.as_bytes().to_vec())]
}

const OBJ_BYTES: &[u8] = b"/ /-0123456789.#\nvtfnlpog e+";

/// Text mutations of an OBJ: bytes replaced with OBJ punctuation, digits and keywords' letters;
/// numbers (indices included) swapped for extremes and for indices past either end; lines
/// swapped, deleted or duplicated.
fn mutate_obj(src: &[u8], rng: &mut Rng) -> Vec<u8> {
    let mut s = String::from_utf8_lossy(src).into_owned();
    for _ in 0..1 + pick(rng, 3) {
        match pick(rng, 5) {
            0 => {
                let b: Vec<usize> = s.char_indices().filter(|(_, c)| c.is_ascii()).map(|(i, _)| i).collect();
                if let Some(&i) = b.get(pick(rng, b.len())) {
                    let c = OBJ_BYTES[pick(rng, OBJ_BYTES.len())] as char;
                    s.replace_range(i..i + 1, &c.to_string());
                }
            }
            1 | 2 => {
                let spans = number_spans(&s);
                if let Some(&(i, j)) = spans.get(pick(rng, spans.len())) {
                    let v = match pick(rng, 3) {
                        0 => EXTREMES[pick(rng, EXTREMES.len())].to_string(),
                        1 => ["0", "-0", "99", "-99", "25", "-25", "2147483648", "-9223372036854775808"][pick(rng, 8)]
                            .into(),
                        _ => format!("{}", pick(rng, 30) as i64 - 15),
                    };
                    s.replace_range(i..j, &v);
                }
            }
            _ => s = line_op(&s, rng),
        }
    }
    s.into_bytes()
}

fn obj_inputs(seed: u64, cases: usize) -> impl Iterator<Item = (String, Input)> {
    let corpus = obj_corpus();
    (0..cases).map(move |case| {
        let mut rng = Rng::keyed(seed, stream::MISC, case as u64, 5);
        let (name, src) = &corpus[case % corpus.len()];
        (name.clone(), Input::Obj(mutate_obj(src, &mut rng)))
    })
}

#[test]
fn mutated_obj_meshes_with_uvs_never_panic_or_hang() {
    let dir = fuzz_dir("scene-fuzz-obj");
    for (name, b) in obj_corpus() {
        assert_eq!(run_input(&Input::Obj(b), &dir), Ok(true), "{name} does not load unmutated");
    }
    let loaded = fuzz("OBJ", &dir, obj_inputs(0x5eed, CASES_OBJ));
    assert!(loaded > CASES_OBJ / 20 && loaded < CASES_OBJ, "{loaded} of {CASES_OBJ} mutants loaded");
}

// ---- the long run ----

/// The formats of the long run, in the order of its counts.
const FORMATS: [&str; 8] = ["TOML", "XML", "PLY", "image", "OBJ", "EXR", "checkpoint", "CLI"];

/// `FORECAST_FUZZ_SECS` seconds (default 600) of mutants of every format in turn (200 of each a
/// round, new seeds from round `FORECAST_FUZZ_FIRST_ROUND`, default 0); prints the counts and
/// fails on any panic or hang. An abort ends the process: `scripts/fuzz.sh`, which runs this,
/// learns which input it was from `FORECAST_FUZZ_STATE` (this writes `FORMAT ROUND CASE` there
/// before each input, and the counts so far to `STATE.counts` after each round), counts it and
/// goes on from the next round.
#[test]
#[ignore]
fn fuzz_for_a_while() {
    use std::io::{Seek, Write};
    let secs: f64 = std::env::var("FORECAST_FUZZ_SECS").ok().and_then(|v| v.parse().ok()).unwrap_or(600.0);
    let first: u64 = std::env::var("FORECAST_FUZZ_FIRST_ROUND").ok().and_then(|v| v.parse().ok()).unwrap_or(0);
    let state_path = std::env::var_os("FORECAST_FUZZ_STATE").map(PathBuf::from);
    let mut state = state_path.as_ref().map(|p| std::fs::File::create(p).unwrap());
    let dir = fuzz_dir("scene-fuzz-long");
    let toml = corpus();
    let mut runner = Runner::new(&dir);
    let started = Instant::now();
    let mut counts = [[0usize; 4]; FORMATS.len()]; // per format: run, loaded, panics, hangs
    let mut worst: [(f64, String); FORMATS.len()] = std::array::from_fn(|_| (0.0, String::new()));
    let mut found = Vec::new();
    let mut round = first;
    while started.elapsed().as_secs_f64() < secs {
        let seed = 0xf022 + round;
        let batch: Vec<(usize, String, Input)> = (0..200)
            .map(|case| {
                let mut rng = Rng::keyed(seed, stream::MISC, case as u64, 3);
                let (name, src) = &toml[case % toml.len()];
                (0, name.clone(), Input::Toml(mutate(src, &mut rng)))
            })
            .chain(xml_inputs(seed, 200).map(|(n, i)| (1, n, i)))
            .chain(ply_inputs(seed, 200).map(|(n, i)| (2, n, i)))
            .chain(image_inputs(seed, 200).map(|(n, i)| (3, n, i)))
            .chain(obj_inputs(seed, 200).map(|(n, i)| (4, n, i)))
            .chain(exr_inputs(seed, 200).map(|(n, i)| (5, n, i)))
            .chain(ckpt_inputs(seed, 200).map(|(n, i)| (6, n, i)))
            .chain(cli_inputs(seed, 200).map(|(n, i)| (7, n, i)))
            .collect();
        for (case, (f, name, input)) in batch.into_iter().enumerate() {
            if let Some(st) = state.as_mut() {
                st.rewind().unwrap();
                write!(st, "{:<12} {round:>12} {:>6}  ", FORMATS[f], case % 200).unwrap();
            }
            counts[f][0] += 1;
            match runner.run(input.clone()) {
                Outcome::Done(Ok(ok), dt) => {
                    counts[f][1] += ok as usize;
                    if dt > worst[f].0 {
                        worst[f] = (dt, format!("round {round}, case {}, {name}", case % 200));
                    }
                }
                Outcome::Done(Err(msg), _) => {
                    counts[f][2] += 1;
                    found.push(format!("round {round} ({name}): panic: {msg}\n{}", input.show()));
                }
                Outcome::Hang => {
                    counts[f][3] += 1;
                    found.push(format!("round {round} ({name}): hang\n{}", input.show()));
                }
            }
        }
        round += 1;
        if let Some(p) = &state_path {
            let lines: String = FORMATS
                .iter()
                .zip(&counts)
                .zip(&worst)
                .map(|((w, [n, l, p, h]), (dt, at))| format!("{w} {n} {l} {p} {h} {dt:.4} {at}\n"))
                .collect();
            std::fs::write(p.with_extension("counts"), format!("rounds {first} {round}\n{lines}")).unwrap();
        }
    }
    for (f, what) in FORMATS.iter().enumerate() {
        let [n, l, p, h] = counts[f];
        eprintln!(
            "{what}: {n} mutants, {l} loaded, {p} panics, {h} hangs, slowest {:.3} s ({})",
            worst[f].0, worst[f].1
        );
    }
    eprintln!(
        "total {:.0} s, rounds {first}..{round}, 0 aborts (the process ran to the end)",
        started.elapsed().as_secs_f64()
    );
    for f in &found {
        eprintln!("FINDING {f}");
    }
    assert!(found.is_empty(), "{} finding(s); first:\n{}", found.len(), found[0]);
}

// ---- rendered EXRs, checkpoints and command lines ----

const CASES_EXR: usize = 1500;
const CASES_CKPT: usize = 1500;
const CASES_CLI: usize = 3000;

/// Named files of a corpus.
type Corpus = Vec<(String, Vec<u8>)>;

/// What this program writes and reads back: the EXR and checkpoint of a tiny render (the binary
/// run once per test process), beside the committed EXR textures (every compression they use).
fn rendered_outputs() -> (Corpus, Corpus) {
    static DONE: std::sync::OnceLock<(Corpus, Corpus)> = std::sync::OnceLock::new();
    DONE.get_or_init(|| {
        let dir = tmp_dir("scene-fuzz-outputs");
        let out = dir.join("r");
        let st = std::process::Command::new(env!("CARGO_BIN_EXE_forecast"))
            .arg("render")
            .arg(root().join("scenes/cornell-box.toml"))
            .args(["--resolution", "6x4", "--spp", "4", "--threads", "1", "--quiet", "--checkpoint-every", "1ms"])
            .arg("--out")
            .arg(&out)
            .status()
            .unwrap();
        assert!(st.success(), "the tiny render failed");
        let mut exr = vec![("r.exr".to_string(), std::fs::read(out.with_extension("exr")).unwrap())];
        for p in ["tests/data/texture/rgb.exr", "tests/data/texture/grey.exr", "tests/data/fuzz-images/half-zip.exr"] {
            exr.push((p.rsplit('/').next().unwrap().into(), std::fs::read(root().join(p)).unwrap()));
        }
        let ckpt = vec![("r.ckpt".to_string(), std::fs::read(out.with_extension("ckpt")).unwrap())];
        (exr, ckpt)
    })
    .clone()
}

fn exr_inputs(seed: u64, cases: usize) -> impl Iterator<Item = (String, Input)> {
    let corpus = rendered_outputs().0;
    (0..cases).map(move |case| {
        let mut rng = Rng::keyed(seed, stream::MISC, case as u64, 6);
        let (name, src) = &corpus[case % corpus.len()];
        (name.clone(), Input::Exr(mutate_image(src, &mut rng)))
    })
}

/// Checkpoint mutations: payload bits flipped or bytes set to extremes (0, 0xff: huge lengths
/// and counts) with the header's checksum recomputed, so the decoder reads them (what
/// `ckpt_tool.py` of the robustness pass forges); header fields (version, payload length, the
/// checksum) set to extremes; the file cut short or grown.
fn mutate_ckpt(src: &[u8], rng: &mut Rng) -> Vec<u8> {
    use forecast::checkpoint::{checksum, HEADER_LEN};
    let mut b = src.to_vec();
    let mut reseal = true;
    for _ in 0..1 + pick(rng, 3) {
        let n = b.len();
        match pick(rng, 6) {
            0 | 1 => {
                for _ in 0..1 + pick(rng, 8) {
                    let i = HEADER_LEN + pick(rng, n.saturating_sub(HEADER_LEN));
                    if i < n {
                        b[i] ^= 1 << pick(rng, 8);
                    }
                }
            }
            2 => {
                let (i, k) = (HEADER_LEN + pick(rng, n.saturating_sub(HEADER_LEN)), 1 + pick(rng, 9));
                let v = [0u8, 0xff, 0x7f, 0x80][pick(rng, 4)];
                b[i.min(n)..(i + k).min(n)].fill(v);
            }
            3 => {
                reseal = false;
                let at = [8usize, 16, 24][pick(rng, 3)];
                let v = [0u64, 1, u32::MAX as u64, u64::MAX, (n - HEADER_LEN) as u64 + 1][pick(rng, 5)];
                if at + 8 <= n {
                    b[at..at + 8].copy_from_slice(&v.to_le_bytes());
                }
            }
            4 => {
                let k = pick(rng, n + 1);
                b.truncate(k);
            }
            _ => {
                let i = HEADER_LEN + pick(rng, n.saturating_sub(HEADER_LEN));
                let k = 1 + pick(rng, 16);
                let chunk: Vec<u8> = b[i.min(n)..(i + k).min(n)].to_vec();
                b.splice(i.min(n)..i.min(n), chunk);
            }
        }
    }
    if reseal && b.len() >= HEADER_LEN {
        let len = (b.len() - HEADER_LEN) as u64;
        b[16..24].copy_from_slice(&len.to_le_bytes());
        let sum = checksum(&b[HEADER_LEN..]);
        b[24..32].copy_from_slice(&sum.to_le_bytes());
    }
    b
}

fn ckpt_inputs(seed: u64, cases: usize) -> impl Iterator<Item = (String, Input)> {
    let corpus = rendered_outputs().1;
    (0..cases).map(move |case| {
        let mut rng = Rng::keyed(seed, stream::MISC, case as u64, 7);
        let (name, src) = &corpus[case % corpus.len()];
        (name.clone(), Input::Ckpt(mutate_ckpt(src, &mut rng)))
    })
}

/// Command lines of every subcommand, with the options docs/cli.md shows.
const CLI_CORPUS: &[&str] = &[
    "render scenes/cornell-box.toml --method pt --spp 4 --resolution 16x16 --seed 3 --threads 1 --out out/x",
    "render scenes/ring.toml --method iws-cf --time 5s --forecast-photons 20000 --clusters 32 --quiet --out r",
    "render scenes/ring.toml --method pt-cf --spp 8 --light-paths 1000 --split 4 --emission-split 4",
    "render scenes/cornell-box.toml --method auto --time 1m --checkpoint-every 30s --checkpoint-path c.ckpt",
    "render scenes/cornell-box.toml --resume c.ckpt --spp 16 --snapshots 4,8 --max-depth 8 --sampler sobol",
    "render scene.xml -D spp=4 -D res=16 --method iws-pm --photons 1000 --gather 16 --max-radius 0.1",
    "render scenes/cornell-box.toml --method iws --vpl-paths 64 --ris-candidates 4 --accel obvhs",
    "render scenes/cornell-box.toml --method pt --max-depth 8 --path-filter DSL,DD* --sampler independent",
    "diff a.exr b.exr --half0 h0.exr --half1 h1.exr",
    "compare scenes/cornell-box.toml --reference ref.exr --out cmp",
    "forecast-map scenes/ring.toml --out fm --forecast-photons 1000 --compare-paths 100 --quiet",
    "reference scenes/cornell-box.toml --spp 64 --out ref",
    "bench --help",
];

const CLI_TOKENS: &[&str] = &[
    "",
    "-",
    "--",
    "-D",
    "=",
    "x=",
    "=1",
    "0",
    "-1",
    "1e400",
    "nan",
    "inf",
    "-inf",
    "18446744073709551616",
    "4294967296",
    "0x0",
    "16x0",
    "0x16",
    "65536x65536",
    "1x99999999999",
    "16x16x16",
    "x",
    "0s",
    "1ms",
    "1e30s",
    "-5s",
    "1h",
    "99999999999999h",
    "nans",
    "∞",
    "\u{0}",
    "a,b,,c",
    ",",
    "4,",
    "--spp",
    "--time",
    "--resolution",
    "--method",
    "--out",
    "--threads",
    "--light-paths",
    "--forecast-photons",
    "--resume",
    "--snapshots",
    "--help",
    "--version",
    "render",
    "diff",
    "compare",
    "forecast-map",
    "--compare-paths",
    "--checkpoint-every",
    "--seed",
];

/// Token mutations: a token replaced by an extreme or another option, deleted, duplicated or
/// swapped with another.
fn mutate_cli(src: &str, rng: &mut Rng) -> Vec<String> {
    let mut t: Vec<String> = src.split(' ').map(str::to_string).collect();
    for _ in 0..1 + pick(rng, 3) {
        let i = pick(rng, t.len());
        match pick(rng, 5) {
            0 | 1 => t[i] = CLI_TOKENS[pick(rng, CLI_TOKENS.len())].to_string(),
            2 => {
                if t.len() > 1 {
                    t.remove(i);
                }
            }
            3 => {
                let x = t[i].clone();
                t.insert(pick(rng, t.len() + 1), x);
            }
            _ => {
                let j = pick(rng, t.len());
                t.swap(i, j);
            }
        }
    }
    std::iter::once("forecast".to_string()).chain(t).collect()
}

fn cli_inputs(seed: u64, cases: usize) -> impl Iterator<Item = (String, Input)> {
    (0..cases).map(move |case| {
        let mut rng = Rng::keyed(seed, stream::MISC, case as u64, 8);
        let src = CLI_CORPUS[case % CLI_CORPUS.len()];
        (format!("cli {}", case % CLI_CORPUS.len()), Input::Cli(mutate_cli(src, &mut rng)))
    })
}

#[test]
fn mutated_rendered_exrs_never_panic_or_hang() {
    let dir = fuzz_dir("scene-fuzz-exr");
    for (name, b) in rendered_outputs().0 {
        assert_eq!(run_input(&Input::Exr(b), &dir), Ok(true), "{name} does not read unmutated");
    }
    let loaded = fuzz("EXR", &dir, exr_inputs(0x5eed, CASES_EXR));
    assert!(loaded > CASES_EXR / 50 && loaded < CASES_EXR, "{loaded} of {CASES_EXR} mutants read");
}

#[test]
fn mutated_checkpoints_never_panic_or_hang() {
    let dir = fuzz_dir("scene-fuzz-ckpt");
    for (name, b) in rendered_outputs().1 {
        assert_eq!(run_input(&Input::Ckpt(b), &dir), Ok(true), "{name} does not read unmutated");
    }
    let loaded = fuzz("checkpoint", &dir, ckpt_inputs(0x5eed, CASES_CKPT));
    assert!(loaded < CASES_CKPT, "{loaded} of {CASES_CKPT} mutants read");
}

#[test]
fn mutated_command_lines_never_panic_or_hang() {
    let dir = fuzz_dir("scene-fuzz-cli");
    for (i, src) in CLI_CORPUS.iter().enumerate() {
        let args: Vec<String> = std::iter::once("forecast").chain(src.split(' ')).map(str::to_string).collect();
        // `bench --help` ends in clap's help "error"
        assert_eq!(run_input(&Input::Cli(args), &dir), Ok(i + 1 != CLI_CORPUS.len()), "{src} does not parse");
    }
    let loaded = fuzz("CLI", &dir, cli_inputs(0x5eed, CASES_CLI));
    assert!(loaded > CASES_CLI / 20 && loaded < CASES_CLI, "{loaded} of {CASES_CLI} mutants parsed");
}

/// The hang the EXR corpus found (case 1339): a rendered-image EXR whose data window's `yMax` is
/// 0xd0000005 kept `read_exr` decoding for minutes; its header is now refused at once, naming
/// the file (the texture decoder's header bounds, `image_io::decode::check_exr_header`).
#[test]
fn an_exr_with_a_huge_data_window_is_refused_from_its_header() {
    let dir = tmp_dir("scene-fuzz-exr-window");
    let mut b = std::fs::read(root().join("tests/data/fuzz-images/half-zip.exr")).unwrap();
    let attr = b"dataWindow\0box2i\0";
    let at = b.windows(attr.len()).position(|w| w == attr).unwrap() + attr.len() + 4 + 12;
    b[at..at + 4].copy_from_slice(&0xd000_0005u32.to_le_bytes());
    let file = dir.join("window.exr");
    std::fs::write(&file, &b).unwrap();
    let t = Instant::now();
    let e = forecast::image_io::read_exr(&file).expect_err("a window of 2^31 rows must be refused");
    assert!(t.elapsed().as_secs_f64() < 1.0, "took {:.1} s", t.elapsed().as_secs_f64());
    assert!(e.to_string().contains("window.exr"), "{e}");
}
