//! The texture module's tests: known texels through each filter and wrap mode, `to_uv`, the
//! checkerboard's rule, the cache and its memory count, the gradient and the prefetch footprints;
//! agreement with Mitsuba 3.9.1 on the committed images is in `texture/tests/mitsuba.rs`.

use super::*;
use crate::image_io::{DecodedImage, TexelData};
use std::path::{Path, PathBuf};
use std::sync::Arc;

mod mitsuba;

fn data_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/texture")
}

/// A 3×2 linear RGB image whose texel `(x, y)` is `[x + 10y, 1 + x, 2 + y]` (every texel and
/// channel distinct).
fn known() -> Arc<TexelImage> {
    let (w, h) = (3, 2);
    let data = (0..h).flat_map(|y| (0..w).flat_map(move |x| [(x + 10 * y) as f32, 1.0 + x as f32, 2.0 + y as f32]));
    let image = DecodedImage { width: w, height: h, channels: 3, data: TexelData::F32(data.collect()), format: "EXR" };
    Arc::new(TexelImage::from_decoded(Path::new("known"), image, false).unwrap())
}

fn t(x: usize, y: usize) -> Rgb {
    Rgb::new((x + 10 * y) as f32, 1.0 + x as f32, 2.0 + y as f32)
}

fn bitmap(filter_type: FilterType, wrap_mode: WrapMode) -> Bitmap {
    Bitmap { image: known(), filter_type, wrap_mode, to_uv: UvTransform::IDENTITY }
}

/// The centre of texel `(x, y)` of the 3×2 image, as uv (any integer, for the wrap modes).
fn centre(x: i32, y: i32) -> Vec2 {
    Vec2::new((x as f32 + 0.5) / 3.0, (y as f32 + 0.5) / 2.0)
}

fn close(a: Rgb, b: Rgb) -> bool {
    (a - b).abs().max_element() <= 1e-5 * b.abs().max_element().max(1.0)
}

#[test]
fn bilinear_reads_texel_centres_and_blends_between() {
    for wrap in [WrapMode::Repeat, WrapMode::Mirror, WrapMode::Clamp] {
        let b = bitmap(FilterType::Bilinear, wrap);
        for y in 0..2 {
            for x in 0..3 {
                let got = b.eval(centre(x as i32, y as i32));
                assert!(close(got, t(x, y)), "{wrap:?} centre ({x},{y}): {got}");
            }
        }
        // half-way between the centres of (0,0) and (1,0), and a quarter of the way down to (1,1)
        let uv = Vec2::new(1.0 / 3.0, 0.25 + 0.25 * 0.5);
        let want = (t(0, 0) + t(1, 0)) * 0.5 * 0.75 + (t(0, 1) + t(1, 1)) * 0.5 * 0.25;
        assert!(close(b.eval(uv), want), "{wrap:?}: {} vs {want}", b.eval(uv));
    }
}

#[test]
fn bilinear_wrap_modes_at_and_beyond_the_edges() {
    let (rep, mir, cla) = (WrapMode::Repeat, WrapMode::Mirror, WrapMode::Clamp);
    let row0 = 0.25; // v of row 0's centres
                     // u = 0: half-way between texel -1 and texel 0
    let uv = Vec2::new(0.0, row0);
    assert!(close(bitmap(FilterType::Bilinear, rep).eval(uv), (t(2, 0) + t(0, 0)) * 0.5));
    assert!(close(bitmap(FilterType::Bilinear, mir).eval(uv), t(0, 0)));
    assert!(close(bitmap(FilterType::Bilinear, cla).eval(uv), t(0, 0)));
    // u = 1: half-way between texel 2 and texel 3
    let uv = Vec2::new(1.0, row0);
    assert!(close(bitmap(FilterType::Bilinear, rep).eval(uv), (t(2, 0) + t(0, 0)) * 0.5));
    assert!(close(bitmap(FilterType::Bilinear, mir).eval(uv), t(2, 0)));
    assert!(close(bitmap(FilterType::Bilinear, cla).eval(uv), t(2, 0)));
    // far outside, at texel centres: index -2 (repeat: 1; mirror: 1; clamp: 0) and 4 (1, 1, 2)
    for (x, r, m, c) in [(-2, 1, 1, 0), (4, 1, 1, 2), (-4, 2, 2, 0), (7, 1, 1, 2), (-1, 2, 0, 0)] {
        let uv = centre(x, 0);
        assert!(close(bitmap(FilterType::Bilinear, rep).eval(uv), t(r, 0)), "repeat {x}");
        assert!(close(bitmap(FilterType::Bilinear, mir).eval(uv), t(m, 0)), "mirror {x}");
        assert!(close(bitmap(FilterType::Bilinear, cla).eval(uv), t(c, 0)), "clamp {x}");
    }
    // v: row -1 is row 1 (repeat), row 0 (mirror, clamp); row 2 is row 0, 1, 1
    for (y, r, m, c) in [(-1, 1, 0, 0), (2, 0, 1, 1), (3, 1, 0, 1)] {
        let uv = centre(1, y);
        assert!(close(bitmap(FilterType::Bilinear, rep).eval(uv), t(1, r)), "repeat v {y}");
        assert!(close(bitmap(FilterType::Bilinear, mir).eval(uv), t(1, m)), "mirror v {y}");
        assert!(close(bitmap(FilterType::Bilinear, cla).eval(uv), t(1, c)), "clamp v {y}");
    }
}

