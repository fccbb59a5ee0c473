//! The time box's phases (`--time`): every phase of a render runs inside the budget. Loading and
//! the BVH are measured (they cannot be cut); writing is reserved up front
//! ([`write_reserve_s`]); each phase that can end early gets a share of what is left when it
//! starts and stops there with what it has: the emission-split probe ([`PROBE_SHARE`]: the bands
//! not probed are not split), the caustic preprocess ([`PREPROCESS_SHARE`]: fewer photons, traced
//! from the same streams) and `pt-cf`'s light-path pilot ([`PILOT_SHARE`]: cut short, the
//! default count), and the integrator's build ([`BUILD_SHARE`]: the CF lookup grid, exact when
//! stopped, slower per lookup). The passes run until the budget less the write reserve
//! (`schedule::Deadline`): a round is started only if it is expected to fit, and a round still
//! running at that deadline is cut within a tile (or a chunk of `pt-cf`'s light paths) and
//! discarded whole on every rank, so the image holds whole passes only, bit for bit the `--spp`
//! render of that many passes with the same preprocess and probe (`pipeline::passes`). The
//! run's first round is the exception: it is never cut by the deadline (a time-boxed image is
//! never empty), so a render whose one pass outlasts the budget ends up to a pass late, with a
//! warning naming the `--time` it needs. A budget that loading, the BVH and writing alone exceed
//! is refused before any other work, with the time the render needs ([`Budget::check_minimal`]).
//!
//! Invariants: every early end leaves the image unbiased (fewer split pixels, fewer photons in a
//! pdf, another light-path count: each an unbiased estimator); a phase's deadline is never after
//! the render's; the report lists each phase's wall seconds and share of the budget
//! ([`PhaseTime`]; `passes` is `stopped` when a round was cut, and the JSON's `passes_cut` and
//! `cut_s` say how many passes and seconds were discarded). Without `--time` no phase has a deadline, and every phase still stops at a
//! signal (`interrupt::Stop`).

use crate::interrupt::{Interrupt, Stop};
use std::time::{Duration, Instant};

/// The probe's share of the budget left when it starts (after the write reserve).
pub const PROBE_SHARE: f64 = 0.10;
/// The caustic preprocess's share of the budget left when it starts (its photon rule aims at a
/// smaller one, `iws_cf::PREPROCESS_SHARE` of the whole budget; this is where it is stopped).
pub const PREPROCESS_SHARE: f64 = 0.30;
/// `pt-cf`'s light-path pilot's share of the budget left when it starts.
pub const PILOT_SHARE: f64 = 0.10;
/// The integrator's build's share of the budget left when it starts: the CF methods' lookup
/// grid (`cf::subset_grid`) stops there and answers from the cluster map (the same image).
pub const BUILD_SHARE: f64 = 0.10;
/// Seconds reserved per pixel for writing `PREFIX.{exr,png,json}` (and a checkpoint): the EXR
/// and PNG of a 2048² image took 3.6–4.6 s of wall time (0.85–1.1 µs per pixel) on the shared
/// 2-core machine of `results/2026-12-07-time-boxes.md`.
pub const WRITE_S_PER_PIXEL: f64 = 1.0e-6;
/// The least write reserve (seconds).
pub const WRITE_MIN_S: f64 = 0.02;

/// Seconds reserved for writing a `w × h` render's outputs (twice with checkpoints).
pub fn write_reserve_s((w, h): (u32, u32), checkpoints: bool) -> f64 {
    let one = WRITE_S_PER_PIXEL * w as f64 * h as f64;
    WRITE_MIN_S + if checkpoints { 2.0 * one } else { one }
}

/// One phase as the report lists it.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PhaseTime {
    /// `load`, `bvh`, `preprocess`, `light pilot`, `probe`, `passes`, `write`.
    pub phase: String,
    /// Its wall seconds.
    pub wall_s: f64,
    /// `wall_s` over the `--time` budget (`None` without one).
    pub share: Option<f64>,
    /// The seconds it was allowed (`None`: no deadline of its own).
    pub allowed_s: Option<f64>,
    /// Whether it ended early at its deadline or a signal.
    pub stopped: bool,
}

