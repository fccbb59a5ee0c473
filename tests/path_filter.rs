//! `pt --path-filter` (a biased diagnostic, `integrators::pt::path_class`): which light paths carry
//! an image's light and noise.
//!
//! - A filtered `pt` draws the random numbers of the unfiltered one, so filters that partition the
//!   classes (`L`, `S*`, `D*`: every class starts with exactly one of them) give images whose
//!   per-pixel radiance sums add up to the unfiltered image's up to the f32 rounding of a
//!   sample's terms (relative 1e-5; a filter that moved a sample's random numbers would differ
//!   by the Monte Carlo noise, ~1e-2 at 8 spp).
//! - The classes mean what they say: without mirrors or glass (`cornell-nodirac`) every class
//!   with an `S` is empty and `DDL` is not; `cornell-box` has `DS*` light.
//! - A filter turns emission splitting off (its extra camera rays add `L`/`SL` light no filter
//!   sees): the filtered renders here keep the default `--emission-split 64`, the unfiltered one
//!   has 1, and `*` (every class kept) is the unfiltered image bit for bit.
//! - `pt-cf`'s filtered parts sum to its image the same way (its splits and table lookups see the
//!   same random numbers).
//! - The IWS methods refuse the option; bad patterns are clear errors; a filtered render warns
//!   (stderr and the JSON's `warnings`) that its image is not the scene's radiance; `compare`
//!   and `reference` refuse it, and a checkpoint records it (no resume across filters).

mod common;
use common::{job, render_film, root, tmp_dir};
use forecast::integrators::Method;
use forecast::render::film::{Film, STRIDE};

fn film(method: Method, filter: Option<&str>, name: &str) -> Film {
    film_of("scenes/cornell-box.toml", method, filter, name)
}

fn film_of(scene: &str, method: Method, filter: Option<&str>, name: &str) -> Film {
    let dir = tmp_dir(name);
    let mut j = job(&root().join(scene), method, 8, 3, (32, 32), 2, &dir.join("img"));
    j.args.pt.path_filter = filter.map(str::to_string);
    if filter.is_none() {
        // what a filter implies (the split's extra rays are unfiltered): the filtered renders
        // keep the default split of 64, which `MethodArgs::emission_split` must turn off
        j.args.settings.emission_split = 1;
        // and a filter turns `pt-cf`'s light paths off (they are not class-filtered)
        j.args.ptcf.light_paths = Some(0);
    }
    j.args.cf.forecast_photons = Some(20_000);
    render_film(&j)
}

fn assert_parts_sum_to_the_image(method: Method) {
    let name = method.name();
    let full = film(method, None, &format!("pf-{name}-full"));
    let parts = ["L", "S*", "D*"].map(|f| film(method, Some(f), &format!("pf-{name}-{}", f.replace('*', "x"))));
    // the pixels' radiance sums Σr, Σg, Σb (`Film` layout: 7 f64 per pixel, sums first)
    let (mut worst, mut nonzero) = (0.0f64, [0usize; 3]);
    for (i, &v) in full.data.iter().enumerate().filter(|(i, _)| i % STRIDE < 3) {
        let sum: f64 = parts.iter().map(|p| p.data[i]).sum();
        worst = worst.max((sum - v).abs() / v.abs().max(1e-3));
        for (k, p) in parts.iter().enumerate() {
            nonzero[k] += usize::from(p.data[i] != 0.0);
        }
    }
    assert!(worst < 1e-5, "{name}: parts differ from the image by {worst} (relative)");
    assert!(nonzero.iter().all(|&n| n > 0), "{name}: a part is empty: {nonzero:?}");
    assert!(film(method, Some("*"), &format!("pf-{name}-star")).data == full.data, "{name}: `*` must keep everything");
}

#[test]
fn filters_that_partition_the_classes_sum_to_the_image() {
    assert_parts_sum_to_the_image(Method::Pt);
}

#[test]
fn pt_cf_filters_partition_its_image_too() {
    assert_parts_sum_to_the_image(Method::PtCf);
}