#[test]
fn wrap_indices() {
    let n = 3;
    let w = |m: WrapMode| (-7..=7).map(|i| m.wrap(i, n)).collect::<Vec<_>>();
    assert_eq!(w(WrapMode::Repeat), [2, 0, 1, 2, 0, 1, 2, 0, 1, 2, 0, 1, 2, 0, 1]);
    assert_eq!(w(WrapMode::Mirror), [0, 0, 1, 2, 2, 1, 0, 0, 1, 2, 2, 1, 0, 0, 1]);
    assert_eq!(w(WrapMode::Clamp), [0, 0, 0, 0, 0, 0, 0, 0, 1, 2, 2, 2, 2, 2, 2]);
    for m in [WrapMode::Repeat, WrapMode::Mirror, WrapMode::Clamp] {
        assert!(m.wrap(i64::MAX, 5) < 5 && m.wrap(i64::MIN, 5) < 5 && m.wrap(0, 1) == 0);
        assert_eq!(WrapMode::parse(m.name()), Ok(m));
    }
    assert!(WrapMode::parse("wrap").unwrap_err().contains("\"repeat\""));
    assert_eq!(FilterType::parse("nearest"), Ok(FilterType::Nearest));
    assert!(FilterType::parse("trilinear").is_err());
}

#[test]
fn nearest_reads_the_containing_texel() {
    let (rep, mir, cla) = (WrapMode::Repeat, WrapMode::Mirror, WrapMode::Clamp);
    for wrap in [rep, mir, cla] {
        let b = bitmap(FilterType::Nearest, wrap);
        // anywhere inside texel (x, y), its corners included
        for (u, v, x, y) in [(0.01, 0.01, 0, 0), (0.34, 0.49, 1, 0), (0.99, 0.51, 2, 1), (0.5, 0.99, 1, 1)] {
            assert_eq!(b.eval(Vec2::new(u, v)), t(x, y), "{wrap:?} {u},{v}");
        }
    }
    // u = -0.1 is index -1; u = 1.2 is index 3; v = 1.7 is index 3; v = -0.6 is index -2
    let at = |m, u, v| bitmap(FilterType::Nearest, m).eval(Vec2::new(u, v));
    assert_eq!(at(rep, -0.1, 0.2), t(2, 0));
    assert_eq!(at(mir, -0.1, 0.2), t(0, 0));
    assert_eq!(at(cla, -0.1, 0.2), t(0, 0));
    assert_eq!(at(rep, 1.2, 0.2), t(0, 0));
    assert_eq!(at(mir, 1.2, 0.2), t(2, 0));
    assert_eq!(at(cla, 1.2, 0.2), t(2, 0));
    assert_eq!(at(rep, 0.5, 1.7), t(1, 1));
    assert_eq!(at(mir, 0.5, 1.7), t(1, 0));
    assert_eq!(at(cla, 0.5, -0.6), t(1, 0));
    assert_eq!(at(mir, 0.5, -0.6), t(1, 1));
}

