//! forecast's own render options in a Mitsuba scene, which Mitsuba has no place for: the
//! `forecast_*` `<default>` values (render method, seed, time, photons, target box, ROIs) →
//! the builder's checked setters (the same limits and words as the TOML `[render]` and
//! `[forecast]` tables).

use super::xml::Node;
use super::Cx;
use crate::math::Vec3;
use crate::scene::spec::Origin;
use crate::scene::SceneError;
use std::collections::BTreeMap;

/// Reads the `forecast_*` defaults into the builder (after the sensor: ROIs need the image size).
pub(super) fn forecast_defaults(cx: &mut Cx, root: &Node, vars: &BTreeMap<String, String>) -> Result<(), SceneError> {
    let line = |k: &str| root.children.iter().find(|c| c.tag == "default" && c.name() == k).map_or(0, |c| c.line);
    let mut rois: Vec<(u64, String, [u32; 4], Origin)> = Vec::new();
    for (k, v) in vars.iter().filter(|(k, _)| k.starts_with("forecast_")) {
        let at = Origin::new(line(k), k.as_str());
        let num = |v: &str| {
            v.trim().parse::<u64>().map_err(|_| cx.b.err(&at, format!("`{v}` is not a non-negative integer")))
        };
        match k.as_str() {
            "forecast_method" => cx.b.method(v, &at)?,
            "forecast_seed" => cx.b.render.seed = num(v)?,
            "forecast_time" => cx.b.time(v, &at)?,
            "forecast_photons" => {
                let n = num(v)?;
                cx.b.forecast_photons(n, &at)?
            }
            "forecast_target_box" => match super::params::numbers(v).as_deref() {
                Some([a, b, c, d, e, f]) => cx.b.forecast_target(Vec3::new(*a, *b, *c), Vec3::new(*d, *e, *f), &at)?,
                _ => return Err(cx.b.err(&at, format!("`{v}`: expected six numbers, min then max"))),
            },
            _ if k.strip_prefix("forecast_roi_").is_some_and(|i| i.parse::<u64>().is_ok()) => {
                let mut it = v.split_whitespace();
                let r: Vec<u32> = it.by_ref().take(4).filter_map(|t| t.parse().ok()).collect();
                let name = it.collect::<Vec<_>>().join(" ");
                let [x, y, w, h] = r[..] else {
                    return Err(cx.b.err(&at, format!("`{v}`: expected `x y w h name` inside the image")));
                };
                let i: u64 = k["forecast_roi_".len()..].parse().unwrap_or(0);
                rois.push((i, name, [x, y, w, h], at));
            }
            _ => return Err(cx.b.err(&at, format!("unknown forecast option `{k}`"))),
        }
    }
    // ROIs in their index order (forecast_roi_0, _1, ...; the map orders `_10` before `_2`)
    rois.sort_by_key(|r| r.0);
    for (_, name, rect, at) in rois {
        cx.b.roi((name, &at), (rect, &at))?;
    }
    Ok(())
}
