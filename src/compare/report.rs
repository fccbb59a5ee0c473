//! The comparison report: `results.json`, charts, ROI crops and `report.md` / `report.html`.
//!
//! Files under the output directory (all written atomically):
//! * `results.json`: the [`CompareOutcome`] (every run with its measurements);
//! * `charts/relmse-time-REGION.{svg,png}`: relMSE vs wall time, log–log, one line per method
//!   (means over seeds per budget), min–max bands over seeds and a slope −1 guide (the 1/N rate
//!   of an unbiased estimator's MSE); `charts/relmse-spp-REGION.{svg,png}`: relMSE vs spp;
//! * `crops/REGION-reference.png`, `crops/REGION-METHOD.png` (largest budget, first seed,
//!   upscaled by pixel replication) and `strip-REGION.png` (reference, then methods, side by side);
//! * `report.md` and `report.html` (same tables; the HTML shows the PNG charts and the crops
//!   labelled with method, budget, wall time and spp).
//!
//! With `--single-run` (`CompareOutcome::single_run`) both reports say, under the header, that
//! the smaller budgets' rows are snapshots of one run at the largest budget.
//!
//! A chart that cannot be drawn (e.g. every run failed) is listed as a note, not an error.

use super::{budget_label, CompareOutcome, RunRecord};
use crate::chart::{self, Series};
use crate::image_io::{self, atomic_write, Image};
use std::fmt::Write as _;
use std::path::Path;

/// PNG exposure of crops and strips, in stops (the same as the render PNGs).
pub const CROP_EXPOSURE: f32 = 0.0;
/// Crops are upscaled by an integer factor until at least this many pixels tall.
pub const CROP_MIN_HEIGHT: usize = 160;

/// Mean, min and max of a statistic over seeds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Agg {
    /// Mean.
    pub mean: f64,
    /// Minimum.
    pub min: f64,
    /// Maximum.
    pub max: f64,
}

/// Aggregates `f` over `values`; `None` if empty.
pub fn aggregate(values: impl IntoIterator<Item = f64>) -> Option<Agg> {
    let v: Vec<f64> = values.into_iter().collect();
    if v.is_empty() {
        return None;
    }
    let mean = v.iter().sum::<f64>() / v.len() as f64;
    Some(Agg {
        mean,
        min: v.iter().copied().fold(f64::INFINITY, f64::min),
        max: v.iter().copied().fold(f64::NEG_INFINITY, f64::max),
    })
}

pub use crate::scene::safe_name;

/// Escapes `&`, `<`, `>` and `"` for HTML.
pub fn esc(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

/// A Markdown table.
pub fn table_md(headers: &[String], rows: &[Vec<String>]) -> String {
    let mut s = format!("| {} |\n|{}\n", headers.join(" | "), "---|".repeat(headers.len()));
    for r in rows {
        let _ = writeln!(s, "| {} |", r.iter().map(|c| c.replace('|', "\\|")).collect::<Vec<_>>().join(" | "));
    }
    s
}

/// An HTML table (cells are escaped).
pub fn table_html(headers: &[String], rows: &[Vec<String>]) -> String {
    let mut s = String::from("<table>\n<tr>");
    for h in headers {
        let _ = write!(s, "<th>{}</th>", esc(h));
    }
    s.push_str("</tr>\n");
    for r in rows {
        s.push_str("<tr>");
        for c in r {
            let _ = write!(s, "<td>{}</td>", esc(c));
        }
        s.push_str("</tr>\n");
    }
    s.push_str("</table>\n");
    s
}

/// A complete HTML page with the report style.
pub fn html_page(title: &str, body: &str) -> String {
    format!(
        "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>{t}</title>\n<style>\
         body{{font-family:sans-serif;margin:20px;max-width:1400px}} table{{border-collapse:collapse;margin:8px 0}}\
         td,th{{border:1px solid #bbb;padding:3px 7px;font-size:13px;text-align:right}} th{{background:#eee}}\
         figure{{display:inline-block;margin:4px;text-align:center}} figcaption{{font-size:12px}}\
         img.crop{{image-rendering:pixelated}} img.chart{{width:560px;margin:4px}} .bad{{color:#b00}}\
         </style></head>\n<body>\n<h1>{t}</h1>\n{body}</body></html>\n",
        t = esc(title)
    )
}

/// Nearest-neighbour upscale by an integer factor.
pub fn upscale(img: &Image, f: usize) -> Image {
    let f = f.max(1);
    Image::from_fn(img.width * f, img.height * f, |x, y| img.get(x / f, y / f))
}

/// Images side by side with a `gap`-pixel white separator, top-aligned (black below short ones).
pub fn hstack(imgs: &[Image], gap: usize) -> Option<Image> {
    let h = imgs.iter().map(|i| i.height).max()?;
    let w = imgs.iter().map(|i| i.width).sum::<usize>() + gap * imgs.len().saturating_sub(1);
    let mut out = Image::from_fn(w, h, |_, _| [1.0; 3]);
    let mut x0 = 0;
    for im in imgs {
        for y in 0..h {
            for x in 0..im.width {
                out.set(x0 + x, y, im.try_get(x, y).unwrap_or([0.0; 3]));
            }
        }
        x0 += im.width + gap;
    }
    Some(out)
}

fn fmt_e(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.3e}")
    } else {
        "–".into()
    }
}