/// The render's budget and the phases so far.
#[derive(Clone, Debug)]
pub struct Budget {
    started: Instant,
    total: Option<f64>,
    write_s: f64,
    interrupt: Interrupt,
    /// The phases recorded, in order.
    pub phases: Vec<PhaseTime>,
}

impl Budget {
    /// A budget of `total` seconds from `started` (`None`: no time box), with `write_s` seconds
    /// kept for writing.
    pub fn new(started: Instant, total: Option<f64>, write_s: f64, interrupt: &Interrupt) -> Budget {
        Budget { started, total, write_s, interrupt: interrupt.clone(), phases: Vec::new() }
    }

    /// The seconds the passes may run until, since the start: the budget less the write reserve.
    pub fn passes_budget(&self) -> Option<f64> {
        self.total.map(|t| (t - self.write_s).max(0.0))
    }

    /// Refuses a budget that what has run (loading, the BVH) and the write reserve already use
    /// up, naming the time the render needs.
    pub fn check_minimal(&self) -> Result<(), String> {
        let Some(t) = self.total else { return Ok(()) };
        let spent = self.started.elapsed().as_secs_f64();
        let need = spent + self.write_s;
        if need < t {
            return Ok(());
        }
        // what it needs, with room for the first pass: twice the minimal phases, rounded up
        let suggest = (2.0 * need * 100.0).ceil() / 100.0;
        Err(format!(
            "--time {t} s is too short for this render: loading and the BVH took {spent:.3} s and writing \
             its outputs needs about {:.3} s, so the minimal phases alone need {need:.3} s; give --time {suggest}s \
             or more (nothing was rendered or written)",
            self.write_s
        ))
    }

    /// The stop of a phase that may use `share` of the budget left now (after the write
    /// reserve), and the seconds that gives; no deadline without a time box.
    pub fn stop_for(&self, share: f64) -> (Stop, Option<f64>) {
        let Some(end) = self.passes_budget() else { return (Stop::new(&self.interrupt, None), None) };
        let left = (end - self.started.elapsed().as_secs_f64()).max(0.0);
        let allowed = share * left;
        let at = Duration::try_from_secs_f64(allowed).ok().and_then(|d| Instant::now().checked_add(d));
        (Stop::new(&self.interrupt, at.or(Some(Instant::now()))), Some(allowed))
    }

    /// Records a phase of `wall_s` seconds.
    pub fn record(&mut self, phase: &str, wall_s: f64, allowed_s: Option<f64>, stopped: bool) {
        let share = self.total.map(|t| wall_s / t);
        self.phases.push(PhaseTime { phase: phase.to_string(), wall_s, share, allowed_s, stopped });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_budget_the_minimal_phases_exceed_is_refused_with_the_time_needed() {
        let started = Instant::now() - Duration::from_millis(50);
        let b = Budget::new(started, Some(0.01), 0.02, &Interrupt::default());
        let e = b.check_minimal().unwrap_err();
        assert!(e.contains("too short") && e.contains("give --time"), "{e}");
        assert!(Budget::new(started, Some(10.0), 0.02, &Interrupt::default()).check_minimal().is_ok());
        assert!(Budget::new(started, None, 0.02, &Interrupt::default()).check_minimal().is_ok());
    }

    #[test]
    fn a_phase_gets_its_share_of_what_is_left_and_none_without_a_box() {
        let b = Budget::new(Instant::now(), Some(10.0), 1.0, &Interrupt::default());
        let (stop, allowed) = b.stop_for(0.1);
        let a = allowed.unwrap();
        assert!(a > 0.85 && a <= 0.9, "{a}");
        assert!(!stop.is_due());
        let (stop, allowed) = Budget::new(Instant::now(), None, 1.0, &Interrupt::default()).stop_for(0.1);
        assert!(allowed.is_none() && stop.deadline().is_none());
        let over = Budget::new(Instant::now() - Duration::from_secs(20), Some(10.0), 1.0, &Interrupt::default());
        assert!(over.stop_for(0.5).0.is_due(), "a phase past the budget stops at once");
    }

    #[test]
    fn the_write_reserve_grows_with_the_image() {
        assert!(write_reserve_s((2048, 2048), false) > write_reserve_s((128, 128), false));
        assert!(write_reserve_s((128, 128), true) > write_reserve_s((128, 128), false));
    }
}
