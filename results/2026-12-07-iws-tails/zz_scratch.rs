mod common;
use common::{cf_test_opts, render_passes as render};
use forecast::accel::World;
use forecast::integrators::iws::Iws;
use forecast::integrators::{BsdfCaustics, Method};
use forecast::render::film::Film;

const RES: u32 = 16;

fn report(label: &str, img: &Film, r: &Film) {
    let (ma, va, mb, vb) = (img.mean(), img.variance_of_mean(), r.mean(), r.variance_of_mean());
    let mut zs: Vec<(f64, usize, f64, f64)> = (0..ma.len() * 3)
        .map(|k| {
            let (i, c) = (k / 3, k % 3);
            let (a, b) = (ma[i][c] as f64, mb[i][c] as f64);
            let v = va[i][c] as f64 + vb[i][c] as f64;
            ((a - b) / v.sqrt().max(1e-30), k, a, b)
        })
        .collect();
    zs.sort_by(|a, b| b.0.abs().partial_cmp(&a.0.abs()).unwrap());
    let ta: f64 = ma.iter().flatten().map(|&x| x as f64).sum();
    let tb: f64 = mb.iter().flatten().map(|&x| x as f64).sum();
    eprint!("{label}: mean ratio {:.4} global z {:.2} |", ta / tb, common::global_z(img, r));
    for (z, i, a, b) in zs.iter().take(5) {
        eprint!(" ({},{}){} z{:.1} r{:.3}", (i / 3) % RES as usize, (i / 3) / RES as usize, ["r", "g", "b"][i % 3], z, a / b);
    }
    eprintln!();
    for px in std::env::var("ZZ_PIX").unwrap_or_default().split(';').filter(|s| !s.is_empty()) {
        let (x, y) = px.split_once(',').unwrap();
        let i = y.parse::<usize>().unwrap() * RES as usize + x.parse::<usize>().unwrap();
        for c in 0..3 {
            let (a, b) = (ma[i][c] as f64, mb[i][c] as f64);
            let v = va[i][c] as f64 + vb[i][c] as f64;
            eprint!("  ({px}){} z{:.2} r{:.3}", ["r", "g", "b"][c], (a - b) / v.sqrt(), a / b);
        }
        eprintln!();
    }
}

fn variant(src: &str) -> World {
    let dir = std::path::Path::new("tests/scenes/materials");
    World::build(common::xml(src, dir).unwrap()).unwrap()
}

#[test]
fn scratch() {
    let path = std::env::var("ZZ_SCENE").unwrap_or("tests/scenes/materials/every-material.xml".into());
    let src = std::fs::read_to_string(&path).unwrap();
    let w = variant(&src);
    let o = cf_test_opts();
    let ptb = Method::Pt.preprocess(&w, &o, 17).unwrap();
    let npt: u64 = std::env::var("ZZ_PT").map(|s| s.parse().unwrap()).unwrap_or(16384);
    let nm: u64 = std::env::var("ZZ_N").map(|s| s.parse().unwrap()).unwrap_or(4096);
    let reference = render(&w, Method::Pt.build(&w, &o, &ptb).unwrap().as_mut(), RES, RES, npt, 11);
    let which = std::env::var("ZZ_WHICH").unwrap_or("bsdf-b,cf".into());
    for k in which.split(',') {
        let (k, seed) = k.split_once(':').map(|(a, b)| (a, b.parse::<u64>().unwrap())).unwrap_or((k, 3));
        let img = match k {
            "bsdf-b" => render(&w, &mut Iws::new(&w, &o, Box::new(BsdfCaustics)), RES, RES, nm, seed),
            "bsdf-0" => {
                let mut o2 = o.clone();
                o2.iws.bound = Some(0.0);
                render(&w, &mut Iws::new(&w, &o2, Box::new(BsdfCaustics)), RES, RES, nm, seed)
            }
            "bsdf-inf" => {
                let mut o2 = o.clone();
                o2.iws.bound = Some(f32::INFINITY);
                render(&w, &mut Iws::new(&w, &o2, Box::new(BsdfCaustics)), RES, RES, nm, seed)
            }
            "cf" => {
                let b = Method::IwsCf.preprocess(&w, &o, 17).unwrap();
                render(&w, Method::IwsCf.build(&w, &o, &b).unwrap().as_mut(), RES, RES, nm, seed)
            }
            "pt" => render(&w, Method::Pt.build(&w, &o, &ptb).unwrap().as_mut(), RES, RES, nm, seed),
            "ptcf" => {
                let b = Method::PtCf.preprocess(&w, &o, 17).unwrap();
                render(&w, Method::PtCf.build(&w, &o, &b).unwrap().as_mut(), RES, RES, nm, seed)
            }
            _ => panic!("{k}"),
        };
        report(k, &img, &reference);
    }
}
