//! Line charts (convergence plots) as SVG and PNG, drawn with `plotters` in pure Rust.
//!
//! * Each chart is written twice: an SVG (vector, text as `<text>` elements) and a PNG of the same
//!   pixel size (rendered into an RGB buffer with `BitMapBackend::with_buffer`, encoded by
//!   [`crate::image_io::encode_png_rgb8`]). The two files are replaced as a set
//!   ([`crate::atomic_io::FileSet`]: both or neither).
//! * Text uses the DejaVu Sans font shipped in `assets/DejaVuSans.ttf` (compiled in with
//!   `include_bytes!`), registered once as `"sans-serif"`; no system fonts are needed.
//! * Axes may be logarithmic; on a log axis points with non-positive coordinates are dropped.
//!   Log axes are labelled by [`log_ticks`]: whole decades when at least three fit, else
//!   1-2-5 × 10^k, else 1…9 × 10^k, else evenly spaced round values, so a range inside one decade
//!   (a `relmse-time` chart over 1–4 minutes) still gets labels; light grid lines at 1…9 × 10^k.
//!   Optional min–max bands are shaded under their series. On log–log charts an optional
//!   power-law guide `y ∝ x^slope` (e.g. slope −1 for error ∝ 1/spp) is drawn dashed.
//! * No panics on bad input: empty or non-finite data gives an `Err` naming the output file.
//!
//! This is the only module that uses `plotters`.

use crate::atomic_io::FileSet;
use crate::image_io::encode_png_rgb8;
use plotters::coord::ranged1d::{AsRangedCoord, DefaultFormatting, KeyPointHint, Ranged, ValueFormatter};
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;
use std::sync::OnceLock;

/// The font compiled into the binary (DejaVu Sans, Bitstream Vera licence, see
/// `assets/DejaVuSans-LICENSE.txt`).
const FONT_BYTES: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");

/// Default chart size in pixels (SVG and PNG).
pub const DEFAULT_SIZE: (u32, u32) = (800, 600);

/// Line colours, cycled through by series index.
const COLOURS: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(23, 190, 207),
];

/// One line of a chart.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    /// Legend text.
    pub label: String,
    /// `(x, y)` points, drawn in the given order.
    pub points: Vec<(f64, f64)>,
    /// Optional shaded band `(x, min, max)` (e.g. min–max over seeds), drawn in ascending x.
    pub band: Option<Vec<(f64, f64, f64)>>,
}

/// Everything about a chart except its data.
#[derive(Clone, Debug, PartialEq)]
pub struct ChartSpec {
    /// Title above the plot.
    pub title: String,
    /// x-axis description.
    pub x_label: String,
    /// y-axis description.
    pub y_label: String,
    /// Logarithmic x axis.
    pub log_x: bool,
    /// Logarithmic y axis.
    pub log_y: bool,
    /// Exponent of a dashed power-law guide `y ∝ x^slope`; drawn only when both axes are log.
    pub slope_guide: Option<f64>,
    /// Size in pixels `(width, height)`.
    pub size: (u32, u32),
}

/// Registers the shipped font as `"sans-serif"` (once per process).
fn ensure_font() -> Result<(), String> {
    static REGISTERED: OnceLock<Result<(), String>> = OnceLock::new();
    REGISTERED
        .get_or_init(|| {
            plotters::style::register_font("sans-serif", FontStyle::Normal, FONT_BYTES)
                .map_err(|_| "the bundled font assets/DejaVuSans.ttf is not a valid TTF".to_string())
        })
        .clone()
}

/// Writes a log–log line chart (SVG and PNG, [`DEFAULT_SIZE`]) with an optional
/// `y ∝ x^slope` guide (pass `Some(-1.0)` for the 1/N convergence rate).
pub fn line_chart_loglog(
    path_svg: &Path,
    path_png: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
    slope_guide: Option<f64>,
) -> Result<(), String> {
    let spec = ChartSpec {
        title: title.into(),
        x_label: x_label.into(),
        y_label: y_label.into(),
        log_x: true,
        log_y: true,
        slope_guide,
        size: DEFAULT_SIZE,
    };
    line_chart(path_svg, path_png, &spec, series)
}

