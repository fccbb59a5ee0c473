//! Cluster abstraction: the few collective operations the renderer needs to split
//! progressive passes across processes and combine their films.
//!
//! * [`Cluster`] is the trait the renderer talks to; it never touches MPI directly.
//! * [`local::Local`] is the single-process implementation (rank 0 of 1); every
//!   collective is the identity.
//! * `mpi::MpiCluster` (only with the cargo feature `mpi`) wraps an MPI world
//!   communicator. It also works as a singleton (size 1) when started without `mpirun`.
//! * [`schedule`] holds the pure pass-ownership and time-box arithmetic.
//! * [`job`]: the ranks' agreement on the job before any work ([`job::agree_job`]) and the
//!   watchdog's limits ([`Cluster::watch`], armed by [`shared_deadline`] for a time box; the
//!   heartbeat of [`Cluster::beat`], once per round of [`agree_round`], for every render).
//! * `error`: [`ClusterError`], the errors of this module's functions.
//!
//! Invariants every implementation keeps:
//! * `rank() < size()` and `size() >= 1`.
//! * Every collective (all methods except `rank`/`size`) must be called by **all** ranks,
//!   in the same order, with the same slice lengths where the method says so; otherwise
//!   MPI deadlocks. Length disagreements that can be detected cheaply cause a panic with a
//!   message naming the lengths, on every rank, rather than a hang or silent corruption.
//! * Message sizes are unlimited: payloads whose element count exceeds `i32::MAX` are split
//!   into chunks internally.

mod error;
pub mod job;
pub mod local;
#[cfg(feature = "mpi")]
pub mod mpi;
pub mod schedule;

use std::time::Instant;

pub use error::ClusterError;
use schedule::Deadline;

/// Collective operations over a group of cooperating processes ("ranks").
///
/// All methods except [`Cluster::rank`] and [`Cluster::size`] are collective: every rank
/// must call them in the same order.
pub trait Cluster {
    /// This process's index in `0..size()`.
    fn rank(&self) -> usize;
    /// Number of cooperating processes (at least 1).
    fn size(&self) -> usize;
    /// Rank 0's bytes are copied to every rank (length first, then payload; chunk payloads > i32::MAX).
    /// On ranks other than 0 the vector's previous contents and length are replaced.
    fn broadcast_bytes(&self, bytes: &mut Vec<u8>);
    /// Element-wise sum over ranks into rank 0: returns Some(sum) on rank 0, None elsewhere.
    /// All ranks must pass slices of the same length (checked; mismatch panics on every rank).
    fn reduce_sum(&self, local: &[f64]) -> Option<Vec<f64>>;
    /// Element-wise sum to all ranks (for agreeing on deadlines/counters).
    /// All ranks must pass slices of the same length (checked; mismatch panics on every rank).
    fn all_reduce_sum(&self, local: &[f64]) -> Vec<f64>;
    /// Max over ranks to all ranks.
    fn all_reduce_max(&self, local: f64) -> f64;
    /// Gather one small byte blob per rank onto rank 0 (per-rank stats JSON): Some(vec per rank) on rank 0,
    /// indexed by rank; None elsewhere. Blobs may have different lengths, including zero.
    fn gather_bytes(&self, local: &[u8]) -> Option<Vec<Vec<u8>>>;
    /// Blocks until every rank has reached it.
    fn barrier(&self);
    /// Arms (`Some((deadline, grace))`) or disarms (`None`) this rank's watchdog: a collective
    /// still waiting at `max(deadline, entry) + grace` ends the whole job with a message (MPI:
    /// `MPI_Abort`). Not collective. The default, for a single process, does nothing (nobody
    /// else can be waited for).
    /// Also starts a new heartbeat: the rounds seen so far are forgotten.
    fn watch(&self, _limit: Option<(Instant, std::time::Duration)>) {}
    /// One beat of the heartbeat (not collective): a round of the pass loop starts. Once a rank
    /// has seen a whole round, a collective waiting longer than [`job::heartbeat_limit`] ends the
    /// whole job with a message (MPI: `MPI_Abort`). The default, for a single process, does
    /// nothing.
    fn beat(&self) {}
}

