//! The loaded parts → `Scene`, by the TOML loader's rules (emitters: emissive triangles in order,
//! then emissive spheres; lights: area emitters then point lights, picked ∝ power), and the
//! `forecast_*` `<default>` values (render method, seed, time, photons, target box, ROIs).

use super::shapes::ShapeOut;
use super::xml::Node;
use super::Cx;
use crate::math::{Vec3, PI};
use crate::sampling::distribution::Distribution1D;
use crate::scene::{
    light_power, Camera, Emitter, LightRef, PointLight, RenderDefaults, Roi, Scene, SceneError, Sphere, Triangle,
};
use std::collections::BTreeMap;

/// forecast's own options (no Mitsuba equivalent).
pub(super) struct Extras {
    rois: Vec<Roi>,
    target: Option<(Vec3, Vec3)>,
    photons: Option<u64>,
}

/// Reads the `forecast_*` defaults into `render` and `Extras`.
pub(super) fn forecast_defaults(
    cx: &Cx,
    root: &Node,
    vars: &BTreeMap<String, String>,
    render: &mut RenderDefaults,
    camera: &Camera,
) -> Result<Extras, SceneError> {
    let line = |k: &str| root.children.iter().find(|c| c.tag == "default" && c.name() == k).map_or(0, |c| c.line);
    let bad = |k: &str, m: String| cx.err(line(k), k, m);
    let mut ex = Extras { rois: Vec::new(), target: None, photons: None };
    let mut rois: Vec<(u64, Roi)> = Vec::new();
    for (k, v) in vars.iter().filter(|(k, _)| k.starts_with("forecast_")) {
        let num = |v: &str| v.trim().parse::<u64>().map_err(|_| bad(k, format!("`{v}` is not a non-negative integer")));
        match k.as_str() {
            "forecast_method" => {
                if !crate::scene::is_method_name(v) {
                    let all = crate::scene::METHOD_NAMES.join(", ");
                    return Err(bad(k, format!("unknown method `{v}` ({}, {all})", crate::scene::AUTO_METHOD)));
                }
                render.method = v.clone();
            }
            "forecast_seed" => render.seed = num(v)?,
            "forecast_time" => render.time = Some(crate::scene::parse_duration(v).map_err(|m| bad(k, m))?),
            "forecast_photons" => {
                let n = num(v)?;
                crate::param_limits::FORECAST_PHOTONS.check(n).map_err(|m| bad(k, m))?;
                ex.photons = Some(n);
            }
            "forecast_target_box" => match super::params::numbers(v).as_deref() {
                Some([a, b, c, d, e, f]) if a <= d && b <= e && c <= f => {
                    ex.target = Some((Vec3::new(*a, *b, *c), Vec3::new(*d, *e, *f)))
                }
                _ => return Err(bad(k, format!("`{v}`: expected six numbers, min then max"))),
            },
            _ if k.strip_prefix("forecast_roi_").is_some_and(|i| i.parse::<u64>().is_ok()) => {
                let mut it = v.split_whitespace();
                let r: Vec<u32> = it.by_ref().take(4).filter_map(|t| t.parse().ok()).collect();
                let name = it.collect::<Vec<_>>().join(" ");
                match r[..] {
                    [x, y, w, h]
                        if w > 0
                            && h > 0
                            && x.checked_add(w).is_some_and(|e| e <= camera.width)
                            && y.checked_add(h).is_some_and(|e| e <= camera.height) =>
                    {
                        let i: u64 = k["forecast_roi_".len()..].parse().unwrap_or(0);
                        rois.push((i, Roi { name, rect: [x, y, w, h] }))
                    }
                    _ => return Err(bad(k, format!("`{v}`: expected `x y w h name` inside the image"))),
                }
            }
            _ => return Err(bad(k, format!("unknown forecast option `{k}`"))),
        }
    }
    // ROIs in their index order (forecast_roi_0, _1, ...; the map orders `_10` before `_2`)
    rois.sort_by_key(|r| r.0);
    ex.rois = rois.into_iter().map(|r| r.1).collect();
    Ok(ex)
}

/// Builds the scene.
pub(super) fn assemble(
    cx: Cx,
    camera: Camera,
    render: RenderDefaults,
    shapes: Vec<ShapeOut>,
    point_lights: Vec<PointLight>,
    ex: Extras,
) -> Result<Scene, SceneError> {
    let mut triangles = Vec::new();
    let mut spheres = Vec::new();
    let mut tri_e = Vec::new();
    let mut sph_e = Vec::new();
    for s in shapes {
        tri_e.extend(std::iter::repeat_n(s.emission, s.tris.len()));
        triangles.extend(s.tris);
        if let Some(sp) = s.sphere {
            spheres.push(sp);
            sph_e.push(s.emission);
        }
    }
    if triangles.is_empty() && spheres.is_empty() {
        return Err(cx.err(1, "shape", "empty scene: no shapes"));
    }
    let mut emitters = Vec::new();
    for (i, e) in tri_e.iter().enumerate() {
        if let Some(le) = e {
            triangles[i].emitter = emitters.len() as u32;
            emitters.push(Emitter { prim: i as u32, radiance: *le, area: triangles[i].area });
        }
    }
    let ntri = triangles.len() as u32;
    for (i, e) in sph_e.iter().enumerate() {
        if let Some(le) = e {
            spheres[i].emitter = emitters.len() as u32;
            let r = spheres[i].radius;
            emitters.push(Emitter { prim: ntri + i as u32, radiance: *le, area: 4.0 * PI * r * r });
        }
    }
    let mut lights: Vec<LightRef> = (0..emitters.len() as u32).map(LightRef::Area).collect();
    lights.extend((0..point_lights.len() as u32).map(LightRef::Point));
    let powers: Vec<f32> = lights.iter().map(|&l| light_power(&emitters, &point_lights, l)).collect();
    if let Some(i) = powers.iter().position(|p| !p.is_finite()) {
        return Err(cx.err(
            0,
            "emitter",
            format!("light {i}'s power overflows f32 (radiance × area or intensity too large)"),
        ));
    }
    let light_pick = Distribution1D::new(&powers).ok_or_else(|| {
        cx.err(1, "emitter", "the scene has no light with positive power (an `area` or `point` emitter)")
    })?;
    let bounds = bounds(&triangles, &spheres);
    Ok(Scene {
        path: cx.file,
        hash: cx.hash,
        camera,
        render,
        materials: cx.materials,
        triangles,
        spheres,
        emitters,
        point_lights,
        lights,
        light_pick,
        rois: ex.rois,
        forecast_target: ex.target,
        forecast_photons: ex.photons,
        bounds,
        warnings: cx.warnings,
    })
}

/// Scene bounds (min, max) over triangles and spheres.
fn bounds(triangles: &[Triangle], spheres: &[Sphere]) -> (Vec3, Vec3) {
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for t in triangles {
        for p in t.p {
            lo = lo.min(p);
            hi = hi.max(p);
        }
    }
    for s in spheres {
        lo = lo.min(s.center - Vec3::splat(s.radius));
        hi = hi.max(s.center + Vec3::splat(s.radius));
    }
    (lo, hi)
}
