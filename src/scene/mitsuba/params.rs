//! Typed access to a Mitsuba plugin's parameters (`<float>`, `<rgb>`, `<transform>`, ...), with
//! every parameter that was not read reported as ignored, with its line; and `to_world`
//! transforms composed in Mitsuba's order (each listed operation applied after the previous
//! ones: M = opₙ ··· op₁).
//!
//! Invariants: a parameter of the wrong kind or with unparsable numbers is an error naming the
//! file, line, plugin and parameter; textures in place of colours are errors.

use super::xml::Node;
use super::Cx;
use crate::math::Rgb;
use crate::scene::SceneError;
use glam::{DMat4, DVec3, DVec4};

/// The (origin, target, up) of a `lookat`.
pub(super) type LookAt = [[f32; 3]; 3];

/// A `to_world` transform: the matrix, and the `lookat` operands when it is exactly one `lookat`
/// (the camera uses them directly, bit-exact with the TOML camera).
pub(super) struct Xform {
    /// Composed matrix.
    pub m: DMat4,
    /// (origin, target, up) of a lone `lookat`, as f32.
    pub lookat: Option<LookAt>,
}

/// One plugin element and which of its children have been read.
pub(super) struct Plugin<'a> {
    /// The element.
    pub node: &'a Node,
    used: Vec<bool>,
}

/// Numbers separated by commas and/or whitespace.
pub(super) fn numbers(s: &str) -> Option<Vec<f32>> {
    s.split(|c: char| c == ',' || c.is_whitespace()).filter(|t| !t.is_empty()).map(|t| t.parse::<f32>().ok()).collect()
}

impl<'a> Plugin<'a> {
    /// Wraps an element.
    pub fn new(node: &'a Node) -> Self {
        Plugin { node, used: vec![false; node.children.len()] }
    }

    /// `bsdf `conductor`` (for messages).
    pub fn what(&self) -> String {
        format!("{} `{}`", self.node.tag, self.node.ty())
    }

    /// An error about parameter `param` at `line`.
    pub fn err(&self, cx: &Cx, line: usize, param: &str, msg: impl std::fmt::Display) -> SceneError {
        cx.err(line, &format!("{}.{param}", self.node.ty()), format!("{}: {msg}", self.what()))
    }

    /// The line of the child named `name` (the element's own line when it has none).
    pub fn line_of(&self, name: &str) -> usize {
        self.node.children.iter().find(|c| c.name() == name).map_or(self.node.line, |c| c.line)
    }