/// Starts the cluster: the MPI world when built with feature `mpi` (also works as a
/// singleton without `mpirun`), else [`local::Local`].
///
/// # Panics
/// When [`try_init`] fails (MPI already initialised in this process, or a non-MPI build
/// started by `mpirun -n N` with N > 1). Use [`try_init`] to handle that yourself.
/// Keep the returned box alive until the end of `main`: dropping it calls `MPI_Finalize`.
pub fn init() -> Box<dyn Cluster> {
    match try_init() {
        Ok(c) => c,
        Err(e) => panic!("cluster init failed: {e}"),
    }
}

/// Like [`init`] but returns an error instead of panicking.
///
/// Errors:
/// * feature `mpi`: MPI was already initialised in this process (call `init` once).
/// * no feature `mpi`: the process was started by a launcher (`mpirun`/`srun`) that says
///   there are several ranks. Each rank would otherwise render the whole image alone and
///   they would all write the same output files.
pub fn try_init() -> Result<Box<dyn Cluster>, ClusterError> {
    #[cfg(feature = "mpi")]
    {
        let c = mpi::MpiCluster::init()?;
        Ok(Box::new(c))
    }
    #[cfg(not(feature = "mpi"))]
    {
        if let Some((var, n)) = launcher_world_size() {
            if n > 1 {
                return Err(ClusterError::NoMpiFeature { var, ranks: n });
            }
        }
        Ok(Box::new(local::Local::new()))
    }
}

/// World size announced by a process launcher through the environment, if any
/// (MPICH/Hydra `PMI_SIZE`, Open MPI `OMPI_COMM_WORLD_SIZE`, Slurm `SLURM_NTASKS`).
#[cfg_attr(feature = "mpi", allow(dead_code))]
fn launcher_world_size() -> Option<(&'static str, usize)> {
    for var in ["PMI_SIZE", "OMPI_COMM_WORLD_SIZE", "PMIX_SIZE"] {
        if let Ok(v) = std::env::var(var) {
            if let Ok(n) = v.trim().parse::<usize>() {
                return Some((var, n));
            }
        }
    }
    None
}

/// True on every rank iff `local_ok` is true on every rank (one tiny all-reduce).
///
/// Use it once per round of passes with the local [`Deadline::should_start_next`] answer so
/// that all ranks render the same number of rounds and the finished passes stay a
/// contiguous range (see [`schedule`]).
pub fn all_agree(c: &dyn Cluster, local_ok: bool) -> bool {
    let veto = if local_ok { 0.0 } else { 1.0 };
    c.all_reduce_max(veto) == 0.0
}

/// `result` if it is `Ok` on every rank; an error on every rank otherwise (collective).
///
/// The failing ranks' messages are gathered to rank 0, whose error names them all (one message
/// when they agree, else `rank r: …` each: [`ClusterError::Failed`]); the other ranks' error is a
/// stand-in ([`ClusterError::FailedElsewhere`]), which the binary does not print (rank 0 prints
/// the job's error once). Costs one 8-byte all-reduce when
/// every rank succeeded. Any error that could end one rank early goes through here, so no rank
/// is left waiting in a collective for a rank that has left.
///
/// A typed error (`E`, sent as its message) comes back as itself where the agreed message is
/// its own (rank 0's error, alone or the same on every failing rank), else as the agreed
/// [`ClusterError`] (`E::from`).
pub fn agree<T, E: std::fmt::Display + From<ClusterError>>(c: &dyn Cluster, result: Result<T, E>) -> Result<T, E> {
    let failed = c.all_reduce_max(if result.is_err() { 1.0 } else { 0.0 }) > 0.0;
    if !failed {
        return result;
    }
    let mine = result.as_ref().err().map(|e| e.to_string()).unwrap_or_default();
    let agreed = match c.gather_bytes(mine.as_bytes()) {
        Some(blobs) => combine_errors(&blobs),
        None => ClusterError::FailedElsewhere,
    };
    match result {
        Err(e) if agreed.to_string() == mine => Err(e),
        _ => Err(E::from(agreed)),
    }
}

/// The gathered messages (empty: that rank did not fail), one entry per distinct message with
/// the ranks that had it ([`ClusterError::Failed`] names the ranks when there is more than one).
fn combine_errors(blobs: &[Vec<u8>]) -> ClusterError {
    let mut failures: Vec<(Vec<usize>, String)> = Vec::new();
    for (rank, b) in blobs.iter().enumerate().filter(|(_, b)| !b.is_empty()) {
        let msg = String::from_utf8_lossy(b).into_owned();
        match failures.iter_mut().find(|(_, m)| *m == msg) {
            Some((ranks, _)) => ranks.push(rank),
            None => failures.push((vec![rank], msg)),
        }
    }
    ClusterError::Failed { failures, ranks: blobs.len() }
}

