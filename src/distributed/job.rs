//! The ranks' agreement on the job, and the watchdog's time limit.
//!
//! * [`agree_job`] (collective, before any work): every rank sends its job as named fields
//!   (`--method`, `--resolution`, a hash of the scene's content, …) to rank 0, which compares
//!   each field with its own and broadcasts the verdict. A mismatch is an error on every rank that
//!   names each differing field and the ranks' values (`mpirun -n 1 A : -n 1 B` with another
//!   `--method` would otherwise hang, another `--resolution` would fail in a reduction, another
//!   scene or seed would sum two images into one).
//! * [`watchdog_limit`]: how long past the time budget a rank may wait inside one collective
//!   before its [`Cluster::watch`] watchdog ends the job (`MPI_Abort`, with a message): a rank that
//!   was stopped (SIGSTOP), hangs or died without MPI noticing would hold the others forever.
//!   Armed for time-boxed renders only (an spp render has no budget to hold it to).
//! * [`heartbeat_limit`]: the heartbeat, for every render, `--spp` ones included. Each round of
//!   the pass loop is a beat ([`Cluster::beat`], called by `agree_round`); once a rank has seen one
//!   whole round, a collective it waits in longer than `max(floor, HEARTBEAT_FACTOR × the slowest
//!   round it has seen)` ends the job the same way. The floor is 60 s, or
//!   `FORECAST_MPI_HEARTBEAT` seconds (`off` turns the heartbeat off: [`heartbeat_floor`]). Before
//!   the first whole round (setup, the preprocess) only the time budget holds.
//!
//! Neither rule touches the render's state (they only read clocks), so they cannot change an image.

use super::{Cluster, ClusterError};
use std::time::{Duration, Instant};