fn fmt_f(v: f64, digits: usize) -> String {
    if v.is_finite() {
        format!("{v:.digits$}")
    } else {
        "–".into()
    }
}

fn ok_runs<'a>(runs: &'a [RunRecord], method: &'a str, budget: f64) -> impl Iterator<Item = &'a RunRecord> + 'a {
    runs.iter().filter(move |r| r.method == method && r.budget_s == budget && r.error.is_none() && r.spp > 0)
}

fn region_rel(r: &RunRecord, region: &str) -> Option<f64> {
    r.regions.iter().find(|e| e.region == region).map(|e| e.rel_mse)
}

/// Methods and budgets in first-seen order.
fn axes(o: &CompareOutcome) -> (Vec<String>, Vec<f64>) {
    let (mut ms, mut bs): (Vec<String>, Vec<f64>) = (Vec::new(), Vec::new());
    for r in &o.runs {
        if !ms.contains(&r.method) {
            ms.push(r.method.clone());
        }
        if !bs.contains(&r.budget_s) {
            bs.push(r.budget_s);
        }
    }
    bs.sort_by(f64::total_cmp);
    (ms, bs)
}

/// One series per method: x = mean of `xf` over seeds, y = mean relMSE, band = min–max relMSE.
fn series(o: &CompareOutcome, region: &str, xf: fn(&RunRecord) -> f64) -> Vec<Series> {
    let (methods, budgets) = axes(o);
    methods
        .iter()
        .map(|m| {
            let mut points = Vec::new();
            let mut band = Vec::new();
            for &b in &budgets {
                let runs: Vec<&RunRecord> = ok_runs(&o.runs, m, b).collect();
                let (Some(x), Some(y)) = (
                    aggregate(runs.iter().map(|r| xf(r))),
                    aggregate(runs.iter().filter_map(|r| region_rel(r, region))),
                ) else {
                    continue;
                };
                points.push((x.mean, y.mean));
                band.push((x.mean, y.min, y.max));
            }
            points.sort_by(|a, b| a.0.total_cmp(&b.0));
            band.sort_by(|a, b| a.0.total_cmp(&b.0));
            Series { label: m.clone(), points, band: Some(band) }
        })
        .collect()
}

