//! Tests of `pt_cf::light`: the light side's splats, MIS weights and class C against the camera
//! side on a glass ball over a floor, and the reciprocity of Dirac vertices under a normal map.

use super::*;
use crate::integrators::iws_cf::targeted_emission;
use std::path::Path;

/// A glass ball over a diffuse floor, a glossy back wall (`tests/scenes/glass-ball`), with a
/// 0.2 m light and 32×24 pixels.
fn scene_src() -> String {
    let geometry = include_str!("../../../tests/scenes/glass-ball/geometry.toml");
    let src = geometry.replace("resolution = [12, 12]", "resolution = [32, 24]").replace(
        "corner = [-0.3, 2.0, -0.3]\nu = [0.6, 0.0, 0.0]\nv = [0.0, 0.0, 0.6]",
        "corner = [-0.1, 2.0, -0.1]\nu = [0.2, 0.0, 0.0]\nv = [0.0, 0.0, 0.2]",
    );
    assert!(src.contains("[32, 24]") && src.contains("[0.2, 0.0, 0.0]"), "glass-ball/geometry.toml changed");
    src + include_str!("../../../tests/scenes/glass-ball/plain.toml")
}

fn hit_along(world: &World, o: Vec3, d: Vec3) -> Hit {
    world.intersect(o, d.normalize(), f32::INFINITY).expect("a hit")
}

fn point(h: &Hit) -> ShadingPoint {
    ShadingPoint::new(h.p, h.ng, h.ns)
}

/// For enumerated paths of C with one and with two non-Dirac vertices, `w_E` computed along
/// the camera path (`first_ratio`, `next_ratio`, `camera_weight`) and `w_L` computed along
/// the light path (`light_weight`, with the light side's own pdfs and cosines) sum to 1 to
/// f32 rounding; and neither is trivial (both in (0.001, 0.999) on some path).
#[test]
fn camera_and_light_weights_sum_to_one() {
    // few light paths, so that both techniques matter on these paths (r ≈ 0.1 … 10)
    const N_L: u64 = 2;
    let s = crate::scene::load_str(&scene_src(), "mis.toml", Path::new(".")).unwrap();
    let world = World::build(s).unwrap();
    let cam = world.scene.camera.clone();
    let light = LightSide { paths: Some(N_L), emission: targeted_emission(&world), max_depth: 64 };
    let mut q = |sp: &ShadingPoint, m: &Material, (wo, wi): (Vec3, Vec3), _d: u32| bsdf::pdf_w(m, sp, wo, wi);
    let (mut checked, mut checked2, mut mixed) = (0, 0, 0);
    for (px, py) in [(16.5, 20.5), (10.2, 21.7), (22.0, 19.1), (16.0, 6.0), (5.5, 9.5), (27.0, 3.0)] {
        let d0 = cam.direction(px, py);
        let h1 = hit_along(&world, cam.position, d0);
        let (m1, sp1, wo1) = (world.scene.material_of(h1.prim), point(&h1), -d0);
        // the chain's end: from the glass ball to a point of the light
        for (k, y) in [Vec3::new(0.03, 2.0, 0.05), Vec3::new(-0.08, 2.0, -0.02)].into_iter().enumerate() {
            let from = Vec3::new(0.1 * k as f32, 0.95, 0.05); // just above the ball
            let hy = hit_along(&world, from, y - from);
            let d = (hy.p - from).normalize();
            assert!(world.scene.emitter_of(hy.prim) != NO_EMITTER);
            // one non-Dirac vertex: x1 → chain
            let wi1 = (Vec3::new(0.05, 0.5, 0.0) - h1.p).normalize();
            let q1 = bsdf::pdf_w(m1, &sp1, wo1, wi1);
            let w_e = camera_weight(&world, &light, &cam, &hy, d, first_ratio(&cam, d0, h1.t, h1.ng, (wo1, wi1), q1));
            let dist2 = (cam.position - h1.p).length_squared();
            let p0 = light_start_density(&world, &light, 1, &hy, d) * dist2 / pinhole_importance(&cam, d0);
            let w_l = light_weight(N_L, &[], (&sp1, m1), (wo1, wi1), p0, &mut q);
            assert!((w_e + w_l - 1.0).abs() < 1e-5, "one vertex: w_E {w_e} + w_L {w_l}");
            checked += 1;
            mixed += (w_l > 1e-3 && w_l < 0.999) as u32;
            // two non-Dirac vertices: x1 → x2 (a point on the glossy wall) → chain
            // x2 on the wall (x1 on the floor) or on the floor (x1 on the wall), clear of the ball
            let on_floor = h1.p.y.abs() < 1e-4;
            let x2 = if on_floor {
                Vec3::new(1.5 - 3.0 * k as f32, 0.3, -1.0)
            } else {
                Vec3::new(1.5 - 3.0 * k as f32, 0.0, 0.8)
            };
            let x1_to_wall = x2 - h1.p;
            let h2 = hit_along(&world, offset_origin(h1.p, h1.ng, x1_to_wall.normalize()), x1_to_wall);
            let (m2, sp2) = (world.scene.material_of(h2.prim), point(&h2));
            if m2.is_dirac() {
                continue; // the ball is in the way
            }
            let (wi1, wo2) = (x1_to_wall.normalize(), -x1_to_wall.normalize());
            let wi2 = (Vec3::new(0.0, 0.55, 0.1) - h2.p).normalize();
            let (q1, q2) = (bsdf::pdf_w(m1, &sp1, wo1, wi1), bsdf::pdf_w(m2, &sp2, wo2, wi2));
            let ratio = first_ratio(&cam, d0, h1.t, h1.ng, (wo1, wi1), q1) * next_ratio(m2, &sp2, (wo2, wi2), q2);
            let w_e = camera_weight(&world, &light, &cam, &hy, d, ratio);
            let v = Vertex { sp: sp2, m: *m2, w_in: wi2, w_out: wo2, pdf_l: bsdf::pdf_w(m2, &sp2, wi2, wo2) };
            let w_l = light_weight(N_L, &[v], (&sp1, m1), (wo1, wi1), p0, &mut q);
            assert!((w_e + w_l - 1.0).abs() < 1e-5, "two vertices: w_E {w_e} + w_L {w_l} ({:?})", h2.p);
            checked2 += 1;
            mixed += (w_l > 1e-3 && w_l < 0.999) as u32;
        }
    }
    eprintln!("{checked} one-vertex and {checked2} two-vertex paths, {mixed} with 0 < w_L < 1");
    assert!(checked == 12 && checked2 >= 6, "{checked} {checked2}");
    assert!(mixed > 0, "every weight was 0 or 1: the test has no power");
}