#[test]
fn dirac_classes_are_empty_without_dirac_objects() {
    let render = |scene: &str, filter: &str| {
        let dir = tmp_dir(&format!("pf-{}-{}", scene.len(), filter.replace('*', "x").replace(',', "_")));
        let mut j = job(&root().join(scene), Method::Pt, 8, 3, (32, 32), 2, &dir.join("img"));
        j.args.pt.path_filter = Some(filter.to_string());
        render_film(&j).mean().iter().flatten().filter(|&&v| v != 0.0).count()
    };
    assert_eq!(
        render("tests/scenes/cornell-nodirac.toml", "S*,DS*,DDS*,DDDS*"),
        0,
        "Dirac classes in a scene without Dirac objects"
    );
    assert!(render("tests/scenes/cornell-nodirac.toml", "DDL") > 0);
    // … and every class there is `L` or `D…DL`, so `L,D*` keeps all of it, bit for bit
    let nodirac = "tests/scenes/cornell-nodirac.toml";
    let (a, b) =
        (film_of(nodirac, Method::Pt, None, "pf-nd-all"), film_of(nodirac, Method::Pt, Some("L,D*"), "pf-nd-ld"));
    assert!(a.data == b.data, "a class with an S in a scene without Dirac objects");
    assert!(render("scenes/cornell-box.toml", "DS*") > 0, "no paths through the mirror or glass ball");
}

#[test]
fn other_methods_and_bad_patterns_are_refused() {
    let run = |args: &[&str]| {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_forecast"))
            .current_dir(root())
            .args(["render", "scenes/cornell-box.toml", "--spp", "1", "--resolution", "8x8", "--quiet", "--out"])
            .arg(tmp_dir("pf-cli").join("x"))
            .args(args)
            .output()
            .unwrap();
        (out.status.code(), String::from_utf8_lossy(&out.stderr).to_string())
    };
    let (code, err) = run(&["--method", "iws-cf", "--path-filter", "DSL"]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("--path-filter belongs to pt/pt-cf, not iws-cf"), "{err}");
    let (code, err) = run(&["--method", "pt", "--path-filter", "DXL"]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("`X` is not D, S or L"), "{err}");
    let (code, err) = run(&["--method", "pt", "--path-filter", "DSL,DD*"]);
    assert_eq!(code, Some(0), "{err}");
    assert!(err.contains("warning: --path-filter DSL,DD*: only these path classes"), "{err}");
    for m in ["iws", "iws-pm"] {
        let (code, err) = run(&["--method", m, "--path-filter", "DSL"]);
        assert!(code == Some(2) && err.contains(&format!("--path-filter belongs to pt/pt-cf, not {m}")), "{m}: {err}");
    }
}

/// `compare` and `reference` refuse a filter before any work; a checkpoint of an unfiltered
/// render cannot be resumed filtered (the passes would be summed into one image).
#[test]
fn filtered_images_never_mix_with_unbiased_ones() {
    let d = tmp_dir("pf-mix");
    let cmd = |args: &[&str]| {
        let out =
            std::process::Command::new(env!("CARGO_BIN_EXE_forecast")).current_dir(root()).args(args).output().unwrap();
        (out.status.code(), String::from_utf8_lossy(&out.stderr).to_string())
    };
    let out = |n: &str| d.join(n).to_str().unwrap().to_string();
    let (code, err) = cmd(&[
        "compare",
        "scenes/cornell-box.toml",
        "--methods",
        "pt",
        "--budgets",
        "1s",
        "--path-filter",
        "DSL",
        "--reference",
        "missing.exr",
        "--out",
        &out("cmp"),
    ]);
    assert!(code == Some(1) && err.contains("compare: --path-filter"), "{err}");
    let (code, err) =
        cmd(&["reference", "scenes/cornell-box.toml", "--time", "1s", "--path-filter", "DSL", "--out", &out("ref")]);
    assert!(code == Some(1) && err.contains("reference: --path-filter"), "{err}");
    let base = ["render", "scenes/cornell-box.toml", "--method", "pt", "--resolution", "8x8", "--seed", "1", "--quiet"];
    let (code, err) = cmd(&[&base[..], &["--spp", "4", "--checkpoint-every", "1ms", "--out", &out("a")]].concat());
    assert_eq!(code, Some(0), "{err}");
    let ckpt = out("a") + ".ckpt";
    let (code, err) =
        cmd(&[&base[..], &["--spp", "8", "--path-filter", "DSL", "--resume", &ckpt, "--out", &out("b")]].concat());
    assert!(code == Some(1) && err.contains("cannot resume") && err.contains("--path-filter DSL"), "{err}");
}