#[test]
fn non_finite_uv_does_not_panic() {
    for f in [FilterType::Bilinear, FilterType::Nearest] {
        for m in [WrapMode::Repeat, WrapMode::Mirror, WrapMode::Clamp] {
            let b = bitmap(f, m);
            for uv in [Vec2::NAN, Vec2::INFINITY, Vec2::NEG_INFINITY, Vec2::new(3e38, -3e38), Vec2::new(1e10, 7.0)] {
                let _ = b.eval(uv);
                let _ = b.eval_1(uv);
            }
        }
    }
}

#[test]
fn to_uv_scale_offset_rotate() {
    // scale(3, 2) then translate(-1, 0.5): uv (x0 + 0.5)/9, (y0)/4 lands on the centre of texel
    // (x0 - 3 + .., ..); checked directly against the untransformed texture
    let plain = bitmap(FilterType::Bilinear, WrapMode::Repeat);
    let m = UvTransform::scale(Vec2::new(3.0, 2.0)).then(UvTransform::translate(Vec2::new(-1.0, 0.5)));
    let b = Bitmap { to_uv: m, ..plain.clone() };
    for uv in [Vec2::new(0.1, 0.2), Vec2::new(0.7, 0.9), Vec2::new(-0.3, 1.4)] {
        let mapped = Vec2::new(3.0 * uv.x - 1.0, 2.0 * uv.y + 0.5);
        assert!(close(b.eval(uv), plain.eval(mapped)));
        assert_eq!(m.apply(uv), mapped);
    }
    // texel (2, 1)'s centre, reached through scale(0.5, 0.5): uv twice its coordinates
    let half = Bitmap { to_uv: UvTransform::scale(Vec2::splat(0.5)), ..plain.clone() };
    assert!(close(half.eval(centre(2, 1) * 2.0), t(2, 1)));
    // rotation: Mitsuba's rotate(30) matrix, then(): translate ∘ rotate ∘ scale
    let r = UvTransform::rotate(30.0);
    assert!((r.rows[0][0] - 0.866_025_4).abs() < 1e-6 && r.rows[0][1] == -0.5 && r.rows[1][0] == 0.5);
    let a = UvTransform::scale(Vec2::new(2.0, 3.0)).then(r).then(UvTransform::translate(Vec2::new(0.25, -0.1)));
    let p = a.apply(Vec2::new(1.0, 0.0));
    assert!((p - Vec2::new(0.25 + 2.0 * 0.866_025_4, -0.1 + 2.0 * 0.5)).length() < 1e-6);
    assert!(UvTransform::default().is_identity() && !a.is_identity());
    let m3 = UvTransform::from_matrix([[1.0, 2.0, 3.0], [4.0, 5.0, 6.0], [7.0, 8.0, 9.0]]);
    assert_eq!(m3.apply(Vec2::new(1.0, 1.0)), Vec2::new(6.0, 15.0));
}

#[test]
fn srgb_decoding_of_8_bit_codes() {
    let image = |raw| {
        let d = DecodedImage {
            width: 4,
            height: 1,
            channels: 1,
            data: TexelData::U8(vec![0, 10, 128, 255]),
            format: "PNG",
        };
        TexelImage::from_decoded(Path::new("codes"), d, raw).unwrap()
    };
    let (srgb, raw) = (image(false), image(true));
    assert!(srgb.is_srgb() && !raw.is_srgb() && raw.raw());
    assert_eq!(srgb.texel(0, 0), Rgb::ZERO);
    assert_eq!(srgb.texel(3, 0), Rgb::ONE);
    assert!((srgb.texel(1, 0).x - 10.0 / 255.0 / 12.92).abs() < 1e-9);
    assert!((srgb.texel(2, 0).x - 0.215_860_5).abs() < 1e-7);
    assert_eq!(raw.texel(2, 0), Rgb::splat(128.0 / 255.0));
    // one channel: eval_1 and mean are the channel itself
    let b = Bitmap::new(Arc::new(raw));
    assert_eq!(b.eval_1(Vec2::new(0.625, 0.5)), 128.0 / 255.0);
    assert!((b.mean() - (10.0 + 128.0 + 255.0) / 255.0 / 4.0).abs() < 1e-7);
}