/// Writes a line chart described by `spec` as an SVG at `path_svg` and a PNG at `path_png`.
pub fn line_chart(path_svg: &Path, path_png: &Path, spec: &ChartSpec, series: &[Series]) -> Result<(), String> {
    ensure_font()?;
    let (w, h) = spec.size;
    if w < 100 || h < 100 || w > 10_000 || h > 10_000 {
        return Err(format!("{}: chart size {w}x{h} must be within 100..=10000", path_svg.display()));
    }
    let bounds = data_bounds(spec, series).map_err(|e| format!("{}: {e}", path_svg.display()))?;

    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (w, h)).into_drawing_area();
        render(root, spec, series, bounds).map_err(|e| format!("{}: {e}", path_svg.display()))?;
    }
    let mut rgb = vec![255u8; w as usize * h as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
        render(root, spec, series, bounds).map_err(|e| format!("{}: {e}", path_png.display()))?;
    }
    let png = encode_png_rgb8(w as usize, h as usize, &rgb).map_err(|e| format!("{}: {e}", path_png.display()))?;
    let mut files = FileSet::new(); // the SVG and the PNG are replaced together or not at all
    files.add(path_svg.to_path_buf(), svg.into_bytes());
    files.add(path_png.to_path_buf(), png);
    files.commit()
}

/// Axis ranges `((x0, x1), (y0, y1))` covering all usable points and bands, padded.
type Bounds = ((f64, f64), (f64, f64));

fn usable(v: f64, log: bool) -> bool {
    v.is_finite() && (!log || v > 0.0)
}

fn padded(lo: f64, hi: f64, log: bool) -> (f64, f64) {
    if log {
        let (lo, hi) = if hi / lo < 1.01 { (lo / 1.5, hi * 1.5) } else { (lo, hi) };
        let pad = (hi / lo).powf(0.04);
        (lo / pad, hi * pad)
    } else {
        let span = if hi - lo > 0.0 { hi - lo } else { lo.abs().max(1.0) };
        (lo - 0.05 * span, hi + 0.05 * span)
    }
}

fn data_bounds(spec: &ChartSpec, series: &[Series]) -> Result<Bounds, String> {
    let (mut xs, mut ys) = (Vec::new(), Vec::new());
    for s in series {
        for &(x, y) in &s.points {
            if usable(x, spec.log_x) && usable(y, spec.log_y) {
                xs.push(x);
                ys.push(y);
            }
        }
        for &(x, lo, hi) in s.band.iter().flatten() {
            if usable(x, spec.log_x) {
                ys.extend([lo, hi].into_iter().filter(|&v| usable(v, spec.log_y)));
            }
        }
    }
    if xs.is_empty() {
        return Err("no finite data points to plot (log axes need positive values)".into());
    }
    let mm = |v: &[f64]| v.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| (a.min(x), b.max(x)));
    let (x0, x1) = mm(&xs);
    let (y0, y1) = mm(&ys);
    Ok((padded(x0, x1, spec.log_x), padded(y0, y1, spec.log_y)))
}

fn err_str<E: std::fmt::Display>(e: E) -> String {
    format!("drawing failed: {e}")
}

/// Draws the whole chart on `root`, choosing linear or logarithmic coordinates.
fn render<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    spec: &ChartSpec,
    series: &[Series],
    ((x0, x1), (y0, y1)): Bounds,
) -> Result<(), String> {
    root.fill(&WHITE).map_err(err_str)?;
    let lin = |a: f64, b: f64| RangedCoordf64::from(a..b);
    let log = |a: f64, b: f64| LogAxis { lo: a, hi: b };
    match (spec.log_x, spec.log_y) {
        (false, false) => plot(&root, spec, series, lin(x0, x1), lin(y0, y1)),
        (true, false) => plot(&root, spec, series, log(x0, x1), lin(y0, y1)),
        (false, true) => plot(&root, spec, series, lin(x0, x1), log(y0, y1)),
        (true, true) => plot(&root, spec, series, log(x0, x1), log(y0, y1)),
    }?;
    root.present().map_err(err_str)
}

