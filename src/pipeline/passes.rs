//! Stage 4 of the pipeline: rounds of interleaved passes until the spp or the time box is
//! reached, with checkpoints and snapshots at round boundaries. A round holds a pass group of `g`
//! passes per rank (`distributed::schedule::pass_group`, agreed by every rank; 1 for integrators
//! with per-pass state and under `--max-rounds`), so the finished passes stay one contiguous range.
//!
//! Cut rounds: every round after the run's first is traced against the time box's end and the
//! signal (`render::trace_passes`, checked per tile and per chunk of light paths): when either
//! comes first on any rank, every rank discards the round whole (`distributed::agree_any`), so the
//! film holds whole passes only, the same as a `--spp` render of that many passes, and the
//! render ends within a tile of the deadline. The run's first round is cut by a signal only (a
//! time-boxed image is never empty): a first pass longer than the budget is warned about with
//! the `--time` it needs. The report counts the passes cut and the seconds they took.

use super::{secs, snapshots, Run};
use crate::distributed;
use crate::distributed::schedule::{pass_group, Deadline, PassTimer};
use crate::integrators::Integrator;
use crate::progress::Progress;
use crate::render::film::Film;
use crate::render::pixel::SplitStats;
use crate::render::{pass_group_limit, trace_passes, PassCounters, PixelSampler, Traced};
use std::time::Instant;

/// This rank's passes.
pub(super) struct Passes {
    pub(super) film: Film,
    pub(super) counters: PassCounters,
    pub(super) my_passes: u64,
    pub(super) passes_done: u64,
    pub(super) render_s: f64,
    /// The run's warnings (rank 0): failed checkpoints, the preprocess over budget.
    pub(super) warnings: Vec<String>,
    pub(super) preprocess_over_budget: bool,
    /// The snapshot schedule and the snapshots written.
    pub(super) snaps: snapshots::Snapshots,
    /// The emission-split probe's findings.
    pub(super) pixel_sampler: SplitStats,
    /// Whether a signal ended the render early (`interrupt`).
    pub(super) interrupted: bool,
    /// Passes (every rank's) of the round cut at the deadline or a signal and discarded.
    pub(super) passes_cut: u64,
    /// The wall seconds of that cut round.
    pub(super) cut_s: f64,
}

impl Passes {
    /// No pass yet: an empty film, rendering resumes at `first_pass`.
    fn new(run: &Run, first_pass: u64, pixel_sampler: SplitStats) -> Passes {
        let (w, h) = run.plan.resolution;
        Passes {
            film: Film::new(w as usize, h as usize),
            counters: PassCounters::default(),
            my_passes: 0,
            passes_done: first_pass,
            render_s: 0.0,
            warnings: Vec::new(),
            preprocess_over_budget: false,
            snaps: snapshots::Snapshots::new(&run.job.snapshots),
            pixel_sampler,
            interrupted: false,
            passes_cut: 0,
            cut_s: 0.0,
        }
    }
}

