//! Agreement with Mitsuba 3.9.1 on the committed images: `eval`, `eval_1` and `mean`
//! (`mitsuba-values.csv`) and `eval_1_grad` (`mitsuba-grad.csv`), written by
//! `scripts/mitsuba-texture-values.py` and `scripts/mitsuba-texture-grad.py`.

use super::*;

/// One row of `mitsuba-values.csv`.
struct Row {
    case: usize,
    texture: String,
    filename: String,
    filter_type: String,
    wrap_mode: String,
    raw: bool,
    m: [f32; 6],
    c0: [f32; 3],
    c1: [f32; 3],
    uv: Vec2,
    rgb: Rgb,
    eval_1: f32,
    mean: f32,
}

fn read_rows() -> Vec<Row> {
    let text = std::fs::read_to_string(data_dir().join("mitsuba-values.csv")).unwrap();
    let mut lines = text.lines();
    assert!(lines.next().unwrap().starts_with("case,texture,filename,"));
    lines
        .map(|line| {
            let f: Vec<&str> = line.split(',').collect();
            assert_eq!(f.len(), 25, "{line}");
            let n = |i: usize| f[i].parse::<f32>().unwrap_or_else(|e| panic!("{line}: field {i}: {e}"));
            Row {
                case: f[0].parse().unwrap(),
                texture: f[1].into(),
                filename: f[2].into(),
                filter_type: f[3].into(),
                wrap_mode: f[4].into(),
                raw: f[5] == "true",
                m: std::array::from_fn(|i| n(6 + i)),
                c0: std::array::from_fn(|i| n(12 + i)),
                c1: std::array::from_fn(|i| n(15 + i)),
                uv: Vec2::new(n(18), n(19)),
                rgb: Rgb::new(n(20), n(21), n(22)),
                eval_1: n(23),
                mean: n(24),
            }
        })
        .collect()
}

/// Relative tolerance of the agreement with Mitsuba for an image file: 16-bit images are held
/// by Mitsuba as half floats (relative step 2^-11), everything else in `f32` (the sRGB curve of
/// 8-bit images a rational fit within ~1e-6 of the exact one used here).
fn tolerance(filename: &str) -> f32 {
    if filename.contains("16") {
        1e-3
    } else {
        1e-5
    }
}

/// Every value of `mitsuba-values.csv` (Mitsuba 3.9.1's `eval`, `eval_1` and `mean` of the
/// committed images and of checkerboards, at 16 uv points, each filter and wrap mode, `raw`
/// both ways, several `to_uv`): `|ours − Mitsuba| <= tol · max(|Mitsuba|, 1e-2)` with `tol`
/// 1e-5 (1e-3 for the 16-bit PNG, which Mitsuba holds as half floats).
#[test]
fn agrees_with_mitsuba() {
    let rows = read_rows();
    assert!(rows.len() >= 800, "{} rows", rows.len());
    let mut cache = TextureCache::new();
    // worst relative difference (to max(|Mitsuba|, 1e-2)) per tolerance class, and unfloored
    let (mut worst, mut worst_16, mut worst_unfloored) = ((0.0f32, String::new()), 0.0f32, 0.0f32);
    let mut cases = std::collections::BTreeSet::new();
    for r in &rows {
        cases.insert(r.case);
        let to_uv = UvTransform { rows: [[r.m[0], r.m[1], r.m[2]], [r.m[3], r.m[4], r.m[5]]] };
        let (texture, tol) = match r.texture.as_str() {
            "bitmap" => {
                let params = BitmapParams {
                    filename: data_dir().join(&r.filename),
                    filter_type: FilterType::parse(&r.filter_type).unwrap(),
                    wrap_mode: WrapMode::parse(&r.wrap_mode).unwrap(),
                    raw: r.raw,
                    to_uv,
                };
                (Texture::Bitmap(cache.bitmap(&params).unwrap()), tolerance(&r.filename))
            }
            "checkerboard" => {
                let c = |c: [f32; 3]| Texture::Constant(Rgb::from_array(c));
                (Texture::Checkerboard(Checkerboard::new(c(r.c0), c(r.c1), to_uv)), 1e-5)
            }
            other => panic!("unknown texture {other}"),
        };
        let what = format!(
            "case {} {} {} {} {} raw={} at {}",
            r.case, r.texture, r.filename, r.filter_type, r.wrap_mode, r.raw, r.uv
        );
        let got = texture.eval(r.uv);
        let checks = [
            ("r", got.x, r.rgb.x),
            ("g", got.y, r.rgb.y),
            ("b", got.z, r.rgb.z),
            ("eval_1", texture.eval_1(r.uv), r.eval_1),
            ("mean", texture.mean(), r.mean),
        ];
        for (name, ours, theirs) in checks {
            let err = (ours - theirs).abs() / theirs.abs().max(1e-2);
            assert!(err <= tol, "{what}: {name} {ours} vs Mitsuba {theirs} (relative {err:.2e} > {tol:.0e})");
            if tol < 1e-4 {
                if err > worst.0 {
                    worst = (err, format!("{what}: {name}"));
                }
                if theirs != 0.0 {
                    worst_unfloored = worst_unfloored.max((ours - theirs).abs() / theirs.abs());
                }
            } else {
                worst_16 = worst_16.max(err);
            }
        }
    }
    assert!(cases.len() >= 50, "{} cases", cases.len());
    eprintln!(
        "worst relative difference to Mitsuba: {:.2e} ({}); without the 1e-2 floor {:.2e}; 16-bit PNG {:.2e}",
        worst.0, worst.1, worst_unfloored, worst_16
    );
}