/// One field of a job as the ranks compare it: its name (the option, or what it covers) and its
/// value (the value itself when short, else a hash of it).
pub type JobField = (&'static str, String);

/// Checks that every rank runs the same `fields` (collective; see the module docs). The error
/// ([`ClusterError::JobMismatch`]) is the same on every rank and names every differing field.
pub fn agree_job(c: &dyn Cluster, fields: &[JobField]) -> Result<(), ClusterError> {
    if c.size() == 1 {
        return Ok(());
    }
    let mine = encode(fields);
    // rank 0's verdict, one differing field a line (none: the jobs agree)
    let mut verdict = match c.gather_bytes(&mine) {
        Some(all) => compare(fields, &all).join("\n").into_bytes(),
        None => Vec::new(),
    };
    c.broadcast_bytes(&mut verdict);
    if verdict.is_empty() {
        return Ok(());
    }
    let differences = String::from_utf8_lossy(&verdict).lines().map(str::to_string).collect();
    Err(ClusterError::JobMismatch { differences })
}

/// `name=value` lines (a value never holds a newline: [`JobField`] values are short or hashed).
fn encode(fields: &[JobField]) -> Vec<u8> {
    fields.iter().map(|(k, v)| format!("{k}={}\n", v.replace('\n', " "))).collect::<String>().into_bytes()
}

/// Rank 0's verdict on the gathered jobs, one entry per field that differs (a value never holds a
/// newline): empty when they all equal rank 0's.
fn compare(fields: &[JobField], all: &[Vec<u8>]) -> Vec<String> {
    let mut differ = Vec::new();
    for (k, v) in fields {
        let line = |b: &Vec<u8>| {
            let text = String::from_utf8_lossy(b).into_owned();
            text.lines().find_map(|l| l.strip_prefix(&format!("{k}=")).map(str::to_string))
        };
        let others: Vec<String> = all
            .iter()
            .enumerate()
            .skip(1)
            .filter_map(|(r, b)| match line(b) {
                Some(o) if o == *v => None,
                o => Some(format!("rank {r} `{}`", o.unwrap_or_else(|| "missing".into()))),
            })
            .collect();
        if !others.is_empty() {
            differ.push(format!("{k} differs (rank 0 `{v}`, {})", others.join(", ")));
        }
    }
    differ
}

/// How long past the budget's end a rank may wait in one collective: 10 s plus a quarter of the
/// budget (the last round's passes and rank 0's writes take about one pass past the deadline).
pub fn watchdog_grace(budget_secs: f64) -> Duration {
    Duration::from_secs_f64(10.0 + 0.25 * budget_secs.clamp(0.0, 1e9))
}

/// The watchdog's rule: a rank that entered a collective at `waiting_since` gives up at
/// `max(deadline, waiting_since) + grace`. `true` when `now` is past it.
pub fn watchdog_fires(now: Instant, waiting_since: Instant, deadline: Instant, grace: Duration) -> bool {
    now > deadline.max(waiting_since) + grace
}

/// The watchdog's time limit for a render with `budget_secs` whose deadline is `deadline`: `None`
/// without a finite budget (see the module docs).
pub fn watchdog_limit(deadline: Instant, budget_secs: Option<f64>) -> Option<(Instant, Duration)> {
    budget_secs.filter(|b| b.is_finite()).map(|b| (deadline, watchdog_grace(b)))
}

/// The environment variable that sets the heartbeat's floor (seconds, or `off`).
pub const HEARTBEAT_ENV: &str = "FORECAST_MPI_HEARTBEAT";

/// The heartbeat's floor without [`HEARTBEAT_ENV`]: rank 0's writes at the end of the render (and
/// its checkpoints) happen while the others wait in a collective, and take well under this.
pub const DEFAULT_HEARTBEAT_FLOOR: Duration = Duration::from_secs(60);

/// How many times the slowest round seen a wait in a collective may last.
pub const HEARTBEAT_FACTOR: u32 = 10;

/// The heartbeat's floor from the value of [`HEARTBEAT_ENV`] (`None`: unset): `Ok(None)` for
/// `off`, the default when unset or empty, else seconds in `(0, 10^6]`.
pub fn heartbeat_floor(value: Option<&str>) -> Result<Option<Duration>, ClusterError> {
    let v = value.map(str::trim).unwrap_or("");
    if v.is_empty() {
        return Ok(Some(DEFAULT_HEARTBEAT_FLOOR));
    }
    if v.eq_ignore_ascii_case("off") {
        return Ok(None);
    }
    match v.parse::<f64>() {
        Ok(s) if s > 0.0 && s <= 1e6 => Ok(Some(Duration::from_secs_f64(s))),
        _ => Err(ClusterError::BadHeartbeat { value: v.to_string() }),
    }
}

/// The heartbeat's limit on one wait in a collective: `max(floor, HEARTBEAT_FACTOR × slowest)`
/// once a whole round has been seen (`slowest`), `None` before (or without a `floor`: off).
pub fn heartbeat_limit(floor: Option<Duration>, slowest: Option<Duration>) -> Option<Duration> {
    Some(floor?.max(slowest? * HEARTBEAT_FACTOR))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_differing_field_is_named_with_every_value() {
        let a: Vec<JobField> = vec![("--method", "pt".into()), ("--seed", "1".into())];
        let b: Vec<JobField> = vec![("--method", "iws".into()), ("--seed", "1".into())];
        let verdict = |all: &[Vec<u8>]| ClusterError::JobMismatch { differences: compare(&a, all) }.to_string();
        assert!(compare(&a, &[encode(&a), encode(&a)]).is_empty());
        let e = verdict(&[encode(&a), encode(&b), encode(&a)]);
        assert!(e.contains("--method differs (rank 0 `pt`, rank 1 `iws`)"), "{e}");
        assert!(!e.contains("--seed"), "{e}");
        let e = verdict(&[encode(&a), encode(&a[..1])]);
        assert!(e.contains("--seed differs (rank 0 `1`, rank 1 `missing`)"), "{e}");
        assert!(e.starts_with("the MPI ranks were started with different jobs: "), "{e}");
        let c = super::super::local::Local::new();
        assert_eq!(agree_job(&c, &a), Ok(()));
    }

    #[test]
    fn the_watchdog_waits_past_the_deadline_and_the_entry() {
        let t0 = Instant::now();
        let g = watchdog_grace(4.0);
        assert_eq!(g, Duration::from_secs(11));
        let deadline = t0 + Duration::from_secs(4);
        assert!(!watchdog_fires(t0 + Duration::from_secs(14), t0, deadline, g));
        assert!(watchdog_fires(t0 + Duration::from_secs(16), t0, deadline, g));
        // entered late: counted from the entry
        let late = t0 + Duration::from_secs(20);
        assert!(!watchdog_fires(t0 + Duration::from_secs(30), late, deadline, g));
        assert!(watchdog_fires(t0 + Duration::from_secs(32), late, deadline, g));
        assert!(watchdog_limit(deadline, None).is_none());
        assert!(watchdog_limit(deadline, Some(f64::INFINITY)).is_none());
    }

    #[test]
    fn the_heartbeat_is_the_floor_or_ten_slowest_rounds() {
        let s = Duration::from_secs;
        assert_eq!(heartbeat_floor(None), Ok(Some(s(60))));
        assert_eq!(heartbeat_floor(Some(" ")), Ok(Some(s(60))));
        assert_eq!(heartbeat_floor(Some("OFF")), Ok(None));
        assert_eq!(heartbeat_floor(Some("2.5")), Ok(Some(Duration::from_millis(2500))));
        for bad in ["0", "-1", "nan", "inf", "1e7", "5s"] {
            assert_eq!(heartbeat_floor(Some(bad)), Err(ClusterError::BadHeartbeat { value: bad.into() }));
        }
        // no whole round seen yet, or off: no limit
        assert_eq!(heartbeat_limit(Some(s(60)), None), None);
        assert_eq!(heartbeat_limit(None, Some(s(1))), None);
        assert_eq!(heartbeat_limit(Some(s(60)), Some(s(1))), Some(s(60)));
        assert_eq!(heartbeat_limit(Some(s(60)), Some(s(7))), Some(s(70)));
    }
}