/// Stage 4: rounds of interleaved passes until the spp or the time box is reached, with
/// checkpoints at round boundaries.
/// The probe ends at `probe` (its share of the budget, or a signal).
pub(super) fn run_passes(
    run: &Run,
    integrator: &mut dyn Integrator,
    deadline: Deadline,
    probe: &crate::interrupt::Stop,
) -> Result<Passes, String> {
    let (rank, size) = (run.cluster.rank() as u64, run.cluster.size() as u64);
    let (first_pass, total) = (run.resumed.first_pass, run.plan.spp.map(|s| s.max(run.resumed.first_pass)));
    let (w, h) = run.plan.resolution;
    let camera = run.world.scene.camera.with_resolution(w, h);
    let (k, cap) = (run.plan.args.emission_split(), integrator.prefix_cap());
    let pixels = run.pool.install(|| {
        PixelSampler::new_until(run.world, &camera, k, cap, probe).with_sampler(run.plan.args.settings.sampler)
    });
    let progress =
        Progress::new(run.job.progress && rank == 0, total.map(|t| t - first_pass), run.plan.time, run.started);
    let mut p = Passes::new(run, first_pass, pixels.stats());
    let (t_render, mut last_ckpt, mut timer) = (Instant::now(), Instant::now(), PassTimer::new());
    let mut failure: Option<String> = None;
    // `--max-rounds` (testing) counts rounds of one pass per rank
    let grouped = integrator.independent_passes() && run.job.max_rounds.is_none();
    let limit = if grouped { pass_group_limit(w as usize, h as usize) as u64 } else { 1 };
    let mut round_start = first_pass;
    let mut cut = false;
    for round in 0u64.. {
        let more = match total {
            Some(t) => round_start < t,
            // the first round always runs, so a time-boxed image is never empty
            None => round == 0 || deadline.should_start_next(Instant::now(), timer.mean_secs()),
        };
        let stop = run.job.interrupt.is_set();
        let go = more && !stop && !cut && run.job.max_rounds.is_none_or(|m| round < m);
        // one agreement per round: a stop (time box, signal) or an error on any rank ends every
        // rank's loop
        if !distributed::agree_round(run.cluster, go, failure.take())? {
            p.interrupted = distributed::agree_any(run.cluster, stop);
            break;
        }
        // the round's pass group, the same on every rank: passes round_start + rank + j·size
        let left = total.map(|t| (t - round_start).div_ceil(size));
        let g = distributed::agree_min(run.cluster, pass_group(limit, &timer, &deadline, Instant::now(), left));
        let mine: Vec<u64> =
            (0..g).map(|j| round_start + rank + j * size).filter(|&q| total.is_none_or(|t| q < t)).collect();
        // the run's first round is cut by a signal only; every later one at the deadline too
        let at = if round == 0 { None } else { deadline.instant() };
        let pass_stop = crate::interrupt::Stop::new(&run.job.interrupt, at);
        let t_pass = Instant::now();
        let traced = if mine.is_empty() {
            Some(None)
        } else {
            run.trace_group(integrator, &pixels, &mine, &pass_stop).map(Some)
        };
        // every rank keeps the round or none does: the finished passes stay one contiguous range
        cut = distributed::agree_any(run.cluster, traced.is_none());
        match traced {
            Some(Some(t)) if !cut => {
                p.counters.add(&run.pool.install(|| t.merge(&pixels, &mut p.film)));
                timer.record_group(secs(t_pass), mine.len() as u64);
                p.my_passes += mine.len() as u64;
            }
            Some(Some(t)) => t.discard(&pixels),
            _ => {}
        }
        if cut {
            p.passes_cut = total.map_or(g * size, |t| (g * size).min(t - round_start));
            p.cut_s = secs(t_pass);
            continue; // the next agreement ends the loop on every rank
        }
        if round == 0 {
            p.warnings.extend(first_round_over(run, &deadline));
        }
        round_start += g * size;
        // a round is done: a signal now saves it (`interrupt`)
        run.job.interrupt.nothing_to_save(false);
        p.passes_done = total.map_or(round_start, |t| round_start.min(t));
        let rays = p.counters.closest_rays + p.counters.shadow_rays;
        progress.update(p.passes_done - first_pass, p.passes_done, secs(t_render), secs(run.started), rays * size);
        p.render_s = secs(t_render);
        // no periodic checkpoint after the last round of a time box or a signal: the final one
        // follows at once, inside the write reserve
        let last = run.job.interrupt.is_set()
            || (total.is_none() && !deadline.should_start_next(Instant::now(), timer.mean_secs()));
        failure = run
            .maybe_checkpoint(&mut p, &*integrator, &mut last_ckpt, last)
            .and_then(|()| run.maybe_snapshot(&mut p))
            .err();
    }
    run.unreached_snapshots(&mut p);
    p.render_s = secs(t_render);
    progress.finish();
    if p.interrupted && p.passes_done == 0 {
        return Err("interrupted before the first pass: nothing was written".into());
    }
    Ok(p)
}

/// The warning when the run's first round (never cut by the deadline) ended past the time box's
/// end for passes, with the `--time` that would have held it (rank 0; `None` otherwise).
fn first_round_over(run: &Run, deadline: &Deadline) -> Option<String> {
    let (at, budget) = (deadline.instant()?, run.plan.time?);
    let over = Instant::now().checked_duration_since(at)?.as_secs_f64();
    let w = format!(
        "the first pass ran {over:.2} s past the --time budget of {budget} s (less the time kept for writing): \
         the image holds that one pass; give --time {}s or more for {} at {}x{} to end in time",
        ((budget + over) * 1.1 * 10.0).ceil() / 10.0,
        run.plan.method.name(),
        run.plan.resolution.0,
        run.plan.resolution.1
    );
    if run.cluster.rank() == 0 {
        crate::errln!("warning: {w}");
        return Some(w);
    }
    None
}

impl Run<'_> {
    /// This rank's passes `mine` of a round, in one group when there are several (the
    /// integrator's passes are then independent: `pass_group`'s limit is 1 otherwise), traced
    /// until `stop` (`None`: cut, nothing of them kept).
    fn trace_group(
        &self,
        integrator: &mut dyn Integrator,
        pixels: &PixelSampler,
        mine: &[u64],
        stop: &crate::interrupt::Stop,
    ) -> Option<Traced> {
        let (world, seed) = (self.world, self.plan.seed);
        for &q in mine {
            integrator.begin_pass(world, seed, q);
        }
        let integ = &*integrator;
        self.pool.install(|| trace_passes(world, integ, pixels, seed, mine, stop))
    }
}

impl Passes {
    /// A failed checkpoint: printed (rank 0 only ever writes) and kept for the report.
    pub(super) fn warn(&mut self, what: String, retry_in: Option<f64>) {
        let w = retry_in.map_or_else(|| what.clone(), |s| format!("{what}; next try in {s} s"));
        crate::errln!("warning: {w}");
        self.warnings.push(w);
    }
}
