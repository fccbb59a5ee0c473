//! Mitsuba's top-level emitter plugins → the builder's lights: `point` (`position` or
//! `to_world`, `intensity`), `spot` (`to_world`, `intensity`, `cutoff_angle` default 20°,
//! `beam_width` default ¾ of it), `directional` (`direction` or `to_world`, `irradiance`),
//! `constant` (`radiance`) and `envmap` (`filename` of an EXR or Radiance HDR image, `scale`,
//! `to_world`). The formulas are `scene::emitters`'; this file reads the parameters and checks
//! them, each error naming the file, the line and the key.
//!
//! Invariants: the transforms of `spot` and `envmap` must be rotations (and a translation; a
//! uniform scale for `spot`), as their directions are read through them; an envmap's image is
//! at least 2×3 texels, every texel finite, non-negative and at most `MAX_RADIANCE` after
//! `scale`, and its texels enter the scene's hash; `constant`'s radiance is a uniform
//! `<spectrum>` by Mitsuba's RGB rule like every emitter's (`Plugin::emission`).

use super::params::{Plugin, Xform};
use super::xml::Node;
use super::Cx;
use crate::math::{Mat3, Rgb, Vec3};
use crate::scene::limits::MAX_RADIANCE;
use crate::scene::spec::Origin;
use crate::scene::{Environment, LatLong, SceneError, Spot};

/// A top-level `<emitter>`.
pub(super) fn emitter(cx: &mut Cx, n: &Node) -> Result<(), SceneError> {
    match n.ty() {
        "point" | "spot" => point(cx, n),
        "directional" => directional(cx, n),
        "constant" | "envmap" => environment(cx, n),
        t => {
            let msg = format!(
                "emitter `{t}` is not supported (`point`, `spot`, `directional`, `constant`, `envmap` at the top \
                 level, `area` inside shapes)"
            );
            Err(cx.err(n.line, &format!("emitter.{t}"), msg))
        }
    }
}

/// The linear part of `x` as a rotation times a uniform scale: `(R, scale)`, or `None` when it
/// shears or scales unevenly.
fn rotation(x: &Xform) -> Option<(Mat3, f32)> {
    let m = x.m.as_mat4();
    let cols = [m.x_axis.truncate(), m.y_axis.truncate(), m.z_axis.truncate()];
    let s = cols[0].length();
    let ok = s > 0.0
        && cols.iter().all(|c| (c.length() - s).abs() <= 1e-4 * s)
        && cols[0].dot(cols[1]).abs() <= 1e-4 * s * s
        && cols[0].dot(cols[2]).abs() <= 1e-4 * s * s
        && cols[1].dot(cols[2]).abs() <= 1e-4 * s * s;
    ok.then(|| (Mat3::from_cols(cols[0] / s, cols[1] / s, cols[2] / s), s))
}

/// `point` and `spot`.
fn point(cx: &mut Cx, n: &Node) -> Result<(), SceneError> {
    let ty = n.ty().to_string();
    let mut p = Plugin::new(n);
    let (pl, xl, il) = (p.line_of("position"), p.line_of("to_world"), p.line_of("intensity"));
    let pos = if ty == "point" { p.point(cx, "position")?.map(Vec3::from_array) } else { None };
    let xf = p.transform(cx, "to_world")?;
    let (position, pat) = match (pos, &xf) {
        (Some(q), _) => (q, Origin::new(pl, format!("{ty}.position"))),
        (None, Some(x)) => (x.m.w_axis.truncate().as_vec3(), Origin::new(xl, format!("{ty}.to_world"))),
        (None, None) => (Vec3::ZERO, Origin::new(n.line, format!("{ty}.position"))),
    };
    let intensity = p.emission(cx, "intensity")?.unwrap_or(Vec3::ONE);
    let spot = if ty == "spot" {
        let (cl, bl) = (p.line_of("cutoff_angle"), p.line_of("beam_width"));
        let cutoff = p.float(cx, "cutoff_angle")?.unwrap_or(20.0);
        let beam = p.float(cx, "beam_width")?.unwrap_or(cutoff * 0.75);
        let (r, _) = match &xf {
            None => (Mat3::IDENTITY, 1.0),
            Some(x) => rotation(x).ok_or_else(|| {
                p.err(cx, xl, "to_world", "a spot's transform must be a rotation, a uniform scale and a translation")
            })?,
        };
        let s = Spot::new(r.z_axis, r.x_axis, cutoff, beam).map_err(|(key, m)| {
            let line = if key == "cutoff_angle" { cl } else { bl };
            p.err(cx, line, key, m)
        })?;
        Some(s)
    } else {
        None
    };
    cx.b.point_light((position, &pat), (intensity, &Origin::new(il, format!("{ty}.intensity"))), spot)?;
    p.finish(cx);
    Ok(())
}

