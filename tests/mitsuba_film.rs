//! The film's crop window and parameters (issue #62): a Mitsuba film's `crop_offset_x/y`,
//! `crop_width/height` render that window of the full film as Mitsuba does (the projection the
//! full film's, the image the window).
//!
//! - `tests/scenes/film/crop.xml` (a 16 × 12 window at (19, 13) of a 40 × 30 film, fov along x)
//!   rendered by `pt` agrees pixel by pixel with Mitsuba 3 `path`'s render of the same window
//!   (`tests/reference/film-crop.json`, by `scripts/mitsuba-crop-reference.py`: 32 renders ×
//!   1024 spp, per-pixel SE from their spread): per-pixel Welch z at family-wise α = 1e-3 (Šidák
//!   over the pixel-channels), `pt`'s variance of the mean the larger of its own and Mitsuba's
//!   per-sample variance over `pt`'s samples (`tests/mitsuba_plugins.rs` says why), and the
//!   window's mean per channel. Power: the window one pixel to the left fails the per-pixel test.
//! - The window is the full film's pixels: the full 40 × 30 render's window agrees with the
//!   cropped render (per-pixel z, both `pt`, other seeds).
//! - A window outside the film, empty or negative: an error naming the file, line and key; the
//!   output-format parameters warn unless they say what the output is.

mod common;
use common::{job, render_film, root, tmp_dir};
use forecast::integrators::Method;
use forecast::render::film::Film;
use forecast::stats::z_test_threshold;

const ALPHA: f64 = 1e-3;
const SPP: u64 = 1024;
/// Mitsuba's samples per pixel in the reference (32 renders × 1024).
const REF_SPP: f64 = 32768.0;

fn scene() -> std::path::PathBuf {
    root().join("tests/scenes/film/crop.xml")
}

/// `pt` on the crop scene with `-D` values `defs`, at its own resolution.
fn render(tag: &str, defs: &[(&str, &str)], seed: u64) -> Film {
    let defines: Vec<(String, String)> = defs.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect();
    let opts = forecast::scene::LoadOptions { defines: defines.clone() };
    let s = forecast::scene::load_with(&scene(), &opts).unwrap();
    let out = tmp_dir(&format!("film-{tag}")).join("img");
    let mut j = job(&scene(), Method::Pt, SPP, seed, (s.camera.width, s.camera.height), 1, &out);
    j.defines = defines;
    render_film(&j)
}

/// Mitsuba's window: per pixel RGB means and standard errors, and its size.
fn reference() -> (Vec<[f64; 3]>, Vec<[f64; 3]>, [usize; 2]) {
    let text = std::fs::read_to_string(root().join("tests/reference/film-crop.json")).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    let list = |k: &str| -> Vec<[f64; 3]> {
        let a: Vec<f64> = v[k].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
        a.chunks(3).map(|c| [c[0], c[1], c[2]]).collect()
    };
    let size = [v["size"][0].as_u64().unwrap() as usize, v["size"][1].as_u64().unwrap() as usize];
    (list("mean"), list("se"), size)
}

/// Largest per-pixel |z| of `pt` (pixels `idx` of `f`) against means `m` with variances `v`
/// (`scale`: `pt`'s variance at least `scale · v` per sample, 0 for none).
fn max_z(f: &Film, idx: &[usize], m: &[[f64; 3]], v: &[[f64; 3]], scale: f64) -> f64 {
    let (fm, fv) = (f.mean(), f.variance_of_mean());
    let mut worst = 0.0f64;
    for (k, &i) in idx.iter().enumerate() {
        for c in 0..3 {
            let own = (fv[i][c] as f64).max(scale * v[k][c] / f.count(i).max(1.0));
            let var = own + v[k][c] + (1e-5 * m[k][c].abs()).powi(2);
            let d = fm[i][c] as f64 - m[k][c];
            worst = worst.max(if d == 0.0 { 0.0 } else { d.abs() / var.sqrt() });
        }
    }
    worst
}

