//! Progress reporting on stderr (the only indicatif user): the preprocess phases ([`Phases`]:
//! name, elapsed time, and counts where known) and then the render passes ([`Progress`]: passes,
//! spp, elapsed and remaining time, and Mrays/s). Hidden with `--quiet`, on non-zero ranks and
//! when stderr is not a terminal. Reporting never touches an image or a random stream.
//!
//! Under `--time` the bar's clock is the time box's own ([`time_box_clock`]): the time since the
//! render started (loading and preprocess included) and the budget left, never a rate estimate
//! (a rate measured from the first round's jump reads seconds where minutes remain).

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressState, ProgressStyle};
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// The time-mode bar's clock: `MM:SS` (or `H:MM:SS`) since the time box began, and what is left
/// of a `budget_secs` box, `elapsed_secs` into it (0 once the budget is spent; the last round then
/// finishes).
pub fn time_box_clock(elapsed_secs: f64, budget_secs: f64) -> String {
    let left = (budget_secs - elapsed_secs).max(0.0);
    format!("{} / {} left", clock(elapsed_secs.max(0.0)), clock(left))
}

/// Whole seconds as `MM:SS`, or `H:MM:SS` from an hour on.
fn clock(secs: f64) -> String {
    let s = secs.round() as u64;
    let (h, m, s) = (s / 3600, s / 60 % 60, s % 60);
    if h > 0 {
        format!("{h}:{m:02}:{s:02}")
    } else {
        format!("{m:02}:{s:02}")
    }
}

/// A progress bar over passes (spp mode) or milliseconds of budget (time mode).
pub struct Progress {
    bar: Option<ProgressBar>,
    time_mode: bool,
}

impl Progress {
    /// `total_passes` for spp mode, or `budget_secs` for time mode, whose box began at `started`
    /// (the render's start: the clock the time box and [`time_box_clock`] count from).
    pub fn new(visible: bool, total_passes: Option<u64>, budget_secs: Option<f64>, started: Instant) -> Progress {
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
            "{spinner} [{time_box}] {wide_bar} {msg}"
        } else {
            "{spinner} [{elapsed_precise} / eta {eta}] {wide_bar} pass {pos}/{len} {msg}"
        };
        if let Ok(style) = ProgressStyle::with_template(tpl) {
            let budget = budget_secs.unwrap_or(0.0);
            let style = style.with_key("time_box", move |_: &ProgressState, w: &mut dyn std::fmt::Write| {
                let _ = w.write_str(&time_box_clock(started.elapsed().as_secs_f64(), budget));
            });
            bar.set_style(style);
        }
        if time_mode {
            // the clock moves between rounds too
            bar.enable_steady_tick(Duration::from_millis(500));
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

/// Where the preprocess reports its phases (tracing, clustering, maps, photon map, pilot). It is
/// passed down explicitly from the pipeline; an implementation only displays or records, so the
/// product and every random stream are the same whichever one is passed (or [`Hidden`]), except
/// that it may also say when to [`Phases::stop`] (a time box's share or a signal): a phase that
/// polls it then ends early with what it has (fewer photons, all traced from the same streams).
/// Phases run one at a time: `begin`, any number of `advance`, then `end`.
pub trait Phases: Sync {
    /// True once the running phases should end early (their deadline or a signal); by default
    /// never.
    fn stop(&self) -> bool {
        false
    }
    /// A phase starts: its name and, where known, the count it runs to (e.g. photons requested).
    fn begin(&self, name: &'static str, total: Option<u64>);
    /// The current phase has reached `done` (e.g. photons stored so far).
    fn advance(&self, done: u64);
    /// The current phase ended.
    fn end(&self);
}

impl dyn Phases + '_ {
    /// Starts a phase; it ends when the returned handle is dropped or finished.
    pub fn phase(&self, name: &'static str, total: Option<u64>) -> PhaseGuard<'_> {
        self.begin(name, total);
        PhaseGuard { sink: self }
    }
}

/// A running phase (ends on drop).
pub struct PhaseGuard<'a> {
    sink: &'a dyn Phases,
}

impl PhaseGuard<'_> {
    /// The phase has reached `done` of its count.
    pub fn set(&self, done: u64) {
        self.sink.advance(done);
    }

    /// Ends the phase.
    pub fn finish(self) {}
}

impl Drop for PhaseGuard<'_> {
    fn drop(&mut self) {
        self.sink.end();
    }
}

/// Reports nothing (library callers, tests, the pilot's inner phases).
pub struct Hidden;

/// Reports nothing but stops when the wrapped reporter does (a pilot's inner phases).
pub struct Muted<'a>(pub &'a dyn Phases);

impl Phases for Muted<'_> {
    fn stop(&self) -> bool {
        self.0.stop()
    }
    fn begin(&self, _: &'static str, _: Option<u64>) {}
    fn advance(&self, _: u64) {}
    fn end(&self) {}
}

impl Phases for Hidden {
    fn begin(&self, _: &'static str, _: Option<u64>) {}
    fn advance(&self, _: u64) {}
    fn end(&self) {}
}

/// Preprocess phases on stderr: a bar `done/total` where a count is known, else a spinner, with
/// the phase name and elapsed time; cleared when the phase ends. Hidden under the render bar's
/// rules (`visible` false with `--quiet` or on non-zero ranks; indicatif hides it when stderr is
/// not a terminal).
pub struct PhaseBar {
    visible: bool,
    bar: Mutex<Option<ProgressBar>>,
    /// When the phases must end early (`Phases::stop`).
    stop: crate::interrupt::Stop,
}

impl PhaseBar {
    /// A reporter that draws only when `visible` (and stderr is a terminal).
    pub fn new(visible: bool) -> PhaseBar {
        PhaseBar { visible, bar: Mutex::new(None), stop: crate::interrupt::Stop::never() }
    }

    /// This reporter, whose phases stop at `stop` (a signal or the time box's deadline).
    pub fn with_stop(self, stop: crate::interrupt::Stop) -> PhaseBar {
        PhaseBar { stop, ..self }
    }

    fn current(&self) -> std::sync::MutexGuard<'_, Option<ProgressBar>> {
        self.bar.lock().unwrap_or_else(|e| e.into_inner())
    }
}

impl Phases for PhaseBar {
    fn stop(&self) -> bool {
        self.stop.is_due()
    }

    fn begin(&self, name: &'static str, total: Option<u64>) {
        let target = ProgressDrawTarget::stderr();
        if !self.visible || target.is_hidden() {
            return;
        }
        let tpl = match total {
            Some(_) => "{spinner} [{elapsed_precise}] {msg} {wide_bar} {human_pos}/{human_len}",
            None => "{spinner} [{elapsed_precise}] {msg}",
        };
        let bar = ProgressBar::with_draw_target(total, target);
        if let Ok(style) = ProgressStyle::with_template(tpl) {
            bar.set_style(style);
        }
        bar.set_message(name);
        bar.enable_steady_tick(Duration::from_millis(100));
        if let Some(old) = self.current().replace(bar) {
            old.finish_and_clear();
        }
    }

    fn advance(&self, done: u64) {
        if let Some(b) = self.current().as_ref() {
            b.set_position(done);
        }
    }

    fn end(&self) {
        if let Some(b) = self.current().take() {
            b.finish_and_clear();
        }
    }
}