#[test]
fn from_decoded_refuses_broken_images() {
    let d = |w, h, c, data| DecodedImage { width: w, height: h, channels: c, data, format: "EXR" };
    let p = Path::new("dir/bad.exr");
    for image in [
        d(0, 1, 3, TexelData::F32(vec![])),
        d(2, 1, 2, TexelData::F32(vec![0.0; 4])),
        d(2, 2, 1, TexelData::F32(vec![0.0; 3])),
        d(2, 1, 1, TexelData::F32(vec![0.0, f32::NAN])),
        d(2, 1, 1, TexelData::F32(vec![-1.0, 0.0])),
    ] {
        let e = TexelImage::from_decoded(p, image, false).unwrap_err();
        assert!(e.to_string().contains("dir/bad.exr"), "{e}");
    }
}

#[test]
fn checkerboard_rule_and_defaults() {
    let c = Checkerboard::default();
    let at = |u, v| c.eval(Vec2::new(u, v)).x;
    // color0 on [0, ½]² and [½, 1]²; a boundary value ½ counts as the lower half
    assert_eq!((at(0.25, 0.25), at(0.75, 0.25), at(0.25, 0.75), at(0.75, 0.75)), (0.4, 0.2, 0.2, 0.4));
    assert_eq!((at(0.5, 0.5), at(0.5, 0.51), at(1.25, -0.75), at(-0.25, 0.25)), (0.4, 0.2, 0.4, 0.2));
    // eval_1 reads the colours the other way round, as Mitsuba 3.9.1 does
    assert_eq!(c.eval_1(Vec2::new(0.25, 0.25)), 0.2);
    assert_eq!(c.eval_1(Vec2::new(0.75, 0.25)), 0.4);
    assert!((c.mean() - 0.3).abs() < 1e-7);
    // to_uv scale 4: cells of ⅛
    let s = Checkerboard::new(Rgb::X.into(), Rgb::Y.into(), UvTransform::scale(Vec2::splat(4.0)));
    assert_eq!(s.eval(Vec2::new(0.1, 0.1)), Rgb::X);
    assert_eq!(s.eval(Vec2::new(0.2, 0.1)), Rgb::Y);
    assert_eq!(s.eval(Vec2::new(0.2, 0.2)), Rgb::X);
    let tex = Texture::Checkerboard(s);
    assert!(tex.is_spatially_varying() && !Texture::Constant(Rgb::ONE).is_spatially_varying());
    assert!((tex.mean() - 1.0 / 3.0).abs() < 1e-7);
    assert!((tex.eval_1(Vec2::new(0.1, 0.1)) - 1.0 / 3.0).abs() < 1e-7);
    // nested: a bitmap as color1, read at the surface's uv
    let b = bitmap(FilterType::Nearest, WrapMode::Repeat);
    let n = Checkerboard::new(Rgb::ZERO.into(), Texture::Bitmap(b.clone()), UvTransform::IDENTITY);
    assert_eq!(n.eval(Vec2::new(0.9, 0.1)), b.eval(Vec2::new(0.9, 0.1)));
    let mut images = 0;
    Texture::Checkerboard(n).for_each_image(&mut |_| images += 1);
    assert_eq!(images, 1);
}

#[test]
fn constant_eval_1_and_mean_are_the_channel_mean() {
    let c = Texture::Constant(Rgb::new(0.9, 0.1, 0.2));
    assert_eq!(c.eval(Vec2::ZERO), Rgb::new(0.9, 0.1, 0.2));
    assert!((c.eval_1(Vec2::ONE) - 0.4).abs() < 1e-7 && (c.mean() - 0.4).abs() < 1e-7);
    assert!((luminance(Rgb::ONE) - 1.0).abs() < 1e-6);
}

