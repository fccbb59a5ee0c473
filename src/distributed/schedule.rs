//! Pure scheduling arithmetic: which rank renders which progressive pass, and whether a
//! time box leaves room for one more pass.
//!
//! Ownership: pass `p` belongs to rank `p % size`. The pass index (not the rank) seeds the
//! pass's random numbers, so the image does not depend on the number of ranks.
//!
//! Contiguity: split the passes `first_pass..total_passes` into *rounds* of `size`
//! consecutive indices, `first_pass + k*size .. first_pass + (k+1)*size`. Each round holds
//! exactly one pass of every rank, and rank `r`'s k-th pass is in round k. So if all ranks
//! stop after the same number of rounds `k` (agree with `distributed::all_agree` once per
//! round), the finished passes are exactly `first_pass..passes_done_after_rounds(..)`, a
//! contiguous range, which is what a checkpoint records. A round may hold a *pass group* of `g`
//! passes of every rank (`size·g` consecutive indices, `g` agreed by all ranks, [`pass_group`]);
//! the argument is the same.
//!
//! Time boxes: [`Deadline`] refuses to start a pass that is expected to end after the
//! deadline, using the running mean pass duration plus a safety margin.

use std::time::{Duration, Instant};

/// Rank that renders pass `pass` in a world of `size` ranks (`pass % size`; a `size` of 0
/// is treated as 1).
pub fn pass_owner(pass: u64, size: usize) -> usize {
    let size = size.max(1) as u64;
    (pass % size) as usize
}

/// The passes in `first_pass..total_passes` (end exclusive) that rank `rank` renders, in
/// increasing order: those `p` with `p % size == rank`. Empty when `rank >= size`.
/// A `size` of 0 is treated as 1.
pub fn passes_for_rank(rank: usize, size: usize, first_pass: u64, total_passes: u64) -> impl Iterator<Item = u64> {
    let size = size.max(1) as u64;
    let rank = rank as u64;
    // Smallest p >= first_pass with p % size == rank.
    let start = if rank >= size {
        total_passes // empty range
    } else {
        let off = (rank + size - first_pass % size) % size;
        first_pass.saturating_add(off)
    };
    (start..total_passes.max(start)).step_by(size as usize)
}

/// Round (0-based) that `pass` falls in when rendering starts at `first_pass` with `size`
/// ranks; `None` when `pass < first_pass`.
pub fn round_of(pass: u64, size: usize, first_pass: u64) -> Option<u64> {
    pass.checked_sub(first_pass).map(|d| d / size.max(1) as u64)
}

/// End (exclusive) of the contiguous range of finished passes after every rank completed
/// `rounds` rounds starting at `first_pass`, capped at `total_passes`.
pub fn passes_done_after_rounds(first_pass: u64, total_passes: u64, size: usize, rounds: u64) -> u64 {
    let span = rounds.saturating_mul(size.max(1) as u64);
    first_pass.saturating_add(span).min(total_passes).max(first_pass.min(total_passes))
}

/// About the longest a pass group is planned to take (seconds), so that progress, checkpoints
/// and snapshots, which happen between rounds, stay about this fresh.
pub const GROUP_SECS: f64 = 1.0;

/// The passes per rank of the next round (a pass group): at most `limit` (1 for an integrator
/// with per-pass state), 1 until a pass has been timed, and no more than fit before the
/// deadline, than take about [`GROUP_SECS`] or than are `left` for this rank (`None` without an
/// spp target). At least 1: whether a round starts at all is [`Deadline::should_start_next`]'s.
pub fn pass_group(limit: u64, timer: &PassTimer, deadline: &Deadline, now: Instant, left: Option<u64>) -> u64 {
    let mean = timer.mean_secs();
    if timer.count() == 0 || mean <= 0.0 {
        return 1;
    }
    let fresh = (GROUP_SECS / mean).floor().min(u64::MAX as f64) as u64;
    [limit, fresh, deadline.passes_that_fit(now, mean), left.unwrap_or(u64::MAX)].into_iter().min().unwrap_or(1).max(1)
}