    /// The child element named `name` (marked read).
    pub fn find(&mut self, name: &str) -> Option<&'a Node> {
        let i = self.node.children.iter().position(|c| c.name() == name)?;
        self.used[i] = true;
        Some(&self.node.children[i])
    }

    /// Child objects with tag `tag` (`bsdf`, `emitter`, `film`, ...; `ref`s included), marked read.
    pub fn objects(&mut self, tags: &[&str]) -> Vec<&'a Node> {
        let mut out = Vec::new();
        for (i, c) in self.node.children.iter().enumerate() {
            if tags.contains(&c.tag.as_str()) {
                self.used[i] = true;
                out.push(c);
            }
        }
        out
    }

    fn value(&self, cx: &Cx, n: &'a Node) -> Result<&'a str, SceneError> {
        n.attr("value").ok_or_else(|| self.err(cx, n.line, n.name(), "missing `value`"))
    }

    /// A `<float>` (or `<integer>`) parameter.
    pub fn float(&mut self, cx: &Cx, name: &str) -> Result<Option<f32>, SceneError> {
        let Some(n) = self.find(name) else { return Ok(None) };
        if n.tag != "float" && n.tag != "integer" {
            return Err(self.err(cx, n.line, name, format!("expected `<float>`, got `<{}>`", n.tag)));
        }
        let v = self.value(cx, n)?;
        match v.trim().parse::<f32>() {
            Ok(x) if x.is_finite() => Ok(Some(x)),
            _ => Err(self.err(cx, n.line, name, format!("`{v}` is not a finite number"))),
        }
    }

    /// An `<integer>` parameter.
    pub fn int(&mut self, cx: &Cx, name: &str) -> Result<Option<i64>, SceneError> {
        let Some(n) = self.find(name) else { return Ok(None) };
        let v = self.value(cx, n)?;
        let t = v.trim();
        match (n.tag.as_str(), t.parse::<i64>()) {
            ("integer", Ok(x)) => Ok(Some(x)),
            ("integer", Err(_))
                if !t.is_empty() && t.trim_start_matches(['-', '+']).bytes().all(|c| c.is_ascii_digit()) =>
            {
                let msg = format!("`{t}` is out of range (an integer between {} and {})", i64::MIN, i64::MAX);
                Err(self.err(cx, n.line, name, msg))
            }
            ("integer", Err(_)) => Err(self.err(cx, n.line, name, format!("`{v}` is not an integer"))),
            _ => Err(self.err(cx, n.line, name, format!("expected `<integer>`, got `<{}>` `{v}`", n.tag))),
        }
    }

    /// A `<boolean>` parameter.
    pub fn boolean(&mut self, cx: &Cx, name: &str) -> Result<Option<bool>, SceneError> {
        let Some(n) = self.find(name) else { return Ok(None) };
        let v = self.value(cx, n)?;
        match (n.tag.as_str(), v.trim()) {
            ("boolean", "true") => Ok(Some(true)),
            ("boolean", "false") => Ok(Some(false)),
            _ => Err(self.err(cx, n.line, name, format!("expected `<boolean>` true/false, got `<{}>` `{v}`", n.tag))),
        }
    }

    /// A `<string>` parameter.
    pub fn string(&mut self, cx: &Cx, name: &str) -> Result<Option<(String, usize)>, SceneError> {
        let Some(n) = self.find(name) else { return Ok(None) };
        if n.tag != "string" {
            return Err(self.err(cx, n.line, name, format!("expected `<string>`, got `<{}>`", n.tag)));
        }
        Ok(Some((self.value(cx, n)?.to_string(), n.line)))
    }

    /// A constant colour: `<rgb>` (1 or 3 numbers), `<spectrum>` with one number, or `<float>`.
    pub fn color(&mut self, cx: &Cx, name: &str) -> Result<Option<Rgb>, SceneError> {
        let Some(n) = self.find(name) else { return Ok(None) };
        let bad = |m: String| self.err(cx, n.line, name, m);
        match n.tag.as_str() {
            "rgb" | "spectrum" | "float" => {
                let v = self.value(cx, n)?;
                if n.tag == "spectrum" && v.contains(':') {
                    return Err(bad("sampled spectra (`wavelength:value`) are not supported; use `<rgb>`".into()));
                }
                match numbers(v).as_deref() {
                    Some([x]) if x.is_finite() => Ok(Some(Rgb::splat(*x))),
                    Some([r, g, b]) if [r, g, b].iter().all(|x| x.is_finite()) => Ok(Some(Rgb::new(*r, *g, *b))),
                    _ => Err(bad(format!("`{v}` is not one or three finite numbers"))),
                }
            }
            "texture" | "ref" => Err(bad("textures are not supported (constant `<rgb>` only)".into())),
            t => Err(bad(format!("`<{t}>` is not supported for a colour (use `<rgb>`)"))),
        }
    }

    /// An emitter's colour (`radiance`, `intensity`): as [`Plugin::color`], except that a uniform
    /// `<spectrum value="v"/>` is Mitsuba 3's equal-energy spectrum in its RGB variants,
    /// v·`UNIFORM_EMISSION_RGB` (docs/mitsuba.md, the SMS ring). A uniform spectrum of a BSDF,
    /// `<rgb>` and `<float>` stay as written, as in Mitsuba.
    pub fn emission(&mut self, cx: &Cx, name: &str) -> Result<Option<Rgb>, SceneError> {
        let uniform = self.find(name).is_some_and(|n| n.tag == "spectrum");
        let e = Rgb::from_array(super::presets::UNIFORM_EMISSION_RGB);
        Ok(self.color(cx, name)?.map(|c| if uniform { c * e } else { c }))
    }

    /// A `<point>`/`<vector>` parameter (`x`, `y`, `z` or `value`).
    pub fn point(&mut self, cx: &Cx, name: &str) -> Result<Option<[f32; 3]>, SceneError> {
        let Some(n) = self.find(name) else { return Ok(None) };
        if n.tag != "point" && n.tag != "vector" {
            return Err(self.err(cx, n.line, name, format!("expected `<point>`, got `<{}>`", n.tag)));
        }
        xyz(n, 0.0).map(Some).map_err(|m| self.err(cx, n.line, name, m))
    }

    /// A `<transform>` parameter.
    pub fn transform(&mut self, cx: &Cx, name: &str) -> Result<Option<Xform>, SceneError> {
        let Some(n) = self.find(name) else { return Ok(None) };
        if n.tag != "transform" {
            return Err(self.err(cx, n.line, name, format!("expected `<transform>`, got `<{}>`", n.tag)));
        }
        let mut m = DMat4::IDENTITY;
        let mut lookat = None;
        for op in &n.children {
            let (step, l) = op_matrix(op, n.children.len() == 1)
                .map_err(|msg| self.err(cx, op.line, &format!("{name}.{}", op.tag), msg))?;
            lookat = lookat.or(l);
            m = step * m;
        }
        if !m.is_finite() {
            return Err(self.err(cx, n.line, name, "the transform is not finite"));
        }
        if m.row(3) != DVec4::W {
            let msg = format!(
                "the transform's last row is {:?}, not [0, 0, 0, 1]: projective transforms are not supported",
                m.row(3).to_array()
            );
            return Err(self.err(cx, n.line, name, msg));
        }
        Ok(Some(Xform { m, lookat }))
    }

    /// Errors for parameters that would change the image and are not supported.
    pub fn reject(&mut self, cx: &Cx, names: &[&str], why: &str) -> Result<(), SceneError> {
        for &name in names {
            if let Some(n) = self.find(name) {
                return Err(self.err(cx, n.line, name, format!("parameter `{name}` is not supported ({why})")));
            }
        }
        Ok(())
    }

    /// Warns about every child that was not read (unknown or ignored parameters).
    pub fn finish(self, cx: &mut Cx) {
        let kids = &self.node.children;
        for (c, used) in kids.iter().zip(&self.used) {
            if *used {
                continue;
            }
            let what = if c.name().is_empty() { format!("`<{}>`", c.tag) } else { format!("`{}`", c.name()) };
            // a repeated parameter: the first is read (`find`), this one is not
            let first = kids.iter().zip(&self.used).find(|(k, u)| **u && !c.name().is_empty() && k.name() == c.name());
            let m = match first {
                Some((f, _)) => format!(
                    "{}: parameter {what} given twice: line {} ignored, the value on line {} is used",
                    self.what(),
                    c.line,
                    f.line
                ),
                None => format!("{}: parameter {what} ignored", self.what()),
            };
            cx.warn(c.line, m);
        }
    }
}