/// The once-per-round agreement of the pass loop (collective): `Ok(true)` when every rank wants
/// another round, `Ok(false)` when one wants to stop (time box), and the [`agree`]d error on every
/// rank when one has a `failure` (a failed write inside the loop, say). Each call is a beat of the
/// heartbeat ([`Cluster::beat`]).
pub fn agree_round<E: std::fmt::Display + From<ClusterError>>(
    c: &dyn Cluster,
    go: bool,
    failure: Option<E>,
) -> Result<bool, E> {
    c.beat();
    let status = if failure.is_some() {
        2.0
    } else if go {
        0.0
    } else {
        1.0
    };
    let all = c.all_reduce_max(status);
    if all >= 2.0 {
        return agree(c, failure.map_or(Ok(false), Err));
    }
    Ok(all == 0.0)
}

/// True on every rank when `flag` is true on any (collective).
pub fn agree_any(c: &dyn Cluster, flag: bool) -> bool {
    c.all_reduce_max(if flag { 1.0 } else { 0.0 }) > 0.0
}

/// The least of every rank's `v` (collective; exact below 2^53).
pub fn agree_min(c: &dyn Cluster, v: u64) -> u64 {
    let m = -c.all_reduce_max(-(v.min(1 << 53) as f64));
    m as u64
}

/// Rank 0's `v` on every rank (collective); `what` names it in the error of a malformed broadcast.
pub fn broadcast_u64(c: &dyn Cluster, v: u64, what: &str) -> Result<u64, ClusterError> {
    let mut bytes = v.to_le_bytes().to_vec();
    c.broadcast_bytes(&mut bytes);
    bytes
        .as_slice()
        .try_into()
        .map(u64::from_le_bytes)
        .map_err(|_| ClusterError::BadBroadcast { what: what.to_string(), len: bytes.len() })
}

/// Builds a [`Deadline`] shared by all ranks for a time box of `budget_secs` seconds
/// counted from rank 0's `local_start` (e.g. the instant rank 0's process started).
///
/// Rank 0 computes the remaining time and broadcasts it; every rank sets its deadline to
/// "now + remaining", so the ranks agree up to the broadcast latency. `None`, a NaN or an
/// infinite budget gives [`Deadline::never`]. Collective: call on all ranks. A finite budget
/// also arms every rank's watchdog ([`Cluster::watch`], [`job::watchdog_limit`]); the caller
/// disarms it when the render is over.
pub fn shared_deadline(c: &dyn Cluster, local_start: Instant, budget_secs: Option<f64>) -> Deadline {
    let mut bytes = Vec::new();
    if c.rank() == 0 {
        let remaining = match budget_secs {
            Some(b) if b.is_finite() => (b - local_start.elapsed().as_secs_f64()).max(0.0),
            _ => f64::INFINITY,
        };
        bytes = remaining.to_le_bytes().to_vec();
    }
    c.broadcast_bytes(&mut bytes);
    let remaining = match <[u8; 8]>::try_from(bytes.as_slice()) {
        Ok(b) => f64::from_le_bytes(b),
        Err(_) => f64::INFINITY, // cannot happen: rank 0 always sends 8 bytes
    };
    let now = Instant::now();
    if let Some(at) = std::time::Duration::try_from_secs_f64(remaining).ok().and_then(|d| now.checked_add(d)) {
        c.watch(job::watchdog_limit(at, budget_secs));
    }
    Deadline::after_secs(now, remaining)
}

