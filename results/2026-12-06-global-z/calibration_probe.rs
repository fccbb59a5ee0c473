mod common;
use common::render_passes as render;
use forecast::accel::World;
use forecast::integrators::{Method, MethodArgs};
use forecast::render::film::Film;
use std::path::Path;

fn opts() -> MethodArgs {
    let mut o = MethodArgs::default();
    (o.settings.max_depth, o.iws.vpl_paths, o.cf.forecast_photons, o.cf.clusters) = (Some(64), 64, Some(20_000), 16);
    o
}
/// (current, G only, Cauchy-Schwarz)
fn zs(a: &Film, b: &Film) -> [f64; 3] {
    let (ma, va, mb, vb) = (a.mean(), a.variance_of_mean(), b.mean(), b.variance_of_mean());
    let (mut d, mut v, mut dg, mut vg, mut vc) = (0.0f64, 0.0f64, 0.0, 0.0, 0.0);
    for i in 0..ma.len() {
        let mut sa = 0.0f64; let mut sb = 0.0f64;
        for c in 0..3 {
            d += ma[i][c] as f64 - mb[i][c] as f64;
            v += (va[i][c] + vb[i][c]) as f64;
            sa += (va[i][c] as f64).sqrt(); sb += (vb[i][c] as f64).sqrt();
        }
        dg += (ma[i][1] - mb[i][1]) as f64; vg += (va[i][1] + vb[i][1]) as f64;
        vc += sa * sa + sb * sb;
    }
    [d / v.sqrt(), dg / vg.sqrt(), d / vc.sqrt()]
}

#[test]
fn probe() {
    let w = World::build(forecast::scene::load(Path::new("scenes/cornell-box.toml")).unwrap()).unwrap();
    for (m, spp) in [(Method::Pt, 4096u64), (Method::IwsCf, 384), (Method::PtCf, 1024)] {
        let bytes = m.preprocess(&w, &opts(), 17).unwrap();
        let imgs: Vec<_> = (200..230u64).map(|s| { let mut p = m.build(&w, &opts(), &bytes).unwrap(); render(&w, p.as_mut(), 16, 16, spp, s) }).collect();
        let z: Vec<[f64; 3]> = imgs.chunks(2).map(|p| zs(&p[0], &p[1])).collect();
        for k in 0..3 {
            let rms = (z.iter().map(|z| z[k] * z[k]).sum::<f64>() / z.len() as f64).sqrt();
            let mx = z.iter().fold(0.0f64, |a, z| a.max(z[k].abs()));
            eprintln!("{m:?} {spp} [{}]: rms z {rms:.2}, max {mx:.2}", ["sum", "G", "CS"][k]);
        }
    }
}