/// One `to_world` operation as a matrix (and the `lookat` operands when `lone`).
fn op_matrix(op: &Node, lone: bool) -> Result<(DMat4, Option<LookAt>), String> {
    let m = match op.tag.as_str() {
        "translate" => DMat4::from_translation(d3(xyz(op, 0.0)?)),
        "scale" => {
            let s = match op.attr("value").and_then(numbers).as_deref() {
                Some([s]) => [*s; 3],
                _ => xyz(op, 1.0)?,
            };
            DMat4::from_scale(d3(s))
        }
        "rotate" => {
            let axis = d3(xyz(op, 0.0)?);
            match op.attr("angle").and_then(|a| a.trim().parse::<f64>().ok()) {
                Some(a) if axis != DVec3::ZERO => rotate(axis, a.to_radians()),
                _ => return Err("`rotate` needs a non-zero axis and a numeric `angle`".into()),
            }
        }
        "matrix" => {
            let v = op.attr("value").and_then(numbers).unwrap_or_default();
            match v.len() {
                16 => DMat4::from_cols_array(&std::array::from_fn(|i| v[(i % 4) * 4 + i / 4] as f64)),
                9 => {
                    let c = |j: usize| DVec4::new(v[j] as f64, v[3 + j] as f64, v[6 + j] as f64, 0.0);
                    DMat4::from_cols(c(0), c(1), c(2), DVec4::W)
                }
                k => return Err(format!("`matrix` needs 16 (or 9) numbers, got {k}")),
            }
        }
        "lookat" => return lookat(op, lone),
        t => return Err(format!("unknown transform operation `<{t}>`")),
    };
    Ok((m, None))
}