/// `directional`: light travels along `direction`, or `to_world·(0,0,1)` (default +z).
fn directional(cx: &mut Cx, n: &Node) -> Result<(), SceneError> {
    let mut p = Plugin::new(n);
    let (dl, xl, il) = (p.line_of("direction"), p.line_of("to_world"), p.line_of("irradiance"));
    let dir = p.point(cx, "direction")?.map(Vec3::from_array);
    let xf = p.transform(cx, "to_world")?;
    let (d, dat) = match (dir, xf) {
        (Some(_), Some(_)) => {
            return Err(p.err(cx, xl, "to_world", "give `direction` or `to_world`, not both (as Mitsuba)"));
        }
        (Some(d), None) => (d, Origin::new(dl, "directional.direction")),
        (None, Some(x)) => (x.m.z_axis.truncate().as_vec3(), Origin::new(xl, "directional.to_world")),
        (None, None) => (Vec3::Z, Origin::new(n.line, "directional.direction")),
    };
    let irradiance = p.emission(cx, "irradiance")?.unwrap_or(Vec3::ONE);
    cx.b.directional_light((d, &dat), (irradiance, &Origin::new(il, "directional.irradiance")))?;
    p.finish(cx);
    Ok(())
}

/// `constant` and `envmap`.
fn environment(cx: &mut Cx, n: &Node) -> Result<(), SceneError> {
    let ty = n.ty().to_string();
    let mut p = Plugin::new(n);
    let at = Origin::new(n.line, format!("emitter.{ty}"));
    let env = if ty == "constant" {
        let rl = p.line_of("radiance");
        let l = p.emission(cx, "radiance")?.unwrap_or(Vec3::ONE);
        if let Some(m) = crate::scene::limits::light_value_error("radiance", l, MAX_RADIANCE) {
            return Err(p.err(cx, rl, "radiance", m));
        }
        Environment::constant(l)
    } else {
        envmap(cx, &mut p)?
    };
    cx.b.environment(env, &at)?;
    p.finish(cx);
    Ok(())
}

fn envmap(cx: &mut Cx, p: &mut Plugin) -> Result<Environment, SceneError> {
    let line = p.node.line;
    let (sl, xl) = (p.line_of("scale"), p.line_of("to_world"));
    let Some((f, fl)) = p.string(cx, "filename")? else {
        return Err(p.err(cx, line, "filename", "missing `filename`"));
    };
    let scale = p.float(cx, "scale")?.unwrap_or(1.0);
    if !(scale.is_finite() && scale >= 0.0) {
        return Err(p.err(cx, sl, "scale", format!("scale {scale}: must be finite and non-negative")));
    }
    let r = match p.transform(cx, "to_world")? {
        None => Mat3::IDENTITY,
        Some(x) => match rotation(&x) {
            Some((r, s)) if (s - 1.0).abs() <= 1e-4 => r,
            _ => return Err(p.err(cx, xl, "to_world", "an envmap's transform must be a rotation")),
        },
    };
    p.reject(cx, &["bitmap", "mis_compensation"], "an envmap reads its `filename`, sampled by its luminance")?;
    let path = cx.dir.join(&f);
    let bad = |m: String| p.err(cx, fl, "filename", format!("{}: {m}", path.display()));
    let img = crate::image_io::decode_texture(&path).map_err(|e| p.err(cx, fl, "filename", e.to_string()))?;
    if img.data.is_integer() {
        return Err(bad(format!(
            "a {} image; an environment map must be OpenEXR or Radiance HDR (linear)",
            img.format
        )));
    }
    let mut texels = Vec::with_capacity(img.width * img.height);
    for y in 0..img.height {
        for x in 0..img.width {
            let t = Rgb::from_array(img.texel(x, y).unwrap_or_default()) * scale;
            if !(t.is_finite() && t.min_element() >= 0.0 && t.max_element() <= MAX_RADIANCE) {
                return Err(bad(format!(
                    "texel ({x}, {y}) × scale is {t}: must be finite, non-negative and at most {MAX_RADIANCE:e} per channel"
                )));
            }
            texels.push(t);
        }
    }
    // the texels enter the scene's hash (a changed map is another scene for `--resume`)
    let bytes: Vec<u8> = texels.iter().flat_map(|t| t.to_array()).flat_map(f32::to_le_bytes).collect();
    let map = LatLong::new(img.width, img.height, texels).map_err(bad)?;
    cx.b.mesh_file(&path, crate::math::fnv1a(0xcbf2_9ce4_8422_2325, &bytes));
    Ok(Environment::lat_long(map, r))
}
