//! A scene's `[render]` table records how the scene is rendered: besides `method`, `spp`, `time`,
//! `seed` and `max_depth`, the render settings and method options by their long flag names
//! (`clusters = 8`, `guide-fraction` or `guide_fraction`), parsed as their flags are
//! (`pipeline::scene_options`). The command line's flags win; `--method` naming another method
//! leaves out the scene's options that it does not take. The rejections (an unknown key, another
//! method's option, a bad value) are in tests/bad_scenes.rs; the format in docs/scene-formats.md.

mod common;

use clap::Parser;
use common::cli::run;
use common::{root, tmp_dir};
use forecast::cli::{Cli, Command};
use forecast::integrators::{Method, MethodChoice};
use forecast::pipeline::{Plan, RenderJob};
use forecast::scene::{load_str, Scene};
use std::path::{Path, PathBuf};

/// The options these tests record (pt-cf's, the CF group's and render settings).
const OPTIONS: &str =
    "clusters = 8\nguide-fraction = 0.5\nforecast_photons = 3000\nlight_paths = 0\nemission_split = 4\n";

/// `scenes/cornell-box.toml` (its method `auto`, which picks pt-cf) with `render` lines added to
/// its `[render]` table.
fn cornell_with(render: &str) -> String {
    let src = std::fs::read_to_string(root().join("scenes/cornell-box.toml")).unwrap();
    assert!(src.contains("[render]\n"), "cornell-box.toml changed: update the test");
    src.replacen("[render]\n", &format!("[render]\n{render}"), 1)
}

fn scene(src: &str) -> Scene {
    load_str(src, "opts.toml", Path::new(".")).unwrap_or_else(|e| panic!("{e}"))
}

/// The job `forecast render opts.toml ARGS` describes, as the binary parses it.
fn job(args: &[&str]) -> RenderJob {
    let argv = ["forecast", "render", "opts.toml"].into_iter().chain(args.iter().copied());
    let cli = Cli::try_parse_from(argv).unwrap_or_else(|e| panic!("{e}"));
    let Command::Render(mut a) = cli.command else { panic!("render") };
    // the ids `Cli::parse_checked` records as given (try_parse_from does not)
    a.method_args.given = args.iter().filter_map(|f| f.strip_prefix("--")).map(|f| f.replace('-', "_")).collect();
    a.job()
}

fn resolve(src: &str, args: &[&str]) -> Plan {
    job(args).resolve(&scene(src)).unwrap_or_else(|e| panic!("{e}"))
}

/// The options a report records for the plan's method (JSON).
fn options(p: &Plan) -> serde_json::Value {
    serde_json::to_value(p.args.options_for(p.method)).unwrap()
}

#[test]
fn the_scenes_options_are_applied() {
    let p = resolve(&cornell_with(OPTIONS), &[]);
    assert_eq!(p.method, Method::PtCf);
    assert_eq!((p.args.cf.clusters, p.args.cf.forecast_photons), (8, Some(3000)));
    assert_eq!((p.args.ptcf.guide_fraction, p.args.ptcf.light_paths), (0.5, Some(0)));
    assert_eq!(p.args.settings.emission_split, 4);
    assert_eq!(p.args.cf.max_rank, 6, "an option the scene does not give keeps its default");
}

/// A scene's options and the same flags on the command line make the same plan: one parser.
#[test]
fn a_scene_option_is_its_flag() {
    let flags = [
        "--clusters",
        "8",
        "--guide-fraction",
        "0.5",
        "--forecast-photons",
        "3000",
        "--light-paths",
        "0",
        "--emission-split",
        "4",
    ];
    let by_flags = resolve(&cornell_with(""), &flags);
    let by_scene = resolve(&cornell_with(OPTIONS), &[]);
    assert_eq!(options(&by_scene), options(&by_flags));
}

/// The command line wins over the scene, option by option.
#[test]
fn the_command_line_wins() {
    let p = resolve(&cornell_with(OPTIONS), &["--clusters", "16", "--emission-split", "1"]);
    assert_eq!((p.args.cf.clusters, p.args.settings.emission_split), (16, 1));
    assert_eq!(p.args.ptcf.guide_fraction, 0.5, "the options the command line does not give are the scene's");
    // the command line's value wins even where it is the default
    let p = resolve(&cornell_with(OPTIONS), &["--clusters", "64"]);
    assert_eq!(p.args.cf.clusters, 64);
}

/// `--method` naming another method than the scene's leaves out the scene's options it does not
/// take (a scene that records its pt-cf options still renders a pt reference); the render
/// settings still apply.
#[test]
fn another_method_leaves_the_scenes_method_options_out() {
    let p = resolve(&cornell_with(OPTIONS), &["--method", "pt"]);
    assert_eq!(p.method, Method::Pt);
    assert_eq!(p.args.settings.emission_split, 4);
    let report = options(&p);
    assert!(report.get("clusters").is_none() && report.get("guide_fraction").is_none(), "{report}");
    let j = RenderJob { method: Some(MethodChoice::Named(Method::IwsCf)), ..job(&[]) };
    let p = j.resolve(&scene(&cornell_with(OPTIONS))).unwrap();
    assert_eq!(p.args.cf.clusters, 8, "iws-cf takes the CF group");
    assert_eq!(p.args.ptcf.guide_fraction, 0.3, "but not pt-cf's own");
}

fn write(dir: &Path, name: &str, src: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, src).unwrap();
    p
}

fn render(scene: &Path, out: &Path, flags: &[&str]) -> serde_json::Value {
    let (s, o) = (scene.display().to_string(), out.display().to_string());
    let mut args = vec!["render", &s, "--spp", "2", "--resolution", "16x16", "--threads", "1", "--quiet", "--out", &o];
    args.extend_from_slice(flags);
    let (code, _, err) = run(&args);
    assert_eq!(code, 0, "{args:?}: {err}");
    serde_json::from_str(&std::fs::read_to_string(out.with_extension("json")).unwrap()).unwrap()
}

/// End to end: a scene that records its options renders the image of the flags, bit for bit,
/// and its report records them; a flag overrides the scene's value.
#[test]
fn the_binary_renders_the_scenes_options() {
    let d = tmp_dir("scene-options");
    let with = write(&d, "with.toml", &cornell_with(OPTIONS));
    let without = write(&d, "without.toml", &cornell_with(""));
    let flags = ["--clusters", "8", "--guide-fraction", "0.5", "--forecast-photons", "3000", "--light-paths", "0"];
    let a = render(&with, &d.join("a"), &[]);
    let b = render(&without, &d.join("b"), &[&flags[..], &["--emission-split", "4"]].concat());
    assert_eq!(a["options"], b["options"]);
    assert_eq!(a["options"]["clusters"], 8);
    let (ia, ib) = (
        forecast::image_io::read_exr(&d.join("a.exr")).unwrap(),
        forecast::image_io::read_exr(&d.join("b.exr")).unwrap(),
    );
    assert!(ia.pixels == ib.pixels, "the scene's options render another image than their flags");
    let c = render(&with, &d.join("c"), &["--clusters", "16"]);
    assert_eq!((c["options"]["clusters"].as_u64(), c["options"]["guide_fraction"].as_f64()), (Some(16), Some(0.5)));
    let _ = std::fs::remove_dir_all(d);
}