/// A glass ball under a normal map (its normal flips with the direction it is seen from):
/// `reciprocal` is symmetric in its two directions; where it holds, the camera side's Dirac
/// sample from the light side's sampled direction returns the light side's incoming one (the
/// same lobe), so both sides draw the same paths; and it fails on some pairs, where the
/// reverse sample goes elsewhere (the transport `pt` does not have, which the light side
/// carried before `reciprocal`: `results/2026-12-07-light-side-bias.md` §3).
#[test]
fn dirac_vertices_of_class_c_are_reciprocal_under_a_normal_map() {
    const BALL: &str = r#"
[camera]
position = [0.0, 1.0, 3.0]
look_at = [0.0, 0.0, 0.0]
fov = 40.0
resolution = [8, 8]
[materials.glass]
type = "glass"
ior = 1.5
normalmap = "../mitsuba-plugins/normals32.png"
[[shape]]
type = "sphere"
center = [0.0, 0.0, 0.0]
radius = 0.4
material = "glass"
[[shape]]
type = "quad"
corner = [-0.3, 2.0, -0.3]
u = [0.6, 0.0, 0.0]
v = [0.0, 0.0, 0.6]
emission = [5.0, 5.0, 5.0]
"#;
    let dir = Path::new("tests/scenes/toml-materials");
    let world = World::build(crate::scene::load_str(BALL, "ball.toml", dir).unwrap()).unwrap();
    let mut rng = Rng::keyed(7, 0, 0, 0);
    let (mut same, mut other) = (0, 0);
    for _ in 0..20_000 {
        // from a point around the ball toward a point on it: a light path's incoming ray
        let o = crate::sampling::warp::sample_uniform_sphere(rng.next_2d()) * 2.0;
        let t = crate::sampling::warp::sample_uniform_sphere(rng.next_2d()) * 0.39;
        let Some(hit) = world.intersect(o, (t - o).normalize(), f32::INFINITY) else { continue };
        let a = (o - hit.p).normalize();
        let (m, sp) = world.shade(&hit, a);
        // u = 0: reflection (F > 0); u just below 1: refraction where F < 1
        for u0 in [0.0f32, 0.999_99] {
            let Some(bs) = bsdf::sample(&m, &sp, a, [u0, 0.5, 0.5], Mode::Importance) else { continue };
            let b = bs.wi;
            let (m2, sp2) = world.shade(&hit, b);
            let r = reciprocal(&world, &hit, &sp, b);
            assert_eq!(r, reciprocal(&world, &hit, &sp2, a), "not symmetric at {:?}", hit.p);
            let back = bsdf::sample(&m2, &sp2, b, [u0, 0.5, 0.5], Mode::Radiance).map(|s| s.wi.dot(a));
            if r {
                assert!(back.is_some_and(|c| c > 1.0 - 1e-4), "reciprocal pair not retraced: {back:?}");
                same += 1;
            } else {
                other += back.is_none_or(|c| c < 1.0 - 1e-3) as u32;
            }
        }
    }
    eprintln!("{same} reciprocal Dirac samples, {other} whose reverse goes elsewhere");
    assert!(same > 10_000 && other > 0, "{same} {other}: the test has no power");
}

/// The pinhole's density per pixel sample.
#[test]
fn pixel_importance_is_the_camera_density() {
    // ∫ over a pixel of 1/(A_pix cos³θ) dω = 1 for every pixel: the pixel split into 16 × 16
    // sub-pixels, each's solid angle ≈ |(c − a) × (e − a)| of its corner directions (unit
    // vectors). At the corners (θ ≈ 24°) cos⁴ in place of cos³ gives 1.16.
    let cam = Camera::new(Vec3::ZERO, Vec3::new(0.0, 0.0, -1.0), Vec3::Y, 40.0, 64, 48);
    for (px, py) in [(32.0f32, 24.0f32), (0.0, 0.0), (63.0, 47.0), (0.0, 24.0), (40.0, 3.0)] {
        let mut sum = 0.0f64;
        for (i, j) in (0..16).flat_map(|i| (0..16).map(move |j| (i as f32 / 16.0, j as f32 / 16.0))) {
            let (x, y, h) = (px + i, py + j, 1.0 / 16.0);
            let (a, b) = (cam.direction(x, y), cam.direction(x + h, y + h));
            let (c, e) = (cam.direction(x + h, y), cam.direction(x, y + h));
            sum += (pinhole_importance(&cam, (a + b).normalize()) * (c - a).cross(e - a).length()) as f64;
        }
        assert!((sum - 1.0).abs() < 1e-3, "pixel ({px}, {py}): {sum}");
    }
}