#[test]
fn cache_shares_one_image_per_file_and_raw_flag() {
    let dir = data_dir();
    let mut cache = TextureCache::new();
    let a = cache.load(&dir.join("rgb8.png"), false).unwrap();
    let b = cache.load(&dir.join("../texture/./rgb8.png"), false).unwrap();
    assert!(Arc::ptr_eq(&a, &b));
    let raw = cache.load(&dir.join("rgb8.png"), true).unwrap();
    assert!(!Arc::ptr_eq(&a, &raw) && raw.raw() && !raw.is_srgb() && a.is_srgb());
    let exr = cache.bitmap(&BitmapParams::new(dir.join("rgb.exr"))).unwrap();
    assert_eq!(
        (exr.filter_type, exr.wrap_mode, exr.to_uv),
        (FilterType::Bilinear, WrapMode::Repeat, UvTransform::IDENTITY)
    );
    assert_eq!(cache.len(), 3);
    // memory: 8-bit RGB 5×4 = 60 code bytes + the 1 KiB table; float RGB 4×3 = 144 bytes
    let fixed = |i: &TexelImage| std::mem::size_of::<TexelImage>() + i.path().as_os_str().len();
    assert_eq!(a.memory_bytes(), 60 + 1024 + fixed(&a));
    assert_eq!(exr.image.memory_bytes(), 144 + fixed(&exr.image));
    assert_eq!(cache.memory_bytes(), a.memory_bytes() + raw.memory_bytes() + exr.image.memory_bytes());
    assert_eq!(cache.images().count(), 3);
    // 16-bit images are held as floats: 4×3×3 samples of 4 bytes
    let x16 = cache.load(&dir.join("rgb16.png"), false).unwrap();
    assert_eq!(x16.memory_bytes(), 144 + fixed(&x16));
    let e = cache.load(&dir.join("missing.png"), false).unwrap_err();
    assert!(e.to_string().contains("missing.png"), "{e}");
    assert_eq!(cache.len(), 4);
}

/// The largest value `eval_1` reads anywhere in `b`'s image (a texel's luminance, or its one
/// channel).
fn max_value(b: &Bitmap) -> f32 {
    let img = &b.image;
    let mut m = 0.0f32;
    for y in 0..img.height() {
        for x in 0..img.width() {
            let t = img.texel(x, y);
            m = m.max(if img.channels() == 1 { t.x } else { luminance(t) });
        }
    }
    m
}

/// The bound on a gradient's difference from Mitsuba's that comes from its texels' differences
/// alone: each of the four texels of the cell within `tol` relative of Mitsuba's (the `eval`
/// agreement above: 1e-5, 1e-3 for the half-float 16-bit PNG), each weighted by at most
/// `resolution · Σ|A|` (`A` the linear part of `to_uv`).
fn grad_bound(b: &Bitmap, tol: f32) -> f32 {
    let [r0, r1] = b.to_uv.rows;
    let a = r0[0].abs() + r0[1].abs() + r1[0].abs() + r1[1].abs();
    let res = b.image.width().max(b.image.height()) as f32;
    4.0 * tol * max_value(b) * res * a
}

/// The central difference of `eval_1` along `d` at `uv` (step `h`, inside one bilinear cell, where
/// `eval_1` is linear along each texel axis).
fn central_difference(t: &Texture, uv: Vec2, d: Vec2, h: f32) -> f32 {
    (t.eval_1(uv + d * h) - t.eval_1(uv - d * h)) / (2.0 * h)
}

/// True when `uv`, after `to_uv`, lies within `margin` texels of a bilinear cell's edge.
fn near_edge(b: &Bitmap, uv: Vec2, margin: f32) -> bool {
    let p = b.to_uv.apply(uv);
    let (w, h) = (b.image.width() as f32, b.image.height() as f32);
    [p.x * w - 0.5, p.y * h - 0.5].iter().any(|q| {
        let f = q - q.floor();
        f.min(1.0 - f) < margin
    })
}