#[test]
fn crop_window_agrees_with_mitsuba() {
    let s = forecast::scene::load(&scene()).unwrap();
    assert_eq!((s.camera.width, s.camera.height, s.camera.film, s.camera.offset), (16, 12, [40.0, 30.0], [19.0, 13.0]));
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    let (rm, rse, size) = reference();
    assert_eq!(size, [16, 12]);
    let rv: Vec<[f64; 3]> = rse.iter().map(|s| s.map(|x| x * x)).collect();
    let per_sample = REF_SPP; // v · REF_SPP = Mitsuba's per-sample variance
    let thr = z_test_threshold(ALPHA, 3 * rm.len());
    let idx: Vec<usize> = (0..rm.len()).collect();
    let f = render("crop", &[], 3);
    let z = max_z(&f, &idx, &rm, &rv, per_sample);
    // the window's mean per channel
    let (fm, fv) = (f.mean(), f.variance_of_mean());
    let n = rm.len() as f64;
    let zc: [f64; 3] = std::array::from_fn(|c| {
        let d: f64 = (0..rm.len()).map(|i| fm[i][c] as f64 - rm[i][c]).sum::<f64>() / n;
        let v: f64 = (0..rm.len()).map(|i| fv[i][c] as f64 + rv[i][c]).sum::<f64>() / (n * n);
        d / v.sqrt()
    });
    let thr3 = z_test_threshold(ALPHA, 3);
    eprintln!("crop vs Mitsuba: max|z| {z:.2} (threshold {thr:.2}); window mean z {zc:+.2?} (threshold {thr3:.2})");
    assert!(z < thr, "the cropped render disagrees with Mitsuba's window: max|z| {z:.2} >= {thr:.2}");
    assert!(zc.iter().all(|z| z.abs() < thr3), "{zc:?}");
    // power: the window one pixel to the left is another image
    let shifted = render("crop-shifted", &[("crop_offset_x", "18")], 4);
    let zs = max_z(&shifted, &idx, &rm, &rv, per_sample);
    eprintln!("window at (18, 13) vs Mitsuba's (19, 13): max|z| {zs:.2}");
    assert!(zs > thr, "a one-pixel shift of the window passes: {zs:.2}");
}

#[test]
fn crop_window_is_the_full_films_window() {
    let crop = render("crop-own", &[], 5);
    let full = render(
        "full",
        &[("crop_offset_x", "0"), ("crop_offset_y", "0"), ("crop_width", "40"), ("crop_height", "30")],
        6,
    );
    assert_eq!((full.width, full.height), (40, 30));
    let (m, v) = (full.mean(), full.variance_of_mean());
    let win: Vec<usize> = (0..12).flat_map(|y| (0..16).map(move |x| (y + 13) * 40 + x + 19)).collect();
    let (wm, wv): (Vec<[f64; 3]>, Vec<[f64; 3]>) =
        win.iter().map(|&i| (m[i].map(|x| x as f64), v[i].map(|x| x as f64))).unzip();
    let idx: Vec<usize> = (0..win.len()).collect();
    let z = max_z(&crop, &idx, &wm, &wv, 0.0);
    let thr = z_test_threshold(ALPHA, 3 * idx.len());
    eprintln!("crop vs the full film's window: max|z| {z:.2} (threshold {thr:.2})");
    assert!(z < thr, "max|z| {z:.2} >= {thr:.2}");
}

/// The film of a small scene with `params` inside `<film type="hdrfilm">` (lines 3 on).
fn film_scene(params: &str) -> String {
    format!(
        "<scene version=\"3.0.0\">\n<sensor type=\"perspective\"><float name=\"fov\" value=\"40\"/>\n<film type=\"hdrfilm\">\n\
         <integer name=\"width\" value=\"40\"/><integer name=\"height\" value=\"30\"/>\n{params}\n</film></sensor>\n\
         <emitter type=\"point\"><point name=\"position\" x=\"0\" y=\"2\" z=\"0\"/></emitter>\n\
         <shape type=\"sphere\"><point name=\"center\" x=\"0\" y=\"0\" z=\"-3\"/></shape>\n</scene>"
    )
}