/// Checks every collective of `c` with known data; meant for `forecast mpi-selftest`.
///
/// Collective: call on all ranks. Returns the same verdict on every rank; rank 0's error
/// message lists the failures of all ranks. Exercises: a 3 MB and an empty broadcast,
/// `reduce_sum`, `all_reduce_sum`, `all_reduce_max` (with negative values), `gather_bytes`
/// with per-rank lengths (rank 0's blob is empty) and `barrier`.
pub fn self_test(c: &dyn Cluster) -> Result<(), ClusterError> {
    let (rank, size) = (c.rank(), c.size());
    if size == 0 || rank >= size {
        return Err(ClusterError::BadTopology { rank, size });
    }
    let mut errs: Vec<String> = Vec::new();
    check_broadcast(c, &mut errs);
    check_sums(c, &mut errs);
    // all_reduce_max with negative values: the max is the last rank's value.
    let m = c.all_reduce_max(rank as f64 * 1.5 - 1000.0);
    let want = (size - 1) as f64 * 1.5 - 1000.0;
    if m != want {
        errs.push(format!("all_reduce_max: {m} != {want}"));
    }
    check_gather(c, &mut errs);
    c.barrier();
    self_test_verdict(c, &errs)
}

/// `self_test`'s broadcasts: 3 MB from rank 0 (other ranks start with a short, different
/// buffer), then an empty one.
fn check_broadcast(c: &dyn Cluster, errs: &mut Vec<String>) {
    let pattern = |i: usize| ((i.wrapping_mul(31) + 7) % 251) as u8;
    let n = 3 * 1024 * 1024 + 17;
    let mut buf: Vec<u8> = if c.rank() == 0 { (0..n).map(pattern).collect() } else { vec![0xAB; 5] };
    c.broadcast_bytes(&mut buf);
    if buf.len() != n {
        errs.push(format!("broadcast: length {} != {n}", buf.len()));
    } else if let Some(i) = (0..n).find(|&i| buf[i] != pattern(i)) {
        errs.push(format!("broadcast: byte {i} is {} != {}", buf[i], pattern(i)));
    }
    let mut empty: Vec<u8> = if c.rank() == 0 { Vec::new() } else { vec![1, 2, 3] };
    c.broadcast_bytes(&mut empty);
    if !empty.is_empty() {
        errs.push(format!("broadcast of empty buffer left {} bytes", empty.len()));
    }
}

/// `self_test`'s `reduce_sum` and `all_reduce_sum`: integers (and halves), so the f64 sums are
/// exact.
fn check_sums(c: &dyn Cluster, errs: &mut Vec<String>) {
    let (rank, size) = (c.rank(), c.size());
    let len = 100_003;
    let local: Vec<f64> = (0..len).map(|i| (rank + 1) as f64 * i as f64 - 0.5).collect();
    let tri = (size * (size + 1) / 2) as f64;
    let expect = |i: usize| tri * i as f64 - 0.5 * size as f64;
    match (rank, c.reduce_sum(&local)) {
        (0, Some(sum)) => {
            if sum.len() != len {
                errs.push(format!("reduce_sum: length {} != {len}", sum.len()));
            } else if let Some(i) = (0..len).find(|&i| sum[i] != expect(i)) {
                errs.push(format!("reduce_sum: element {i} is {} != {}", sum[i], expect(i)));
            }
        }
        (0, None) => errs.push("reduce_sum returned None on rank 0".into()),
        (_, Some(_)) => errs.push("reduce_sum returned Some on a non-root rank".into()),
        (_, None) => {}
    }
    let all = c.all_reduce_sum(&local[..1000]);
    if all.len() != 1000 {
        errs.push(format!("all_reduce_sum: length {} != 1000", all.len()));
    } else if let Some(i) = (0..1000).find(|&i| all[i] != expect(i)) {
        errs.push(format!("all_reduce_sum: element {i} is {} != {}", all[i], expect(i)));
    }
    if !c.all_reduce_sum(&[]).is_empty() {
        errs.push("all_reduce_sum of an empty slice is not empty".into());
    }
}

/// `self_test`'s `gather_bytes` with different lengths per rank (rank 0 sends nothing).
fn check_gather(c: &dyn Cluster, errs: &mut Vec<String>) {
    let (rank, size) = (c.rank(), c.size());
    let blob = |r: usize| -> Vec<u8> { (0..r * 3).map(|k| (r * 7 + k) as u8).collect() };
    match (rank, c.gather_bytes(&blob(rank))) {
        (0, Some(v)) => {
            if v.len() != size {
                errs.push(format!("gather_bytes: {} blobs for {size} ranks", v.len()));
            }
            for (r, b) in v.iter().enumerate().filter(|(r, b)| **b != blob(*r)) {
                errs.push(format!("gather_bytes: blob of rank {r} wrong ({} bytes)", b.len()));
            }
        }
        (0, None) => errs.push("gather_bytes returned None on rank 0".into()),
        (_, Some(_)) => errs.push("gather_bytes returned Some on a non-root rank".into()),
        (_, None) => {}
    }
}

