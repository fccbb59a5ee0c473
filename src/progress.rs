//! Progress reporting on stderr (the only indicatif user): passes, spp, elapsed and remaining
//! time, and Mrays/s. Hidden with `--quiet`, on non-zero ranks and when stderr is not a terminal.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// A progress bar over passes (spp mode) or milliseconds of budget (time mode).
pub struct Progress {
    bar: Option<ProgressBar>,
    time_mode: bool,
}

impl Progress {
    /// `total_passes` for spp mode, or `budget_secs` for time mode.
    pub fn new(visible: bool, total_passes: Option<u64>, budget_secs: Option<f64>) -> Progress {
        if !visible {
            return Progress { bar: None, time_mode: false };
        }
        let (len, time_mode) = match (total_passes, budget_secs) {
            (_, Some(b)) => ((b * 1000.0) as u64, true),
            (Some(p), None) => (p, false),
            _ => (0, false),
        };
        let bar = ProgressBar::with_draw_target(Some(len), ProgressDrawTarget::stderr());
        let tpl = if time_mode {
            "{spinner} [{elapsed_precise} / eta {eta}] {wide_bar} {msg}"
        } else {
            "{spinner} [{elapsed_precise} / eta {eta}] {wide_bar} pass {pos}/{len} {msg}"
        };
        if let Ok(style) = ProgressStyle::with_template(tpl) {
            bar.set_style(style);
        }
        Progress { bar: Some(bar), time_mode }
    }

    /// Updates after a round of passes.
    pub fn update(&self, passes: u64, spp: u64, elapsed_render_secs: f64, elapsed_total_secs: f64, rays: u64) {
        if let Some(b) = &self.bar {
            let mrays = rays as f64 / elapsed_render_secs.max(1e-9) / 1e6;
            if self.time_mode {
                b.set_position((elapsed_total_secs * 1000.0) as u64);
                b.set_message(format!("passes {passes}, {spp} spp, {mrays:.1} Mrays/s"));
            } else {
                b.set_position(passes);
                b.set_message(format!("{spp} spp, {mrays:.1} Mrays/s"));
            }
        }
    }

    /// Clears the bar.
    pub fn finish(&self) {
        if let Some(b) = &self.bar {
            b.finish_and_clear();
        }
    }
}
