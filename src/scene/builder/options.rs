//! The render options a scene file may carry (`[render]`, `[forecast]`, `[[roi]]` in TOML; the
//! integrator's `max_depth` in Mitsuba XML), checked with the limits the command line uses
//! (`param_limits`) and named by their origin.

use super::super::spec::{Origin, SceneError};
use super::super::Roi;
use super::SceneBuilder;
use crate::math::Vec3;
use crate::param_limits as params;

impl SceneBuilder {
    /// The default method (`auto` or one of `METHOD_NAMES`).
    pub fn method(&mut self, m: &str, at: &Origin) -> Result<(), SceneError> {
        if !super::super::is_method_name(m) {
            let all = super::super::METHOD_NAMES.join(", ");
            return Err(self.err(at, format!("unknown method `{m}` ({}, {all})", super::super::AUTO_METHOD)));
        }
        self.render.method = m.to_string();
        Ok(())
    }

    /// The default spp (the limits of `--spp`).
    pub fn spp(&mut self, n: u64, at: &Origin) -> Result<(), SceneError> {
        params::SPP.check(n).map_err(|m| self.err(at, m))?;
        self.render.spp = Some(n);
        Ok(())
    }

    /// The default time budget, a duration (`30s`, `4m`; the limits of `--time`).
    pub fn time(&mut self, t: &str, at: &Origin) -> Result<(), SceneError> {
        let secs = params::parse_duration(t).and_then(|v| params::check_time(v).map(|()| v));
        self.render.time = Some(secs.map_err(|m| self.err(at, m))?);
        Ok(())
    }

    /// The path-vertex cap (the limits of `--max-depth`).
    pub fn max_depth(&mut self, d: u64, at: &Origin) -> Result<(), SceneError> {
        params::MAX_DEPTH.check(d).map_err(|m| self.err(at, m))?;
        self.render.max_depth = u32::try_from(d).map_err(|_| self.err(at, format!("max_depth {d} is too large")))?;
        Ok(())
    }

    /// A Mitsuba `max_depth` of `d` ≥ 1 path segments: the vertex cap d − 1 (0: the emitters seen
    /// directly, 1: direct light; below `--max-depth`'s least, 2, which the command line keeps).
    pub fn max_segments(&mut self, d: u64, at: &Origin) -> Result<(), SceneError> {
        let cap = d.checked_sub(1).ok_or_else(|| self.err(at, "max_depth must be at least 1 segment"))?;
        self.render.max_depth = u32::try_from(cap).map_err(|_| self.err(at, format!("max_depth {d} is too large")))?;
        Ok(())
    }

    /// Forecast photons to store (the limits of `--forecast-photons`).
    pub fn forecast_photons(&mut self, n: u64, at: &Origin) -> Result<(), SceneError> {
        params::FORECAST_PHOTONS.check(n).map_err(|m| self.err(at, m))?;
        self.forecast_photons = Some(n);
        Ok(())
    }

    /// The forecast target box: finite, min <= max.
    pub fn forecast_target(&mut self, lo: Vec3, hi: Vec3, at: &Origin) -> Result<(), SceneError> {
        if !lo.is_finite() || !hi.is_finite() || lo.cmpgt(hi).any() {
            return Err(self.err(at, "the target box must be finite, min then max with min <= max"));
        }
        self.forecast_target = Some((lo, hi));
        Ok(())
    }

    /// A region of interest: a name of its own (`roi_name_error`), non-empty and inside the image
    /// (the camera comes first).
    pub fn roi(&mut self, (name, nat): (String, &Origin), (rect, at): ([u32; 4], &Origin)) -> Result<(), SceneError> {
        let earlier = self.rois.iter().map(|(r, at)| (r.name.as_str(), at));
        if let Some(m) = roi_name_error(&name, earlier) {
            return Err(self.err(nat, m));
        }
        let (cw, ch) = self.camera.as_ref().map_or((0, 0), |c| (c.width, c.height));
        let [x, y, w, h] = rect;
        let inside = |o: u32, len: u32, size: u32| o.checked_add(len).is_some_and(|e| e <= size);
        if w == 0 || h == 0 || !inside(x, w, cw) || !inside(y, h, ch) {
            return Err(self.err(at, format!("rect {rect:?} must be non-empty and inside the {cw}x{ch} image")));
        }
        self.rois.push((Roi { name, rect }, nat.clone()));
        Ok(())
    }
}

/// `None` when ROI `name` gives `compare` files of its own (`crops/NAME-*.png`, `strip-NAME.png`,
/// after `safe_name`; `full` is the whole image), else the message; `earlier`: the ROIs before.
fn roi_name_error<'a>(name: &str, mut earlier: impl Iterator<Item = (&'a str, &'a Origin)>) -> Option<String> {
    let file = super::super::safe_name;
    if name == "full" {
        return Some("roi name `full` is reserved: `compare` names the whole image `full`".into());
    }
    let (first, at) = earlier.find(|(n, _)| file(n) == file(name))?;
    let alike = if first == name { String::new() } else { format!(" as `{first}` (both files `{}`)", file(name)) };
    Some(format!(
        "duplicate roi name `{name}`: `{}` (line {}) has it already{alike}; `compare` names each ROI's files after it",
        at.key, at.line
    ))
}
