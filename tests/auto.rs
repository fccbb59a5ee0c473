//! `--method auto` (`integrators::auto`): its choice on each committed scene, its precedence
//! against `--method` and the scene's `[render] method`, and the reason in the terminal and in
//! the JSON report. The rule and its evidence: `docs/auto.md`; whether the choices hold at equal
//! time (within 1.1× of the best method's whole-image RMSE at 1 min) is `scripts/auto-check.sh`.

mod common;

use clap::Parser;
use common::{root, tmp_dir};
use forecast::cli::{Cli, Command};
use forecast::integrators::auto::{choose, evidence, resolve, resolve_evidence, REASON_MAX_CHARS};
use forecast::integrators::{Method, MethodChoice};
use forecast::scene::Scene;

fn load(rel: &str) -> Scene {
    forecast::scene::load(&root().join(rel)).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

/// The documented choice per scene (`docs/auto.md`, "The choice per committed scene").
#[test]
fn auto_picks_the_documented_method_for_each_scene() {
    for (scene, want, why) in [
        ("scenes/cornell-box.toml", Method::PtCf, "area lights"),
        ("scenes/ring.toml", Method::PtCf, "area lights"),
        ("scenes/figurines.toml", Method::PtCf, "area lights"),
        ("scenes/stability/no-dirac.toml", Method::Pt, "no mirror or glass"),
        ("scenes/stability/point-glass.toml", Method::PtCf, "point lights only"),
        ("tests/scenes/cornell-nodirac.toml", Method::Pt, "no mirror or glass"),
    ] {
        let (m, reason) = choose(&load(scene));
        assert_eq!(m, want, "{scene}: {reason}");
        assert!(reason.contains(why) && reason.contains(m.name()), "{scene}: {reason}");
        // the reason is one short line; what it rests on is the evidence, which starts with it
        assert!(reason.chars().count() <= REASON_MAX_CHARS && !reason.contains('\n'), "{scene}: {reason}");
        assert!(evidence(&load(scene)).contains(why), "{scene}");
    }
}

/// The evidence holds the figures and notes the one-line reason leaves out (issue #63: they were
/// about 330 characters on every run): `cornell-box`'s equal-time RMSE ratios and docs/auto.md,
/// `figurines`' glossy-receiver note, a scene with area and point lights its L S+ D note.
#[test]
fn the_figures_are_in_the_evidence_not_the_reason() {
    let cornell = load("scenes/cornell-box.toml");
    let (_, reason) = choose(&cornell);
    let ev = evidence(&cornell);
    for figure in ["0.49x", "0.64x", "docs/auto.md"] {
        assert!(ev.contains(figure) && !reason.contains(figure), "{figure}: reason {reason}; evidence {ev}");
    }
    let figurines = load("scenes/figurines.toml");
    let ev = evidence(&figurines);
    assert!(ev.contains("glossy") && !choose(&figurines).1.contains("glossy"), "{ev}");
    // every committed scene with Dirac objects: a line short enough for a terminal
    for s in ["scenes/ring.toml", "scenes/stability/point-glass.toml", "scenes/external/sms-ring/ring.xml"] {
        let (_, reason) = choose(&load(s));
        assert!(reason.chars().count() <= REASON_MAX_CHARS, "{s}: {reason}");
    }
}

/// Caustics lit by point lights are rendered by `pt-cf`'s light paths only: the reason says so.
#[test]
fn the_reason_names_what_only_pt_cf_renders() {
    let (_, reason) = choose(&load("scenes/stability/point-glass.toml"));
    assert!(reason.contains("L S+ D") && reason.contains("pt-cf"), "{reason}");
    let (_, reason) = choose(&load("scenes/cornell-box.toml"));
    assert!(!reason.contains("L S+ D"), "cornell-box has no point lights: {reason}");
}

/// `--method` first, then the scene's `[render] method`, else `auto`.
#[test]
fn the_command_line_then_the_scene_then_auto() {
    let glass = load("scenes/stability/point-glass.toml"); // names `pt`
    let (m, why) = resolve(Some(Method::IwsPm.into()), &glass).unwrap();
    assert_eq!(m, Method::IwsPm);
    assert!(why.contains("--method"), "{why}");
    let (m, why) = resolve(None, &glass).unwrap();
    assert_eq!(m, Method::Pt);
    assert!(why.contains("scene"), "{why}");
    let cornell = load("scenes/cornell-box.toml"); // names none
    assert_eq!(cornell.render.method, "auto");
    let (m, why) = resolve(None, &cornell).unwrap();
    assert_eq!(m, Method::PtCf);
    assert!(why.starts_with("auto"), "{why}");
    let (m, why) = resolve(Some(MethodChoice::Auto), &glass).unwrap();
    assert_eq!(m, choose(&glass).0);
    assert!(why.starts_with("auto (--method auto)"), "{why}");
    // the evidence comes with `auto` only, from the command line or the scene
    assert_eq!(resolve_evidence(Some(MethodChoice::Auto), &glass), Some(evidence(&glass)));
    assert_eq!(resolve_evidence(None, &glass), None);
    assert_eq!(resolve_evidence(Some(Method::Pt.into()), &cornell), None);
    assert_eq!(resolve_evidence(None, &cornell), Some(evidence(&cornell)));
}

/// `--method` takes `auto` and every method's name, and nothing else.
#[test]
fn method_flag_takes_auto() {
    let parse = |m: &str| Cli::try_parse_from(["forecast", "render", "s.toml", "--method", m]).map(|c| c.command);
    let Ok(Command::Render(a)) = parse("auto") else { panic!("--method auto does not parse") };
    assert_eq!(a.method, Some(MethodChoice::Auto));
    for &m in Method::ALL {
        let Ok(Command::Render(a)) = parse(m.name()) else { panic!("--method {} does not parse", m.name()) };
        assert_eq!(a.method, Some(MethodChoice::Named(m)));
    }
    assert!(parse("bdpt").is_err());
    let Ok(Command::Render(a)) = Cli::try_parse_from(["forecast", "render", "s.toml"]).map(|c| c.command) else {
        panic!("render parses")
    };
    assert_eq!(a.method, None);
}

/// A scene may name `auto`; an unknown name is refused with the list, `auto` first.
#[test]
fn scenes_may_name_auto() {
    let d = tmp_dir("auto-scene");
    let src = std::fs::read_to_string(root().join("scenes/stability/no-dirac.toml")).unwrap();
    assert!(src.contains("method    = \"pt\""), "no-dirac.toml changed: update the test");
    let write = |name: &str, m: &str| {
        let p = d.join(name);
        std::fs::write(&p, src.replace("method    = \"pt\"", &format!("method = \"{m}\""))).unwrap();
        p
    };
    let s = forecast::scene::load(&write("auto.toml", "auto")).unwrap();
    assert_eq!(s.render.method, "auto");
    let err = forecast::scene::load(&write("bad.toml", "bdpt")).unwrap_err().to_string();
    assert!(err.contains("render.method") && err.contains("(auto, pt,"), "{err}");
    let _ = std::fs::remove_dir_all(d);
}

/// The terminal and the JSON report say what was chosen and why.
#[test]
fn terminal_and_json_give_the_method_and_its_reason() {
    let d = tmp_dir("auto-json");
    let prefix = d.join("r");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_forecast"))
        .current_dir(root())
        .args(["render", "scenes/stability/no-dirac.toml", "--method", "auto", "--spp", "1"])
        .args(["--resolution", "8x8", "--threads", "1", "--out"])
        .arg(&prefix)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{err}");
    assert!(err.contains("method: pt (auto (--method auto): no mirror or glass objects"), "{err}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(prefix.with_extension("json")).unwrap()).unwrap();
    assert_eq!(json["method"], "pt");
    let reason = json["method_reason"].as_str().expect("method_reason is a string");
    assert!(reason.starts_with("auto (--method auto): no mirror or glass objects"), "{reason}");
    // one line on the terminal; the evidence in the JSON only
    let line = err.lines().find(|l| l.starts_with("method: ")).expect("a method line");
    assert!(line.chars().count() <= "method: pt-cf (auto (--method auto): )".len() + REASON_MAX_CHARS, "{line}");
    let ev = json["method_evidence"].as_str().expect("method_evidence is a string under auto");
    assert!(ev.contains("docs/auto.md") && !err.contains(ev), "{ev}");
    let _ = std::fs::remove_dir_all(d);
}