/// Mitsuba's `Transform4f::rotate(axis, angle)` (Dr.Jit's `rotate`): Rodrigues' matrix of the axis
/// as written, not normalised (a longer axis scales and shears, as in Mitsuba), in Dr.Jit's
/// order of operations (`fmadd`); `angle` in radians.
fn rotate(a: DVec3, angle: f64) -> DMat4 {
    let (s, c) = angle.sin_cos();
    let cm = 1.0 - c;
    let (shuf1, shuf2) = (DVec3::new(a.y, a.z, a.x), DVec3::new(a.z, a.x, a.y));
    let tmp0 = (a * a).mul_add(DVec3::splat(cm), DVec3::splat(c));
    let tmp1 = (a * shuf1).mul_add(DVec3::splat(cm), shuf2 * s);
    let tmp2 = (a * shuf2).mul_add(DVec3::splat(cm), -(shuf1 * s));
    // rows (tmp0.x, tmp2.y, tmp1.z), (tmp1.x, tmp0.y, tmp2.z), (tmp2.x, tmp1.y, tmp0.z)
    DMat4::from_cols(
        DVec4::new(tmp0.x, tmp1.x, tmp2.x, 0.0),
        DVec4::new(tmp2.y, tmp0.y, tmp1.y, 0.0),
        DVec4::new(tmp1.z, tmp2.z, tmp0.z, 0.0),
        DVec4::W,
    )
}

/// Mitsuba's look-at matrix: columns left = normalize(up × dir), up' = dir × left, dir, origin.
fn lookat(op: &Node, lone: bool) -> Result<(DMat4, Option<LookAt>), String> {
    let p = |k: &str| op.attr(k).and_then(numbers).filter(|v| v.len() == 3).map(|v| [v[0], v[1], v[2]]);
    let (Some(o), Some(t)) = (p("origin"), p("target")) else {
        return Err("`lookat` needs `origin` and `target` (three numbers each)".into());
    };
    let up = p("up").unwrap_or([0.0, 1.0, 0.0]);
    let dir = (d3(t) - d3(o)).normalize();
    let left = d3(up).cross(dir).normalize();
    if !left.is_finite() || !dir.is_finite() {
        return Err("`lookat`: target equals origin or up is parallel to the view".into());
    }
    let nu = dir.cross(left);
    let m = DMat4::from_cols(left.extend(0.0), nu.extend(0.0), dir.extend(0.0), d3(o).extend(1.0));
    Ok((m, lone.then_some([o, t, up])))
}

fn d3(a: [f32; 3]) -> DVec3 {
    DVec3::new(a[0] as f64, a[1] as f64, a[2] as f64)
}

/// `x`/`y`/`z` attributes (missing ones = `default`) or a 3-number `value`.
fn xyz(n: &Node, default: f32) -> Result<[f32; 3], String> {
    if let Some(v) = n.attr("value") {
        return match numbers(v).as_deref() {
            Some([x, y, z]) => Ok([*x, *y, *z]),
            _ => Err(format!("`value=\"{v}\"` is not three numbers")),
        };
    }
    let mut out = [default; 3];
    for (k, a) in ["x", "y", "z"].iter().enumerate() {
        if let Some(s) = n.attr(a) {
            out[k] = s.trim().parse::<f32>().map_err(|_| format!("`{a}=\"{s}\"` is not a number"))?;
        }
    }
    if out.iter().any(|x| !x.is_finite()) {
        return Err("values must be finite".into());
    }
    Ok(out)
}
