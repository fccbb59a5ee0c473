//! Micro-benchmark of the light and direction samplers (formerly the ignored "test"
//! `tests/selection.rs` `bench_selection_and_mixture`): RIS point-light selection
//! (`transport::light_select`) on 75 VPLs against the full unshadowed sum, and the defensive
//! BSDF/table mixture (`forecast::mixture`) against `bsdf::sample` alone.
//!
//! Run: `cargo bench --bench selection` (prints ns per call: the minimum over 7 runs of 100k
//! calls, the least disturbed by other processes). Not a test: it asserts nothing.

use forecast::bsdf::{self, Mode, ShadingPoint};
use forecast::cf::direction_table::{ForecastTables, Splat, TableMode};
use forecast::cf::mixture::{DefensiveMixture, MixtureWeights};
use forecast::math::{luminance, Frame, Rgb, Vec3, PI};
use forecast::sampling::rng::{stream, Rng};
use forecast::scene::Material;
use forecast::transport::light_select::{LightSelector, RisParams};
use std::time::Instant;

/// ns per call of `f`: the minimum over 7 runs of 100k calls.
fn time(f: &mut dyn FnMut()) -> f64 {
    (0..7)
        .map(|_| {
            let t0 = Instant::now();
            for _ in 0..100_000 {
                f();
            }
            t0.elapsed().as_nanos() as f64 / 1e5
        })
        .fold(f64::INFINITY, f64::min)
}

/// RIS on 75 VPLs on a box's walls at a Lambertian point on the floor, p̂ = lum(f·min(G,b)·Φ).
fn bench_ris() {
    let mut r = Rng::keyed(1, stream::MISC, 0, 0);
    let vpls: Vec<(Vec3, Vec3, Rgb)> = (0..75)
        .map(|i| {
            let p = Vec3::new(2.0 * r.next_f32() - 1.0, 2.0 * r.next_f32() - 1.0, 2.0 * r.next_f32());
            let n = if i % 2 == 0 { -Vec3::Z } else { Vec3::X };
            (p, n, Rgb::new(r.next_f32(), r.next_f32(), r.next_f32()))
        })
        .collect();
    let phi: Vec<f32> = vpls.iter().map(|v| luminance(v.2)).collect();
    let (x, nx, rho, b) = (Vec3::new(0.1, 0.2, 0.0), Vec3::Z, Rgb::splat(0.7 / PI), 10.0f32);
    let target = |i: usize| {
        let (p, n, pw) = vpls[i];
        let d = p - x;
        let r2 = d.length_squared();
        let w = d / r2.sqrt();
        let g = (nx.dot(w).max(0.0) * n.dot(-w).abs() / r2).min(b);
        let c = rho * pw * g;
        (luminance(c), c)
    };
    let sel = LightSelector::new(&phi).expect("positive powers");
    for (m, k) in [(4u32, 1u32), (8, 1), (16, 1), (0, 1), (8, 4)] {
        let p = RisParams::new(m, k, true).expect("valid RIS parameters");
        let mut rng = Rng::keyed(2, stream::MISC, 0, 0);
        let (mut acc, mut calls) = (0.0f64, 0u64);
        let ns = time(&mut || {
            calls += 1;
            sel.select(&p, &mut rng, target, |s| acc += luminance(s.value * s.weight) as f64);
        });
        println!("RIS n=75 M={m} K={k}: {ns:.1} ns/selection (mean estimate {:.4})", acc / calls as f64);
    }
    let (mut acc, mut calls) = (0.0f64, 0u64);
    let ns = time(&mut || {
        calls += 1;
        let mut sum = Rgb::ZERO;
        for i in 0..75 {
            sum += target(std::hint::black_box(i)).1;
        }
        acc += luminance(sum) as f64;
    });
    println!("full sum of the 75 unshadowed terms (no rays): {ns:.1} ns (value {:.4})", acc / calls as f64);
}

fn dir(theta_deg: f32, phi_deg: f32) -> Vec3 {
    let (t, p) = (theta_deg.to_radians(), phi_deg.to_radians());
    Vec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos())
}

/// The mixture of `m` at a flat point seen from `wo`, tables from 200 forecasters near (θ, φ).
fn bench_mixture(name: &str, m: Material, wo: Vec3, (theta, phi): (f32, f32)) {
    let sp = ShadingPoint::new(Vec3::ZERO, Vec3::Z, Vec3::Z);
    let mut r = Rng::keyed(5, stream::MISC, 5, 0);
    let photons: Vec<(Vec3, f32)> = (0..200)
        .map(|_| {
            let d = dir(
                (theta + 10.0 * (2.0 * r.next_f32() - 1.0)).clamp(0.5, 89.0),
                phi + 10.0 * (2.0 * r.next_f32() - 1.0),
            );
            (d, d.z)
        })
        .collect();
    let frame = Frame::from_normal(sp.ns);
    let fc = |l: Vec3| luminance(bsdf::eval(&m, &sp, wo, frame.to_world(l), Mode::Radiance)) * l.z;
    let t = ForecastTables::build_with(photons, fc, TableMode::Dual, Splat::None);
    let w = MixtureWeights::new(0.3, 0.5, 0.2).expect("valid weights");
    let mix = DefensiveMixture::new(&m, &sp, wo, &t, frame, w);
    let mut rng = Rng::keyed(3, stream::MISC, 0, 0);
    let mut acc = 0.0f32;
    let ns = time(&mut || acc += mix.sample(&mut rng).map_or(0.0, |s| s.pdf_w));
    let ns_b = time(&mut || {
        let u = [rng.next_f32(), rng.next_f32(), rng.next_f32()];
        acc += bsdf::sample(&m, &sp, wo, u, Mode::Radiance).map_or(0.0, |s| s.pdf_w);
    });
    println!("mixture {name}: {ns:.1} ns/sample (bsdf::sample alone {ns_b:.1} ns) [{acc:.1}]");
}

fn main() {
    bench_ris();
    let lambert = Material::Diffuse { albedo: Rgb::new(0.7, 0.5, 0.3) };
    let phong = Material::Glossy { albedo: Rgb::splat(0.3), specular: Rgb::splat(0.5), exponent: 10.0 };
    bench_mixture("lambert dual", lambert, dir(30.0, 0.0), (60.0, 200.0));
    bench_mixture("phong dual", phong, dir(45.0, 20.0), (60.0, 200.0));
    bench_mixture("phong dual, photons near the lobe", phong, dir(60.0, 0.0), (40.0, 30.0));
}