/// Agrees on `self_test`'s verdict and brings every rank's messages to rank 0.
fn self_test_verdict(c: &dyn Cluster, errs: &[String]) -> Result<(), ClusterError> {
    let rank = c.rank();
    let text = errs.iter().map(|e| format!("rank {rank}: {e}")).collect::<Vec<_>>().join("\n");
    let all_text = c.gather_bytes(text.as_bytes());
    let failures = c.all_reduce_sum(&[errs.len() as f64])[0];
    if failures == 0.0 {
        return Ok(());
    }
    let report = all_text.map(|v| {
        v.iter()
            .filter(|b| !b.is_empty())
            .map(|b| String::from_utf8_lossy(b).into_owned())
            .collect::<Vec<_>>()
            .join("\n")
    });
    Err(ClusterError::SelfTest { failures: failures as u64, report })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn self_test_passes_on_local() {
        let c = local::Local::new();
        assert_eq!(self_test(&c), Ok(()));
    }

    #[test]
    fn all_agree_local() {
        let c = local::Local::new();
        assert!(all_agree(&c, true));
        assert!(!all_agree(&c, false));
    }

    #[test]
    fn agreed_errors_name_each_failing_rank() {
        let c = local::Local::new();
        assert_eq!(agree(&c, Ok::<u8, String>(3)), Ok(3));
        assert_eq!(agree(&c, Err::<u8, String>("disk full".into())), Err("disk full".into()));
        assert_eq!(agree_round(&c, true, None::<String>), Ok(true));
        assert_eq!(agree_round(&c, false, None::<String>), Ok(false));
        assert_eq!(agree_round(&c, true, Some("x".to_string())), Err("x".to_string()));
        let blobs = |v: &[&str]| v.iter().map(|s| s.as_bytes().to_vec()).collect::<Vec<_>>();
        let combined = |v: &[&str]| combine_errors(&blobs(v)).to_string();
        assert_eq!(combined(&["a", "a"]), "a");
        assert_eq!(combined(&["a", ""]), "a");
        assert_eq!(combined(&["", "b"]), "rank 1: b");
        assert_eq!(combined(&["a", "b", "a"]), "rank 0,2: a; rank 1: b");
        assert_eq!(
            combine_errors(&blobs(&["", "b"])),
            ClusterError::Failed { failures: vec![(vec![1], "b".into())], ranks: 2 }
        );
        assert_eq!(ClusterError::FailedElsewhere.to_string(), "the job failed on another rank (rank 0 reports it)");
    }

    /// A rank's own typed error comes back as itself (one rank: the agreed message is its own).
    #[test]
    fn agree_keeps_a_typed_error() {
        #[derive(Debug, PartialEq)]
        enum Typed {
            Mine(u8),
            Agreed(String),
        }
        impl std::fmt::Display for Typed {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                match self {
                    Typed::Mine(n) => write!(f, "error {n}"),
                    Typed::Agreed(m) => write!(f, "{m}"),
                }
            }
        }
        impl From<ClusterError> for Typed {
            fn from(e: ClusterError) -> Typed {
                Typed::Agreed(e.to_string())
            }
        }
        let c = local::Local::new();
        assert_eq!(agree(&c, Err::<(), _>(Typed::Mine(7))), Err(Typed::Mine(7)));
        assert_eq!(agree(&c, Ok::<u8, Typed>(1)), Ok(1));
    }

    #[test]
    fn shared_deadline_local() {
        let c = local::Local::new();
        let start = Instant::now();
        let d = shared_deadline(&c, start, Some(3600.0));
        assert!(d.should_start_next(Instant::now(), 1.0));
        let d = shared_deadline(&c, start, Some(0.0));
        assert!(!d.should_start_next(Instant::now(), 0.0));
        let d = shared_deadline(&c, start, None);
        assert!(d.should_start_next(Instant::now(), 1e12));
        let d = shared_deadline(&c, start, Some(f64::NAN));
        assert!(d.should_start_next(Instant::now(), 1e12));
    }
}