/// `eval_1_grad` is the derivative of `eval_1`: against central differences (a step of at most
/// 1e-2 texel, inside the cell; the rounding of the texel position, ~1e-6 texel at |uv| ≤ 8, is
/// 1e-4 of the difference quotient, within the tolerance's 2e-3 of the scale `resolution · Σ|A|
/// · max value`) on 400 points of each committed image, each wrap mode,
/// to_uv the identity, a scaling with a translation, a mirroring, and, where the image is
/// square (rgb.hdr, 3×3), a rotation (where Mitsuba's order of resolution and `A^T` is exact).
/// For a rotation on a non-square image Mitsuba's formula is not the derivative, and neither is
/// ours (it is Mitsuba's): the last check asserts that difference is there.
#[test]
fn grad_is_the_derivative_of_eval_1() {
    let mut cache = TextureCache::new();
    let shift_scale = UvTransform::scale(Vec2::new(2.0, 3.0)).then(UvTransform::translate(Vec2::new(0.25, -0.1)));
    let mirror = UvTransform::scale(Vec2::new(-1.5, 0.75)).then(UvTransform::translate(Vec2::new(0.3, 0.2)));
    let rotate = UvTransform::rotate(30.0).then(shift_scale);
    let mut cases = vec![];
    for file in ["rgb8.png", "grey8.png", "rgb.exr", "grey.exr", "rgb.hdr"] {
        for wrap in [WrapMode::Repeat, WrapMode::Mirror, WrapMode::Clamp] {
            for to_uv in [UvTransform::IDENTITY, shift_scale, mirror] {
                cases.push((file, wrap, to_uv));
            }
        }
    }
    cases.push(("rgb.hdr", WrapMode::Repeat, rotate));
    cases.push(("rgb.hdr", WrapMode::Mirror, rotate));
    let (mut checked, mut worst) = (0, 0.0f32);
    for (file, wrap, to_uv) in cases {
        let mut p = BitmapParams::new(data_dir().join(file));
        (p.wrap_mode, p.to_uv) = (wrap, to_uv);
        let b = cache.bitmap(&p).unwrap();
        let t = Texture::Bitmap(b.clone());
        let scale = grad_bound(&b, 1.0) / 4.0;
        // a step of at most 1e-2 texel after to_uv (which scales by up to 3)
        let h = 1e-2 / (b.image.width().max(b.image.height()) as f32 * 3.0);
        for k in 0..400 {
            let uv = Vec2::new(-1.3 + 3.7 * ((k as f32 * 0.618034) % 1.0), -1.1 + 3.3 * ((k as f32 * 0.754878) % 1.0));
            if near_edge(&b, uv, 0.03) {
                continue;
            }
            let g = t.eval_1_grad(uv);
            let fd = Vec2::new(central_difference(&t, uv, Vec2::X, h), central_difference(&t, uv, Vec2::Y, h));
            let err = (g - fd).abs().max_element() / scale;
            assert!(err <= 2e-3, "{file} {wrap:?} {to_uv:?} at {uv}: grad {g} vs central difference {fd} ({err:.1e})");
            worst = worst.max(err);
            checked += 1;
        }
    }
    assert!(checked >= 12_000, "{checked} points");
    eprintln!("eval_1_grad vs central differences: {checked} points, worst {worst:.1e} of the scale");

    // a rotation on the 5×4 rgb8.png: Mitsuba's order (A^T, then the resolution) is off the
    // derivative by up to |w − h|/max(w, h) of the slope, and so is ours
    let mut p = BitmapParams::new(data_dir().join("rgb8.png"));
    p.to_uv = rotate;
    let t = Texture::Bitmap(cache.bitmap(&p).unwrap());
    let uv = (0..100)
        .map(|k| Vec2::new(0.05 + 0.009 * k as f32, 0.31 + 0.004 * k as f32))
        .find(|uv| !near_edge(&cache.bitmap(&p).unwrap(), *uv, 0.05))
        .unwrap();
    let (g, h) = (t.eval_1_grad(uv), 1e-4);
    let fd = Vec2::new(central_difference(&t, uv, Vec2::X, h), central_difference(&t, uv, Vec2::Y, h));
    assert!((g - fd).length() > 0.05 * fd.length(), "rotated non-square: grad {g} equals the derivative {fd}");
}

/// A constant's gradient is zero, a checkerboard has none in Mitsuba (a bump map refuses it).
#[test]
fn grad_of_constants_and_checkerboards() {
    let c = Texture::Constant(Rgb::new(0.2, 0.5, 0.9));
    assert_eq!(c.eval_1_grad(Vec2::new(0.3, 0.7)), Vec2::ZERO);
    assert!(c.has_eval_1_grad());
    let k = Texture::Checkerboard(Checkerboard::new(c.clone(), Texture::Constant(Rgb::ONE), UvTransform::IDENTITY));
    assert!(!k.has_eval_1_grad());
    assert!(Texture::Bitmap(bitmap(FilterType::Nearest, WrapMode::Repeat)).has_eval_1_grad());
}