/// A short tick label: 3 significant digits without trailing zeros, scientific outside
/// [1e-2, 1e4) (`2e-3`, `2.5e-3`, `60`, `0.25`).
fn tick(v: f64) -> String {
    let a = v.abs();
    if v == 0.0 {
        "0".into()
    } else if !(1e-2..1e4).contains(&a) {
        let s = format!("{v:.2e}");
        let (mantissa, exp) = s.split_once('e').unwrap_or((&s, "0"));
        let mantissa =
            if mantissa.contains('.') { mantissa.trim_end_matches('0').trim_end_matches('.') } else { mantissa };
        format!("{mantissa}e{exp}")
    } else {
        let s = format!("{v:.3}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        s.to_string()
    }
}

/// Fewest labels a log axis gets before [`log_ticks`] tries a denser set.
const MIN_TICKS: usize = 3;
/// Most labels on a log axis (decades are thinned to every n-th beyond this).
const MAX_TICKS: usize = 12;

/// The values `m × 10^k` (for each mantissa `m`) inside `[lo, hi]`, ascending.
fn mantissa_ticks(lo: f64, hi: f64, mantissas: &[f64]) -> Vec<f64> {
    let (k0, k1) = (lo.log10().floor() as i32 - 1, hi.log10().ceil() as i32 + 1);
    let mut v = Vec::new();
    for k in k0..=k1 {
        for &m in mantissas {
            // m·10^k via a decimal string, so 0.2 is the f64 nearest 0.2 (not 2 × 0.1)
            let x: f64 = format!("{m}e{k}").parse().unwrap_or(f64::NAN);
            if x >= lo * (1.0 - 1e-12) && x <= hi * (1.0 + 1e-12) {
                v.push(x);
            }
        }
    }
    v
}

/// Evenly spaced round values (step 1, 2 or 5 × 10^k) inside `[lo, hi]`, at least [`MIN_TICKS`].
fn linear_ticks(lo: f64, hi: f64) -> Vec<f64> {
    let raw = (hi - lo) / MIN_TICKS as f64;
    let e = 10f64.powf(raw.log10().floor());
    let step = [5.0, 2.0, 1.0].iter().map(|m| m * e).find(|&s| s <= raw).unwrap_or(e);
    let first = (lo / step).ceil() as i64;
    let last = (hi / step).floor() as i64;
    (first..=last).map(|i| i as f64 * step).collect()
}

/// Tick values for a logarithmic axis over `[lo, hi]` (`0 < lo < hi`, both finite): whole
/// decades if at least [`MIN_TICKS`] fit (every n-th decade if more than [`MAX_TICKS`]), else
/// 1-2-5 × 10^k, else 1…9 × 10^k, else evenly spaced round values. Empty for an invalid range.
pub fn log_ticks(lo: f64, hi: f64) -> Vec<f64> {
    if !(lo > 0.0 && hi > lo && hi.is_finite()) {
        return Vec::new();
    }
    let decades = mantissa_ticks(lo, hi, &[1.0]);
    if decades.len() >= MIN_TICKS {
        let every = decades.len().div_ceil(MAX_TICKS);
        return decades.into_iter().step_by(every).collect();
    }
    for set in [&[1.0, 2.0, 5.0][..], &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0]] {
        let t = mantissa_ticks(lo, hi, set);
        if t.len() >= MIN_TICKS {
            return t;
        }
    }
    linear_ticks(lo, hi)
}

/// A logarithmic axis labelled by [`log_ticks`] (plotters' own log axis labels whole decades
/// only, so a range inside one decade had no labels at all).
#[derive(Clone, Debug)]
struct LogAxis {
    lo: f64,
    hi: f64,
}

impl Ranged for LogAxis {
    type FormatOption = DefaultFormatting;
    type ValueType = f64;