#[test]
fn bad_crop_windows_name_file_line_and_key() {
    let cases = [
        (
            "<integer name=\"crop_offset_x\" value=\"30\"/>\n<integer name=\"crop_width\" value=\"11\"/>",
            6,
            "hdrfilm.crop_width",
            "crop_offset_x 30 + crop_width 11 > width 40",
        ),
        (
            "<integer name=\"crop_offset_y\" value=\"1\"/>",
            5,
            "hdrfilm.crop_offset_y",
            "crop_offset_y 1 + crop_height 30 > height 30",
        ),
        ("<integer name=\"crop_height\" value=\"31\"/>", 5, "hdrfilm.crop_height", "crop_height 31 > height 30"),
        ("<integer name=\"crop_width\" value=\"0\"/>", 5, "hdrfilm.crop_width", "the crop window has no pixels"),
        ("<integer name=\"crop_offset_x\" value=\"-1\"/>", 5, "hdrfilm.crop_offset_x", "crop_offset_x -1 must be >= 0"),
    ];
    for (params, line, key, words) in cases {
        let e = common::xml(&film_scene(params), &root()).unwrap_err();
        assert_eq!((e.file.as_str(), e.line, e.key.as_str()), ("t.xml", line, key), "{params}: {e}");
        assert!(e.message.contains(words), "{params}: {e}");
    }
    // the largest window is the film itself: no crop
    let s = common::xml(&film_scene("<integer name=\"crop_width\" value=\"40\"/>"), &root()).unwrap();
    assert!(!s.camera.is_cropped() && s.camera.width == 40);
}

#[test]
fn output_format_parameters_warn_unless_they_are_the_output() {
    let quiet = "<string name=\"pixel_format\" value=\"rgba\"/><string name=\"file_format\" value=\"openexr\"/>\
                 <string name=\"component_format\" value=\"float32\"/><boolean name=\"sample_border\" value=\"false\"/>\
                 <boolean name=\"banner\" value=\"false\"/>";
    let s = common::xml(&film_scene(quiet), &root()).unwrap();
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    let loud = "<string name=\"pixel_format\" value=\"luminance\"/><string name=\"file_format\" value=\"pfm\"/>\
                <string name=\"component_format\" value=\"float16\"/><boolean name=\"sample_border\" value=\"true\"/>";
    let s = common::xml(&film_scene(loud), &root()).unwrap();
    let w = s.warnings.join("\n");
    for k in ["pixel_format `luminance`", "file_format `pfm`", "component_format `float16`", "sample_border"] {
        assert!(w.contains(k), "{k}: {w}");
    }
}

/// `sms-pool`'s form: the film and the sampler at the top level with ids, the sensor's `<ref>`s
/// naming them; a top-level film without an id is refused at its line.
#[test]
fn top_level_film_and_sampler_referenced_by_the_sensor() {
    let src = "<scene version=\"2.0.0\">\n<film type=\"hdrfilm\" id=\"film\"><integer name=\"width\" value=\"40\"/>\
               <integer name=\"height\" value=\"30\"/><integer name=\"crop_offset_x\" value=\"4\"/>\
               <integer name=\"crop_width\" value=\"20\"/></film>\n\
               <sampler type=\"independent\" id=\"sampler\"><integer name=\"sample_count\" value=\"7\"/></sampler>\n\
               <sensor type=\"perspective\"><float name=\"fov\" value=\"40\"/><ref id=\"sampler\"/><ref id=\"film\"/></sensor>\n\
               <emitter type=\"point\"><point name=\"position\" x=\"0\" y=\"2\" z=\"0\"/></emitter>\n\
               <shape type=\"sphere\"><point name=\"center\" x=\"0\" y=\"0\" z=\"-3\"/></shape>\n</scene>";
    let s = common::xml(src, &root()).unwrap();
    assert_eq!((s.camera.width, s.camera.height, s.camera.film, s.camera.offset), (20, 30, [40.0, 30.0], [4.0, 0.0]));
    assert_eq!(s.render.spp, Some(7));
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    let e = common::xml(&src.replace(" id=\"film\">", ">"), &root()).unwrap_err();
    assert_eq!((e.line, e.key.as_str()), (2, "film"), "{e}");
}