/// A time box end shared by all ranks, with a safety margin for the pass in flight.
///
/// A new pass may start only if `now + mean_pass * (1 + margin_frac) + margin_secs` is not
/// after the deadline. Defaults: `margin_frac = 0.25`, `margin_secs = 0.05` (covers the
/// final reduction and pass-time jitter).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Deadline {
    at: Option<Instant>,
    margin_frac: f64,
    margin_secs: f64,
}

impl Deadline {
    /// Default relative margin on the mean pass duration.
    pub const DEFAULT_MARGIN_FRAC: f64 = 0.25;
    /// Default absolute margin in seconds.
    pub const DEFAULT_MARGIN_SECS: f64 = 0.05;

    /// A deadline at the instant `at`.
    pub fn at(at: Instant) -> Self {
        Deadline { at: Some(at), margin_frac: Self::DEFAULT_MARGIN_FRAC, margin_secs: Self::DEFAULT_MARGIN_SECS }
    }

    /// No time box: every pass may start.
    pub fn never() -> Self {
        Deadline { at: None, margin_frac: Self::DEFAULT_MARGIN_FRAC, margin_secs: Self::DEFAULT_MARGIN_SECS }
    }

    /// A deadline `secs` seconds after `now`. Negative or NaN `secs` mean "already
    /// passed"; infinite `secs` (or an instant beyond the clock's range) mean [`Deadline::never`].
    pub fn after_secs(now: Instant, secs: f64) -> Self {
        if secs == f64::INFINITY {
            return Self::never();
        }
        let secs = if secs.is_nan() || secs < 0.0 { 0.0 } else { secs };
        match Duration::try_from_secs_f64(secs).ok().and_then(|d| now.checked_add(d)) {
            Some(at) => Self::at(at),
            None => Self::never(),
        }
    }

    /// Replaces the margins (negative or NaN values become 0).
    pub fn with_margin(mut self, margin_frac: f64, margin_secs: f64) -> Self {
        self.margin_frac = if margin_frac > 0.0 { margin_frac } else { 0.0 };
        self.margin_secs = if margin_secs > 0.0 { margin_secs } else { 0.0 };
        self
    }

    /// The deadline instant, or `None` for no time box.
    pub fn instant(&self) -> Option<Instant> {
        self.at
    }

    /// Seconds left until the deadline at `now` (0 once passed, infinite without a box).
    pub fn remaining_secs(&self, now: Instant) -> f64 {
        match self.at {
            Some(at) => at.saturating_duration_since(now).as_secs_f64(),
            None => f64::INFINITY,
        }
    }

    /// True if a pass started at `now`, expected to take `mean_pass_secs` (the running mean;
    /// use 0 before any pass finished), ends before the deadline with the margin.
    /// NaN or negative means count as 0.
    pub fn should_start_next(&self, now: Instant, mean_pass_secs: f64) -> bool {
        let Some(at) = self.at else { return true };
        let mean = if mean_pass_secs > 0.0 { mean_pass_secs } else { 0.0 };
        let need = mean * (1.0 + self.margin_frac) + self.margin_secs;
        let left = at.saturating_duration_since(now).as_secs_f64();
        // Strictly before the deadline: nothing starts once it has passed.
        now < at && need <= left
    }

    /// How many passes of `mean_pass_secs` each may start at `now` and all end before the
    /// deadline with the margin (a pass group): `u64::MAX` without a time box or before any pass
    /// finished (mean 0), else `⌊(left − margin_secs) / (mean·(1 + margin_frac))⌋`. At least 1
    /// exactly when [`Deadline::should_start_next`] holds (given a positive mean).
    pub fn passes_that_fit(&self, now: Instant, mean_pass_secs: f64) -> u64 {
        let Some(at) = self.at else { return u64::MAX };
        if mean_pass_secs.is_nan() || mean_pass_secs <= 0.0 {
            return u64::MAX;
        }
        if now >= at {
            return 0;
        }
        let left = at.saturating_duration_since(now).as_secs_f64() - self.margin_secs;
        let n = (left / (mean_pass_secs * (1.0 + self.margin_frac))).floor();
        if n >= 1.0 {
            n.min(u64::MAX as f64) as u64
        } else {
            0
        }
    }
}

/// Running mean of pass durations (seconds), for [`Deadline::should_start_next`].
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct PassTimer {
    count: u64,
    total_secs: f64,
}