    fn map(&self, v: &f64, limit: (i32, i32)) -> i32 {
        let t = (v.ln() - self.lo.ln()) / (self.hi.ln() - self.lo.ln());
        let p = limit.0 as f64 + t * (limit.1 - limit.0) as f64;
        // far outside the box is clipped by the drawing area; NaN maps to 0 (`as` saturates)
        p.round().clamp(-1e6, 1e6) as i32
    }

    fn key_points<H: KeyPointHint>(&self, hint: H) -> Vec<f64> {
        let major = log_ticks(self.lo, self.hi);
        if hint.weight().allow_light_points() {
            let minor = mantissa_ticks(self.lo, self.hi, &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0]);
            if minor.len() <= hint.max_num_points() && minor.len() > major.len() {
                return minor;
            }
        }
        major
    }

    fn range(&self) -> std::ops::Range<f64> {
        self.lo..self.hi
    }
}

fn plot<DB, X, Y>(
    root: &DrawingArea<DB, Shift>,
    spec: &ChartSpec,
    series: &[Series],
    xr: X,
    yr: Y,
) -> Result<(), String>
where
    DB: DrawingBackend,
    X: AsRangedCoord<Value = f64>,
    Y: AsRangedCoord<Value = f64>,
    X::CoordDescType: ValueFormatter<f64>,
    Y::CoordDescType: ValueFormatter<f64>,
{
    let mut chart = ChartBuilder::on(root)
        .caption(&spec.title, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(48)
        .y_label_area_size(72)
        .build_cartesian_2d(xr, yr)
        .map_err(err_str)?;
    chart
        .configure_mesh()
        .x_desc(spec.x_label.as_str())
        .y_desc(spec.y_label.as_str())
        .label_style(("sans-serif", 13))
        .axis_desc_style(("sans-serif", 15))
        .light_line_style(RGBColor(235, 235, 235))
        .x_labels(MAX_TICKS)
        .y_labels(MAX_TICKS)
        .x_label_formatter(&|v| tick(*v))
        .y_label_formatter(&|v| tick(*v))
        .draw()
        .map_err(err_str)?;

    let (lx, ly) = (spec.log_x, spec.log_y);
    for (i, s) in series.iter().enumerate() {
        let colour = COLOURS[i % COLOURS.len()];
        if let Some(band) = &s.band {
            let mut b: Vec<(f64, f64, f64)> =
                band.iter().copied().filter(|&(x, lo, hi)| usable(x, lx) && usable(lo, ly) && usable(hi, ly)).collect();
            b.sort_by(|p, q| p.0.total_cmp(&q.0));
            if b.len() >= 2 {
                let mut poly: Vec<(f64, f64)> = b.iter().map(|&(x, lo, _)| (x, lo)).collect();
                poly.extend(b.iter().rev().map(|&(x, _, hi)| (x, hi)));
                chart.draw_series(std::iter::once(Polygon::new(poly, colour.mix(0.18).filled()))).map_err(err_str)?;
            }
        }
        let pts: Vec<(f64, f64)> = s.points.iter().copied().filter(|&(x, y)| usable(x, lx) && usable(y, ly)).collect();
        chart
            .draw_series(LineSeries::new(pts.iter().copied(), colour.stroke_width(2)))
            .map_err(err_str)?
            .label(s.label.as_str())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2)));
        chart.draw_series(pts.iter().map(|&p| Circle::new(p, 3, colour.filled()))).map_err(err_str)?;
    }

    if let (Some(slope), true, true) = (spec.slope_guide, lx, ly) {
        if let Some(seg) = guide_segment(series, slope, chart.x_range(), chart.y_range()) {
            let grey = RGBColor(90, 90, 90);
            chart
                .draw_series(DashedLineSeries::new(seg, 8, 5, grey.stroke_width(1)))
                .map_err(err_str)?
                .label(format!("slope {slope}"))
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], grey.stroke_width(1)));
        }
    }

    if series.iter().any(|s| !s.label.is_empty()) || spec.slope_guide.is_some() {
        chart
            .configure_series_labels()
            .label_font(("sans-serif", 13))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(err_str)?;
    }
    Ok(())
}