/// One row of `mitsuba-grad.csv` (`scripts/mitsuba-texture-grad.py`): Mitsuba 3.9.1's bitmap
/// `eval_1_grad` and `eval_1` at a uv point of a case.
struct GradRow {
    case: u32,
    params: BitmapParams,
    uv: Vec2,
    grad: Vec2,
    eval_1: f32,
}

fn read_grad_rows() -> Vec<GradRow> {
    let text = std::fs::read_to_string(data_dir().join("mitsuba-grad.csv")).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next().unwrap(),
        "case,filename,filter_type,wrap_mode,raw,m00,m01,m02,m10,m11,m12,u,v,du,dv,eval_1"
    );
    lines
        .map(|line| {
            let f: Vec<&str> = line.split(',').collect();
            assert_eq!(f.len(), 16, "{line}");
            let n = |i: usize| f[i].parse::<f32>().unwrap_or_else(|e| panic!("{line}: field {i}: {e}"));
            GradRow {
                case: f[0].parse().unwrap(),
                params: BitmapParams {
                    filename: data_dir().join(f[1]),
                    filter_type: FilterType::parse(f[2]).unwrap(),
                    wrap_mode: WrapMode::parse(f[3]).unwrap(),
                    raw: f[4] == "true",
                    to_uv: UvTransform { rows: [[n(5), n(6), n(7)], [n(8), n(9), n(10)]] },
                },
                uv: Vec2::new(n(11), n(12)),
                grad: Vec2::new(n(13), n(14)),
                eval_1: n(15),
            }
        })
        .collect()
}

/// Every row of `mitsuba-grad.csv` (Mitsuba 3.9.1's bitmap `eval_1_grad` on the committed images:
/// each image, both filters, each wrap mode, `raw` both ways, to_uv scalings, rotations, shears and
/// mirrorings, on square and non-square images, 18 uv points inside and outside [0, 1]² away from
/// the cells' edges): `|ours − Mitsuba| <= grad_bound` per component, and `eval_1` as in
/// `agrees_with_mitsuba`.
#[test]
fn grad_agrees_with_mitsuba() {
    let rows = read_grad_rows();
    assert!(rows.len() >= 600, "{} rows", rows.len());
    let mut cache = TextureCache::new();
    let (mut worst, mut cases, mut nonzero) = ((0.0f32, String::new()), std::collections::BTreeSet::new(), 0);
    for r in &rows {
        cases.insert(r.case);
        let b = cache.bitmap(&r.params).unwrap();
        let tol = tolerance(&r.params.filename.to_string_lossy());
        let what = format!(
            "case {} {} {} {} raw={} at {}",
            r.case,
            r.params.filename.file_name().unwrap().to_string_lossy(),
            r.params.filter_type.name(),
            r.params.wrap_mode.name(),
            r.params.raw,
            r.uv
        );
        let t = Texture::Bitmap(b.clone());
        let (g, bound) = (t.eval_1_grad(r.uv), grad_bound(&b, tol));
        for (c, ours, theirs) in [("du", g.x, r.grad.x), ("dv", g.y, r.grad.y)] {
            let err = (ours - theirs).abs();
            assert!(err <= bound, "{what}: {c} {ours} vs Mitsuba {theirs} (|difference| {err:.2e} > {bound:.2e})");
            if tol < 1e-4 && err / theirs.abs().max(bound) > worst.0 {
                worst = (err / theirs.abs().max(bound), format!("{what}: {c}"));
            }
        }
        nonzero += (r.grad != Vec2::ZERO) as usize;
        if r.params.filter_type == FilterType::Nearest {
            assert_eq!(g, Vec2::ZERO, "{what}: nearest");
        }
        let y = t.eval_1(r.uv);
        assert!((y - r.eval_1).abs() <= tol * r.eval_1.abs().max(1e-2), "{what}: eval_1 {y} vs Mitsuba {}", r.eval_1);
    }
    assert!(cases.len() >= 35 && nonzero >= 350, "{} cases, {nonzero} non-zero gradients", cases.len());
    eprintln!(
        "eval_1_grad: worst difference to Mitsuba relative to max(|Mitsuba|, its bound): {:.2e} ({})",
        worst.0, worst.1
    );
}