/// The texels a prefetch fetches are the texels a lookup reads: with 1 on `texels_read(uv)` and
/// 0 elsewhere, `eval` is 1 (its weights sum to 1 on them); with 0 on them and 1 elsewhere,
/// `eval` and `eval_1_grad` are 0 (no other texel has a weight); for every filter, wrap mode and
/// `to_uv`, uvs inside and outside `[0, 1]²`. And `texel_address` is the sample `texel` reads.
#[test]
fn texels_read_are_the_texels_the_lookups_read() {
    let (w, h) = (5, 4);
    let image = |inside: &[(usize, usize)], on: f32, off: f32, channels: usize| {
        let texel = |x, y| if inside.contains(&(x, y)) { on } else { off };
        let data = (0..h).flat_map(|y| (0..w).flat_map(move |x| std::iter::repeat_n(texel(x, y), channels)));
        let image = DecodedImage { width: w, height: h, channels, data: TexelData::F32(data.collect()), format: "EXR" };
        Arc::new(TexelImage::from_decoded(Path::new("mask"), image, false).unwrap())
    };
    let to_uvs = [
        UvTransform::IDENTITY,
        UvTransform::scale(Vec2::new(2.5, -1.5))
            .then(UvTransform::rotate(33.0))
            .then(UvTransform::translate(Vec2::new(0.3, -0.7))),
    ];
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut next = || {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (state >> 40) as f32 / (1u64 << 24) as f32 * 6.0 - 2.5
    };
    let mut checked = 0;
    for filter_type in [FilterType::Bilinear, FilterType::Nearest] {
        for wrap_mode in [WrapMode::Repeat, WrapMode::Mirror, WrapMode::Clamp] {
            for to_uv in to_uvs {
                for channels in [1, 3] {
                    for _ in 0..200 {
                        let uv = Vec2::new(next(), next());
                        let probe = Bitmap { image: image(&[], 0.0, 0.0, channels), filter_type, wrap_mode, to_uv };
                        let read = probe.texels_read(uv);
                        assert!(read.iter().all(|&(x, y)| x < w && y < h), "{read:?}");
                        let ones = Bitmap { image: image(&read, 1.0, 0.0, channels), ..probe.clone() };
                        let zeros = Bitmap { image: image(&read, 0.0, 1.0, channels), ..probe.clone() };
                        let at = format!("{filter_type:?} {wrap_mode:?} {to_uv:?} {channels} at {uv}: {read:?}");
                        assert!(close(ones.eval(uv), Rgb::ONE), "{at}: {}", ones.eval(uv));
                        assert_eq!(zeros.eval(uv), Rgb::ZERO, "{at}");
                        assert_eq!(zeros.eval_1_grad(uv), Vec2::ZERO, "{at}");
                        checked += 1;
                    }
                }
            }
        }
    }
    assert_eq!(checked, 2 * 3 * 2 * 2 * 200);
    // each texel's first sample is its index: the address holds the value `texel` returns
    for channels in [1, 3] {
        let data = (0..w * h).flat_map(|k| std::iter::repeat_n(k as f32, channels)).collect();
        let decoded = DecodedImage { width: w, height: h, channels, data: TexelData::F32(data), format: "EXR" };
        let i = TexelImage::from_decoded(Path::new("index"), decoded, false).unwrap();
        for (x, y) in (0..h).flat_map(|y| (0..w).map(move |x| (x, y))) {
            // SAFETY: `x < w`, `y < h`: the address of a sample of the store, an aligned f32
            let at = unsafe { *(i.texel_address(x, y) as *const f32) };
            assert_eq!((at, i.texel(x, y).x), ((y * w + x) as f32, (y * w + x) as f32));
        }
        let data = (0..w * h).flat_map(|k| std::iter::repeat_n(k as u8, channels)).collect();
        let decoded = DecodedImage { width: w, height: h, channels, data: TexelData::U8(data), format: "PNG" };
        let i = TexelImage::from_decoded(Path::new("codes"), decoded, true).unwrap();
        for (x, y) in (0..h).flat_map(|y| (0..w).map(move |x| (x, y))) {
            // SAFETY: as above, a code of the store
            assert_eq!(unsafe { *i.texel_address(x, y) }, (y * w + x) as u8);
        }
    }
}