impl PassTimer {
    /// An empty timer (mean 0).
    pub fn new() -> Self {
        Self::default()
    }
    /// Records one finished pass. Non-finite or negative durations are ignored.
    pub fn record(&mut self, secs: f64) {
        self.record_group(secs, 1);
    }
    /// Records `n` passes that took `secs` together (a pass group) as `n` passes of `secs / n`.
    /// Non-finite or negative durations are ignored.
    pub fn record_group(&mut self, secs: f64, n: u64) {
        if secs.is_finite() && secs >= 0.0 && n > 0 {
            self.count += n;
            self.total_secs += secs;
        }
    }
    /// Number of recorded passes.
    pub fn count(&self) -> u64 {
        self.count
    }
    /// Mean recorded duration in seconds (0 before the first pass).
    pub fn mean_secs(&self) -> f64 {
        if self.count == 0 {
            0.0
        } else {
            self.total_secs / self.count as f64
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn owner_is_modulo() {
        assert_eq!(pass_owner(0, 3), 0);
        assert_eq!(pass_owner(7, 3), 1);
        assert_eq!(pass_owner(5, 1), 0);
        assert_eq!(pass_owner(5, 0), 0);
    }

    #[test]
    fn passes_partition_the_range() {
        for size in 1..6usize {
            for first in 0..9u64 {
                for total in 0..20u64 {
                    let mut all: Vec<u64> = Vec::new();
                    for rank in 0..size {
                        let mine: Vec<u64> = passes_for_rank(rank, size, first, total).collect();
                        assert!(mine.windows(2).all(|w| w[0] < w[1]));
                        assert!(mine.iter().all(|&p| pass_owner(p, size) == rank));
                        all.extend(mine);
                    }
                    all.sort_unstable();
                    let want: Vec<u64> = (first..total.max(first)).collect();
                    assert_eq!(all, want, "size {size} first {first} total {total}");
                }
            }
        }
    }

    #[test]
    fn passes_examples_and_edges() {
        assert_eq!(passes_for_rank(1, 2, 0, 7).collect::<Vec<_>>(), vec![1, 3, 5]);
        assert_eq!(passes_for_rank(0, 2, 3, 9).collect::<Vec<_>>(), vec![4, 6, 8]);
        assert_eq!(passes_for_rank(2, 2, 0, 9).count(), 0); // rank out of range
        assert_eq!(passes_for_rank(0, 1, 5, 3).count(), 0); // first beyond total
        assert_eq!(passes_for_rank(0, 0, 0, 3).collect::<Vec<_>>(), vec![0, 1, 2]);
        let near_max: Vec<u64> = passes_for_rank(1, 4, u64::MAX - 10, u64::MAX).collect();
        assert!(near_max.iter().all(|&p| p % 4 == 1 && p >= u64::MAX - 10));
    }

    #[test]
    fn rounds_keep_finished_passes_contiguous() {
        for size in 1..5usize {
            for first in 0..7u64 {
                let total = first + 23;
                for rounds in 0..10u64 {
                    let mut done: Vec<u64> =
                        (0..size).flat_map(|r| passes_for_rank(r, size, first, total).take(rounds as usize)).collect();
                    done.sort_unstable();
                    let end = passes_done_after_rounds(first, total, size, rounds);
                    assert_eq!(done, (first..end).collect::<Vec<_>>());
                    assert!(done.iter().all(|&p| round_of(p, size, first).is_some_and(|k| k < rounds)));
                }
            }
        }
        assert_eq!(round_of(3, 2, 5), None);
        assert_eq!(passes_done_after_rounds(10, 5, 3, 4), 5);
    }

    #[test]
    fn deadline_refuses_passes_that_would_overrun() {
        let t0 = Instant::now();
        let d = Deadline::after_secs(t0, 10.0).with_margin(0.25, 0.0);
        assert!(d.should_start_next(t0, 0.0));
        assert!(d.should_start_next(t0, 8.0)); // 10 s needed, 10 s left
        assert!(!d.should_start_next(t0, 8.1)); // 10.125 s needed
        let later = t0 + Duration::from_secs(9);
        assert!(d.should_start_next(later, 0.5));
        assert!(!d.should_start_next(later, 0.9));
        let after = t0 + Duration::from_secs(11);
        assert!(!d.should_start_next(after, 0.0));
        assert_eq!(d.remaining_secs(after), 0.0);
        assert!(!d.should_start_next(t0 + Duration::from_secs(10), 0.0)); // exactly at the deadline
    }

    #[test]
    fn deadline_default_margin_and_edge_inputs() {
        let t0 = Instant::now();
        let d = Deadline::after_secs(t0, 1.0);
        assert!(!d.should_start_next(t0, 0.78)); // 0.78*1.25+0.05 = 1.025 > 1
        assert!(d.should_start_next(t0, 0.7));
        assert!(d.should_start_next(t0, f64::NAN)); // treated as 0
        assert!(!Deadline::after_secs(t0, -3.0).should_start_next(t0, 0.0));
        assert!(!Deadline::after_secs(t0, f64::NAN).should_start_next(t0, 0.0));
        assert!(Deadline::after_secs(t0, f64::INFINITY).should_start_next(t0, 1e300));
        assert!(Deadline::after_secs(t0, 1e300).should_start_next(t0, 1e6)); // beyond clock range
        assert!(Deadline::never().should_start_next(t0, f64::INFINITY));
        assert_eq!(Deadline::never().remaining_secs(t0), f64::INFINITY);
        assert_eq!(Deadline::never().instant(), None);
    }

    #[test]
    fn pass_timer_mean() {
        let mut t = PassTimer::new();
        assert_eq!(t.mean_secs(), 0.0);
        t.record(1.0);
        t.record(3.0);
        t.record(f64::NAN);
        t.record(-1.0);
        assert_eq!((t.count(), t.mean_secs()), (2, 2.0));
        t.record_group(6.0, 3);
        t.record_group(1.0, 0);
        t.record_group(f64::NAN, 2);
        assert_eq!((t.count(), t.mean_secs()), (5, 2.0));
    }

    /// A group of n passes fits exactly when n passes back to back would each be allowed to
    /// start: n·mean·(1 + frac) + secs ≤ left.
    #[test]
    fn passes_that_fit_agrees_with_should_start_next() {
        let t0 = Instant::now();
        let d = Deadline::after_secs(t0, 10.0).with_margin(0.25, 0.5);
        assert_eq!(d.passes_that_fit(t0, 1.0), 7); // 7·1.25 + 0.5 = 9.25 ≤ 10 < 8·1.25 + 0.5
        assert_eq!(d.passes_that_fit(t0, 0.0), u64::MAX, "no pass timed yet");
        assert_eq!(d.passes_that_fit(t0, f64::NAN), u64::MAX);
        assert_eq!(d.passes_that_fit(t0 + Duration::from_secs(11), 1.0), 0);
        assert_eq!(Deadline::never().passes_that_fit(t0, 1.0), u64::MAX);
        for mean in [0.01, 0.3, 1.0, 7.6, 9.5, 12.0] {
            assert_eq!(d.passes_that_fit(t0, mean) >= 1, d.should_start_next(t0, mean), "mean {mean}");
        }
    }

    #[test]
    fn pass_groups_respect_every_bound() {
        let t0 = Instant::now();
        let never = Deadline::never();
        let mut timer = PassTimer::new();
        assert_eq!(pass_group(16, &timer, &never, t0, None), 1, "no pass timed yet");
        timer.record(0.01);
        assert_eq!(pass_group(16, &timer, &never, t0, None), 16, "the limit");
        assert_eq!(pass_group(1, &timer, &never, t0, None), 1, "an integrator with per-pass state");
        assert_eq!(pass_group(16, &timer, &never, t0, Some(5)), 5, "the passes left");
        assert_eq!(pass_group(16, &timer, &never, t0, Some(0)), 1, "at least 1");
        let d = Deadline::after_secs(t0, 0.105).with_margin(0.0, 0.0);
        assert_eq!(pass_group(16, &timer, &d, t0, None), 10, "the time box");
        let mut slow = PassTimer::new();
        slow.record(GROUP_SECS / 3.5);
        assert_eq!(pass_group(16, &slow, &never, t0, None), 3, "about GROUP_SECS per group");
    }
}