/// A table: its header and rows.
type Table = (Vec<String>, Vec<Vec<String>>);
/// A chart drawn: region, kind (`time` or `spp`), path without extension.
type ChartEntry = (String, &'static str, String);
/// A region's crops: region, then (PNG path, label) per image.
type CropRow = (String, Vec<(String, String)>);

/// What `report.md` and `report.html` show, built once for both.
struct Sections {
    header: String,
    single: Option<String>,
    charts: Vec<ChartEntry>,
    crops: Vec<CropRow>,
    summary: Table,
    runs: Table,
    notes: Vec<String>,
}

/// Writes every artifact of the comparison into `dir`.
pub fn write_compare_report(dir: &Path, o: &CompareOutcome, reference: &Image) -> Result<(), String> {
    for sub in ["charts", "crops"] {
        let d = dir.join(sub);
        std::fs::create_dir_all(&d).map_err(|e| format!("cannot create {}: {e}", d.display()))?;
    }
    let json = serde_json::to_string_pretty(o).map_err(|e| e.to_string())?;
    atomic_write(&dir.join("results.json"), json.as_bytes())?;
    let (methods, budgets) = axes(o);
    let mut notes = Vec::new();
    let charts = write_charts(dir, o, &mut notes);
    let top = budgets.last().copied();
    let mut crops = Vec::new();
    for reg in &o.regions {
        crops.push(write_crops(dir, o, reg, reference, &methods, top, &mut notes)?);
    }
    let sections = Sections {
        header: report_header(o),
        single: single_run_line(o, &budgets),
        charts,
        crops,
        summary: summary_table(o, &methods, &budgets),
        runs: runs_table(o),
        notes,
    };
    atomic_write(&dir.join("report.md"), report_md(o, &sections).as_bytes())?;
    atomic_write(&dir.join("report.html"), html_page("Time-boxed comparison", &report_html(o, &sections)).as_bytes())?;
    Ok(())
}

/// The relMSE charts (against wall time and against spp) of every region; a chart that cannot
/// be drawn becomes a note.
fn write_charts(dir: &Path, o: &CompareOutcome, notes: &mut Vec<String>) -> Vec<ChartEntry> {
    let mut charts = Vec::new();
    for reg in &o.regions {
        let rn = safe_name(&reg.name);
        for (kind, x_label, xf) in [
            ("time", "wall time [s] (preprocess included)", (|r: &RunRecord| r.wall_s) as fn(&RunRecord) -> f64),
            ("spp", "samples per pixel", |r: &RunRecord| r.spp as f64),
        ] {
            let base = format!("charts/relmse-{kind}-{rn}");
            let title = format!("relMSE vs {kind}: {} ({})", reg.name, Path::new(&o.scene).display());
            let s = series(o, &reg.name, xf);
            let (svg, png) = (dir.join(format!("{base}.svg")), dir.join(format!("{base}.png")));
            match chart::line_chart_loglog(
                &svg,
                &png,
                &title,
                x_label,
                "relMSE (mean over seeds, band min–max)",
                &s,
                Some(-1.0),
            ) {
                Ok(()) => charts.push((reg.name.clone(), kind, base)),
                Err(e) => notes.push(format!("chart not drawn: {e}")),
            }
        }
    }
    charts
}

/// The crops of one region at the largest budget `top`, first seed: the reference, then each
/// method, each upscaled; and their side-by-side strip. A run whose image cannot be read becomes
/// a note.
fn write_crops(
    dir: &Path,
    o: &CompareOutcome,
    reg: &super::Region,
    reference: &Image,
    methods: &[String],
    top: Option<f64>,
    notes: &mut Vec<String>,
) -> Result<CropRow, String> {
    let rn = safe_name(&reg.name);
    let cut = |img: &Image| -> Result<Image, image_io::ImageError> {
        let c = match reg.rect {
            Some((x, y, w, h)) => img.crop(x, y, w, h)?,
            None => img.clone(),
        };
        Ok(upscale(&c, CROP_MIN_HEIGHT.div_ceil(c.height.max(1))))
    };
    let mut row = Vec::new();
    let mut imgs = Vec::new();
    let rc = cut(reference)?;
    let p = format!("crops/{rn}-reference.png");
    image_io::write_png_srgb(&dir.join(&p), &rc, CROP_EXPOSURE)?;
    row.push((p, "reference".to_string()));
    imgs.push(rc);
    for m in methods {
        let Some(run) = top.and_then(|b| ok_runs(&o.runs, m, b).min_by_key(|r| r.seed_index)) else { continue };
        let exr = crate::image_io::with_ext(&run.prefix, "exr");
        let c = match image_io::read_exr(&exr).and_then(|i| cut(&i)) {
            Ok(c) => c,
            Err(e) => {
                notes.push(format!("crop not made: {}: {e}", exr.display()));
                continue;
            }
        };
        let p = format!("crops/{rn}-{}.png", safe_name(m));
        image_io::write_png_srgb(&dir.join(&p), &c, CROP_EXPOSURE)?;
        let rel = region_rel(run, &reg.name).map_or("–".into(), fmt_e);
        let (budget, wall, spp) = (budget_label(run.budget_s), run.wall_s, run.spp);
        row.push((p, format!("{m} · {budget} budget · {wall:.1} s · {spp} spp · relMSE {rel}")));
        imgs.push(c);
    }
    if let Some(strip) = hstack(&imgs, 4) {
        image_io::write_png_srgb(&dir.join(format!("strip-{rn}.png")), &strip, CROP_EXPOSURE)?;
    }
    Ok((reg.name.clone(), row))
}

/// The summary table: one row per (method, budget), means and ranges over seeds.
fn summary_table(o: &CompareOutcome, methods: &[String], budgets: &[f64]) -> Table {
    let mut sum_h: Vec<String> =
        ["method", "budget", "runs measured", "mean spp", "mean wall s", "preprocess share"].map(String::from).to_vec();
    for reg in &o.regions {
        sum_h.push(format!("relMSE {} (mean)", reg.name));
        sum_h.push(format!("relMSE {} (min–max)", reg.name));
    }
    let mut sum_rows = Vec::new();
    for m in methods {
        for &b in budgets {
            let runs: Vec<&RunRecord> = ok_runs(&o.runs, m, b).collect();
            let all: Vec<&RunRecord> = o.runs.iter().filter(|r| &r.method == m && r.budget_s == b).collect();
            let zero = all.iter().filter(|r| r.error.is_none() && r.spp == 0).count();
            let a = |f: fn(&RunRecord) -> f64| aggregate(runs.iter().map(|r| f(r))).map_or(f64::NAN, |a| a.mean);
            let zeros = if zero > 0 { format!(" ({zero} with 0 spp)") } else { String::new() };
            let mut row = vec![
                m.clone(),
                budget_label(b),
                format!("{}/{}{zeros}", runs.len(), all.len()),
                fmt_f(a(|r| r.spp as f64), 1),
                fmt_f(a(|r| r.wall_s), 2),
                fmt_f(a(|r| r.preprocess_share), 3),
            ];
            for reg in &o.regions {
                match aggregate(runs.iter().filter_map(|r| region_rel(r, &reg.name))) {
                    Some(g) => row.extend([fmt_e(g.mean), format!("{}–{}", fmt_e(g.min), fmt_e(g.max))]),
                    None => row.extend(["–".into(), "–".into()]),
                }
            }
            sum_rows.push(row);
        }
    }
    (sum_h, sum_rows)
}

/// The table of every run with its status and per-region RMSE and relMSE.
fn runs_table(o: &CompareOutcome) -> Table {
    let mut run_h: Vec<String> =
        ["method", "budget", "seed", "status", "spp", "wall s", "preprocess s", "preprocess share", "non-finite"]
            .map(String::from)
            .to_vec();
    for reg in &o.regions {
        run_h.push(format!("RMSE {}", reg.name));
        run_h.push(format!("relMSE {}", reg.name));
    }
    let run_rows = o.runs.iter().map(|r| run_row(o, r)).collect();
    (run_h, run_rows)
}

/// One row of [`runs_table`].
fn run_row(o: &CompareOutcome, r: &RunRecord) -> Vec<String> {
    let mut row = vec![
        r.method.clone(),
        budget_label(r.budget_s),
        r.seed.to_string(),
        match &r.error {
            Some(e) => format!("FAILED: {e}"),
            None if r.spp == 0 => "0 spp: no pass fit in the budget (left out of means and charts)".into(),
            None if r.from_snapshot => "ok (snapshot)".into(),
            None => "ok".into(),
        },
        r.spp.to_string(),
        format!("{:.3}", r.wall_s),
        format!("{:.3}", r.preprocess_s),
        format!("{:.3}", r.preprocess_share),
        r.nonfinite_samples.to_string(),
    ];
    for reg in &o.regions {
        match r.regions.iter().find(|e| e.region == reg.name) {
            Some(e) => row.extend([fmt_e(e.rmse), fmt_e(e.rel_mse)]),
            None => row.extend(["–".into(), "–".into()]),
        }
    }
    row
}

/// The line under the title: scene, reference, size, regions and the metric.
fn report_header(o: &CompareOutcome) -> String {
    let reg_desc: Vec<String> = o
        .regions
        .iter()
        .map(|r| match r.rect {
            Some((x, y, w, h)) => format!("{} = {x},{y},{w},{h}", r.name),
            None => format!("{} = whole image", r.name),
        })
        .collect();
    format!(
        "Scene `{}`, reference `{}`, {}x{} pixels. Regions (x,y,w,h at this resolution): {}. \
         relMSE = mean of (I−R)²/(R²+0.01); budgets include scene loading and preprocess.",
        o.scene,
        o.reference.display(),
        o.resolution.0,
        o.resolution.1,
        reg_desc.join("; ")
    )
}

/// With `--single-run`, the note that the smaller budgets are snapshots of one run.
fn single_run_line(o: &CompareOutcome, budgets: &[f64]) -> Option<String> {
    o.single_run.then(|| {
        format!(
            "Single run (--single-run): each (method, seed) was rendered once, at the largest budget ({}); \
             the rows of smaller budgets were measured from snapshots of that run (`render --snapshots`), \
             so their preprocess was sized for the largest budget and their wall time is the round \
             boundary the snapshot was taken at.",
            budgets.last().map_or_else(|| "–".into(), |&b| budget_label(b))
        )
    })
}

/// `report.md`.
fn report_md(o: &CompareOutcome, s: &Sections) -> String {
    let mut md = format!("# Time-boxed comparison\n\n{}\n\n", s.header);
    if let Some(line) = &s.single {
        let _ = writeln!(md, "**{line}**\n");
    }
    for w in &o.warnings {
        let _ = writeln!(md, "> **warning:** {w}\n");
    }
    let _ = write!(md, "## Summary (over seeds)\n\n{}\n## Charts\n\n", table_md(&s.summary.0, &s.summary.1));
    for (reg, kind, base) in &s.charts {
        let _ = writeln!(md, "![relMSE vs {kind}, {reg}]({base}.svg)\n");
    }
    md.push_str("## Crops (largest budget, first seed)\n\n");
    for (reg, row) in &s.crops {
        let _ = writeln!(md, "### {reg}\n\n![strip {reg}](strip-{}.png)\n", safe_name(reg));
        let _ = writeln!(md, "Left to right: {}\n", row.iter().map(|(_, l)| l.as_str()).collect::<Vec<_>>().join("; "));
    }
    let _ = write!(md, "## All runs\n\n{}\n", table_md(&s.runs.0, &s.runs.1));
    for n in &s.notes {
        let _ = writeln!(md, "- note: {n}");
    }
    md
}

/// The body of `report.html`.
fn report_html(o: &CompareOutcome, s: &Sections) -> String {
    let mut body = format!("<p>{}</p>\n", esc(&s.header));
    if let Some(line) = &s.single {
        let _ = writeln!(body, "<p><b>{}</b></p>", esc(line));
    }
    for w in &o.warnings {
        let _ = writeln!(body, "<p class=\"bad\"><b>warning:</b> {}</p>", esc(w));
    }
    let summary = table_html(&s.summary.0, &s.summary.1);
    let _ = write!(body, "<h2>Summary (over seeds)</h2>\n{summary}<h2>Charts</h2>\n<div>");
    for (reg, kind, base) in &s.charts {
        let _ = write!(
            body,
            "<a href=\"{base}.svg\"><img class=\"chart\" src=\"{base}.png\" alt=\"relMSE vs {kind}, {}\"></a>",
            esc(reg)
        );
    }
    body.push_str("</div>\n<h2>Crops (largest budget, first seed)</h2>\n");
    for (reg, row) in &s.crops {
        let _ = write!(body, "<h3>{}</h3>\n<div>", esc(reg));
        for (p, label) in row {
            let _ = write!(
                body,
                "<figure><img class=\"crop\" src=\"{p}\"><figcaption>{}</figcaption></figure>",
                esc(label)
            );
        }
        body.push_str("</div>\n");
    }
    let _ = write!(body, "<h2>All runs</h2>\n{}", table_html(&s.runs.0, &s.runs.1));
    for n in &s.notes {
        let _ = writeln!(body, "<p class=\"bad\">note: {}</p>", esc(n));
    }
    body
}