/// The guide `y = (y_a / 2) (x / x_a)^slope`, i.e. through half the first usable point of the
/// first series (offset so it runs beside a matching curve instead of hiding under it), clipped (in log space) to the plotted box; `None` if nothing of it is visible.
fn guide_segment(
    series: &[Series],
    slope: f64,
    xr: std::ops::Range<f64>,
    yr: std::ops::Range<f64>,
) -> Option<Vec<(f64, f64)>> {
    let (x0, x1, y0, y1) = (xr.start, xr.end, yr.start, yr.end);
    if !slope.is_finite() {
        return None;
    }
    let &(xa, ya) = series.iter().flat_map(|s| s.points.iter()).find(|&&(x, y)| usable(x, true) && usable(y, true))?;
    let (lxa, lya) = (xa.ln(), (0.5 * ya).ln());
    let y_at = |lx: f64| lya + slope * (lx - lxa);
    // Parametrise by ln x over [ln x0, ln x1] and intersect with ln y in [ln y0, ln y1].
    let (mut lo, mut hi) = (x0.ln(), x1.ln());
    if slope != 0.0 {
        let a = lxa + (y0.ln() - lya) / slope;
        let b = lxa + (y1.ln() - lya) / slope;
        lo = lo.max(a.min(b));
        hi = hi.min(a.max(b));
    } else if !(y0.ln()..=y1.ln()).contains(&lya) {
        return None;
    }
    if lo.is_nan() || hi.is_nan() || lo >= hi {
        return None;
    }
    Some(vec![(lo.exp(), y_at(lo).exp()), (hi.exp(), y_at(hi).exp())])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::image_io::read_png_rgb8;

    fn demo() -> Vec<Series> {
        let spp = [1.0, 4.0, 16.0, 64.0, 256.0];
        vec![
            Series {
                label: "pt".into(),
                points: spp.iter().map(|&n| (n, 0.5 / n)).collect(),
                band: Some(spp.iter().map(|&n| (n, 0.4 / n, 0.6 / n)).collect()),
            },
            Series { label: "iws+cf".into(), points: spp.iter().map(|&n| (n, 0.1 / n.sqrt())).collect(), band: None },
        ]
    }

    #[test]
    fn writes_svg_and_png() {
        let d = std::env::temp_dir().join(format!("forecast-chart-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        let (svg, png) = (d.join("c.svg"), d.join("c.png"));
        line_chart_loglog(&svg, &png, "rel MSE vs spp", "samples per pixel", "relMSE", &demo(), Some(-1.0)).unwrap();
        let text = std::fs::read_to_string(&svg).unwrap();
        assert!(text.trim_start().starts_with("<svg"), "{}", &text[..80.min(text.len())]);
        assert!(text.trim_end().ends_with("</svg>"));
        for needle in ["rel MSE vs spp", "samples per pixel", "relMSE", "iws+cf", "slope -1", "<polygon"] {
            assert!(text.contains(needle), "SVG lacks {needle}");
        }
        let bytes = std::fs::read(&png).unwrap();
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
        let (w, h, rgb) = read_png_rgb8(&png).unwrap();
        assert_eq!((w, h), (800, 600));
        // Something besides white was drawn, including the first series' blue.
        assert!(rgb.chunks(3).filter(|p| p != &[255, 255, 255]).count() > 5000);
        assert!(rgb.chunks(3).any(|p| p == [31, 119, 180]));
        assert!(!crate::image_io::atomic_path(&png).exists());

        let spec = ChartSpec {
            title: "linear".into(),
            x_label: "x".into(),
            y_label: "y".into(),
            log_x: false,
            log_y: false,
            slope_guide: Some(-1.0),
            size: (400, 300),
        };
        let lin = vec![Series { label: "neg".into(), points: vec![(0.0, -1.0), (1.0, 2.0)], band: None }];
        line_chart(&svg, &png, &spec, &lin).unwrap();
        assert_eq!(read_png_rgb8(&png).unwrap().0, 400);
        let _ = std::fs::remove_dir_all(d);
    }

    #[test]
    fn bad_input_is_an_error() {
        let d = std::env::temp_dir();
        let (svg, png) = (d.join("forecast-chart-bad.svg"), d.join("forecast-chart-bad.png"));
        let neg = vec![Series { label: "n".into(), points: vec![(-1.0, 1.0), (f64::NAN, 2.0)], band: None }];
        let e = line_chart_loglog(&svg, &png, "t", "x", "y", &neg, None).unwrap_err();
        assert!(e.contains("forecast-chart-bad.svg"), "{e}");
        assert!(line_chart_loglog(&svg, &png, "t", "x", "y", &[], None).is_err());
        assert!(!svg.exists());
    }

    #[test]
    fn log_ticks_label_every_range() {
        // several decades: decades only
        assert_eq!(log_ticks(0.5, 2000.0), vec![1.0, 10.0, 100.0, 1000.0]);
        // 1.5 decades: only 2 decades fit, so 1-2-5
        assert_eq!(log_ticks(0.03, 1.0), vec![0.05, 0.1, 0.2, 0.5, 1.0]);
        // inside one decade (a 1-4 min budget axis): 1..9 x 10^k
        assert_eq!(log_ticks(57.0, 252.0), vec![60.0, 70.0, 80.0, 90.0, 100.0, 200.0]);
        assert_eq!(log_ticks(1.9e-3, 8.4e-3), vec![2e-3, 3e-3, 4e-3, 5e-3, 6e-3, 7e-3, 8e-3]);
        // narrower than the 1..9 grid: round linear steps
        assert_eq!(log_ticks(1.02, 1.09), vec![1.02, 1.04, 1.06, 1.08]);
        // twenty decades are thinned to at most MAX_TICKS
        let t = log_ticks(1e-10, 1e10);
        assert!(t.len() >= MIN_TICKS && t.len() <= MAX_TICKS, "{t:?}");
        assert_eq!((t[0], t[1]), (1e-10, 1e-8));
        // never fewer than MIN_TICKS inside the range, always ascending, always inside
        for &(lo, hi) in &[(0.7, 1.3), (3.1, 9.7), (0.011, 0.099), (45.0, 460.0), (2.0, 2.5), (1e-300, 1e300)] {
            let t = log_ticks(lo, hi);
            assert!(t.len() >= MIN_TICKS, "{lo}..{hi}: {t:?}");
            assert!(t.windows(2).all(|w| w[0] < w[1]) && t.iter().all(|&v| v >= lo && v <= hi), "{lo}..{hi}: {t:?}");
        }
        assert!(
            log_ticks(0.0, 1.0).is_empty() && log_ticks(2.0, 1.0).is_empty() && log_ticks(1.0, f64::NAN).is_empty()
        );
    }

    #[test]
    fn tick_labels_are_short() {
        assert_eq!(tick(2e-3), "2e-3");
        assert_eq!(tick(2.5e-3), "2.5e-3");
        assert_eq!(tick(60.0), "60");
        assert_eq!(tick(0.25), "0.25");
        assert_eq!(tick(1e5), "1e5");
    }

    #[test]
    fn guide_is_clipped_to_box() {
        let s = vec![Series { label: String::new(), points: vec![(1.0, 2.0)], band: None }]; // guide through (1, 1)
        let seg = guide_segment(&s, -1.0, 0.1..100.0, 0.1..10.0).unwrap();
        // y = 1/x clipped to y in [0.1, 10] and x in [0.1, 100] -> x in [0.1, 10]
        assert!((seg[0].0 - 0.1).abs() < 1e-12 && (seg[0].1 - 10.0).abs() < 1e-9);
        assert!((seg[1].0 - 10.0).abs() < 1e-9 && (seg[1].1 - 0.1).abs() < 1e-12);
        assert!(guide_segment(&s, 0.0, 0.1..100.0, 2.0..3.0).is_none());
    }
}
