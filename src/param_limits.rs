//! The one set of limits on render parameters, shared by the scene file's `[render]` and
//! `[forecast]` tables (`scene::file`), the command line (each method's `*Args::validate`) and
//! the resolved render plan (`pipeline::Plan::validate`), so that a value is refused with the same
//! bound and the same words wherever it is written. The caller adds where the value came from
//! (`file:line: render.spp: …` or `--spp 0: …`).
//!
//! Invariants: every limit is inclusive; a refused value is refused before any work starts (no
//! preprocess, no pass, no file written). The upper bounds stop values that cannot finish or
//! cannot be allocated (`--split 4294967295` is 4·10⁹ table samples per camera sample,
//! `--vpl-paths 4294967295` 4·10⁹ light paths per pass, `--light-paths 1e13` a pass of days);
//! they are far above any useful setting.

/// An inclusive range for one integer parameter.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Limit {
    /// The parameter's name in words (`spp`, `max_depth`).
    pub name: &'static str,
    /// Smallest allowed value.
    pub min: u64,
    /// Largest allowed value.
    pub max: u64,
}

impl Limit {
    /// `Ok` when `min <= value <= max`; else the message (`spp must be at least 1 (got 0)`).
    pub fn check(&self, value: u64) -> Result<(), String> {
        let (name, min, max) = (self.name, self.min, self.max);
        match (value < min || value > max, max == u64::MAX) {
            (false, _) => Ok(()),
            (true, true) => Err(format!("{name} must be at least {min} (got {value})")),
            (true, false) => Err(format!("{name} must be between {min} and {max} (got {value})")),
        }
    }

    /// [`Limit::check`] for a command-line option: `--flag VALUE: message`.
    pub fn check_flag(&self, flag: &str, value: u64) -> Result<(), String> {
        self.check(value).map_err(|m| format!("{flag} {value}: {m}"))
    }
}

/// Samples per pixel (`--spp`, `render.spp`): at least one, or the image is black.
pub const SPP: Limit = Limit { name: "spp", min: 1, max: u64::MAX };
/// Path-vertex safety cap (`--max-depth`, `render.max_depth`): a camera vertex and one bounce.
pub const MAX_DEPTH: Limit = Limit { name: "max_depth", min: 2, max: u64::MAX };
/// iws-pm caustic photons to store (`--photons`).
pub const PHOTONS: Limit = Limit { name: "photons", min: 1, max: u64::MAX };
/// iws-cf forecast photons to store (`--forecast-photons`, `forecast.photons`).
pub const FORECAST_PHOTONS: Limit = Limit { name: "forecast photons", min: 1, max: u64::MAX };
/// Worker threads per process (`--threads`); more fail late with "Resource temporarily unavailable".
pub const THREADS: Limit = Limit { name: "threads", min: 1, max: MAX_THREADS as u64 };
/// The most worker threads a process may ask for.
pub const MAX_THREADS: usize = 4096;
/// iws-cf splitting factor S0 (`--split`): table samples per camera sample at depth 0.
pub const SPLIT: Limit = Limit { name: "split", min: 1, max: 1024 };
/// IWS light paths per pass N (`--vpl-paths`).
pub const VPL_PATHS: Limit = Limit { name: "vpl paths", min: 1, max: 65_536 };

/// `pt-cf`'s light paths per pass (`--light-paths`): 0 (the camera side alone) up to 2³⁰, 16,384
/// per pixel of a 256² image; the defaults are ⅛ to 2 per pixel.
pub const LIGHT_PATHS: Limit = Limit { name: "light paths", min: 0, max: 1 << 30 };

/// `forecast-map --compare-paths`: untargeted light paths for the yield comparison, 0 (none) up
/// to 2³⁰ (about 8 minutes on 2 cores; 10⁶ take 0.44 s).
pub const COMPARE_PATHS: Limit = Limit { name: "compare paths", min: 0, max: 1 << 30 };

/// A time budget in seconds (`--time`, `render.time`): positive and finite.
pub fn check_time(secs: f64) -> Result<(), String> {
    if secs.is_finite() && secs > 0.0 {
        Ok(())
    } else {
        Err(format!("time budget must be a positive duration (got {secs} s)"))
    }
}

/// Bytes of memory this machine can still give (`MemAvailable` in `/proc/meminfo`); `None` where
/// that is unknown (not Linux), and then no memory check is made.
pub fn available_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib.saturating_mul(1024))
}

/// Refuses a render whose estimated memory `need` (bytes, `what` says of what) exceeds `available`.
pub fn check_memory(need: u64, available: Option<u64>, what: &str) -> Result<(), String> {
    match available {
        Some(avail) if need > avail => Err(format!(
            "this render needs about {} of memory ({what}) but only {} is available; \
             lower --resolution or the photon counts",
            gib(need),
            gib(avail)
        )),
        _ => Ok(()),
    }
}

fn gib(bytes: u64) -> String {
    format!("{:.1} GiB", bytes as f64 / (1u64 << 30) as f64)
}

/// Parses a duration such as `500ms`, `30s`, `4m`, `1h` or `1m30s` into seconds.
pub fn parse_duration(s: &str) -> Result<f64, String> {
    let s = s.trim();
    let mut total = 0.0;
    let mut num = String::new();
    let mut chars = s.chars().peekable();
    let mut any = false;
    while let Some(c) = chars.next() {
        if c.is_ascii_digit() || c == '.' {
            num.push(c);
            continue;
        }
        let mut unit = c.to_string();
        while let Some(&n) = chars.peek() {
            if n.is_ascii_alphabetic() {
                unit.push(n);
                chars.next();
            } else {
                break;
            }
        }
        let v: f64 = num.parse().map_err(|_| format!("bad duration `{s}` (expected e.g. 30s, 4m, 1h)"))?;
        total += v * match unit.as_str() {
            "ms" => 1e-3,
            "s" => 1.0,
            "m" | "min" => 60.0,
            "h" => 3600.0,
            _ => return Err(format!("bad duration unit `{unit}` in `{s}` (use ms, s, m, h)")),
        };
        num.clear();
        any = true;
    }
    if !num.is_empty() {
        // a bare number means seconds
        total += num.parse::<f64>().map_err(|_| format!("bad duration `{s}`"))?;
        any = true;
    }
    if !any || !total.is_finite() || total <= 0.0 {
        return Err(format!("bad duration `{s}`: must be positive (e.g. 30s, 4m, 1h)"));
    }
    Ok(total)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bounds_are_inclusive_and_messages_name_the_value() {
        assert!(SPP.check(1).is_ok());
        assert_eq!(SPP.check(0).unwrap_err(), "spp must be at least 1 (got 0)");
        assert!(SPLIT.check(1024).is_ok());
        assert_eq!(
            SPLIT.check_flag("--split", 4294967295).unwrap_err(),
            "--split 4294967295: split must be between 1 and 1024 (got 4294967295)"
        );
        assert!(MAX_DEPTH.check(1).is_err() && MAX_DEPTH.check(2).is_ok());
        assert!(check_memory(2 << 30, Some(1 << 30), "film").unwrap_err().contains("2.0 GiB"));
        assert!(check_memory(2 << 30, None, "film").is_ok());
        assert!(check_time(0.0).is_err() && check_time(f64::INFINITY).is_err() && check_time(0.001).is_ok());
    }
}
