//! [`Cluster`] over an MPI world communicator (rsmpi 0.8, tested with MPICH 4.0.2).
//!
//! Compiled only with the cargo feature `mpi`. Started without `mpirun` it is a singleton
//! world of size 1.
//!
//! Invariants and choices:
//! * MPI is initialised with `Threading::Funneled`: only the thread that called
//!   [`MpiCluster::init`] (the main thread) may call the collectives; rayon workers must not.
//! * The `Universe` lives inside the struct; dropping the cluster calls `MPI_Finalize`.
//!   Keep it alive until the end of `main` (and avoid `std::process::exit` before that).
//! * MPI counts are `i32`: every payload is split into chunks of at most
//!   `max_chunk_bytes` bytes (default 1 GiB), so any length works.
//! * Reductions first agree on the slice length with one tiny all-reduce; a mismatch panics
//!   on every rank with both lengths named, instead of deadlocking or reading out of bounds.
//!   (The pipeline's `job::agree_job` refuses mismatched jobs before any of these.)
//! * The watchdog: every collective marks this rank as waiting while it runs; a thread (started
//!   by `init`, it calls nothing of MPI but `MPI_Abort`) checks the mark five times a second
//!   against the limit armed by [`Cluster::watch`] (`job::watchdog_fires`) and against the
//!   heartbeat (`job::heartbeat_limit`: the slowest interval between two [`Cluster::beat`]s,
//!   floor from `FORECAST_MPI_HEARTBEAT`, read once by `init`), and past either prints which rank
//!   gave up after how long and why, and ends the whole job with `MPI_Abort` (exit 1).

use ::mpi::collective::SystemOperation;
use ::mpi::datatype::PartitionMut;
use ::mpi::environment::Universe;
use ::mpi::topology::SimpleCommunicator;
use ::mpi::traits::*;
use ::mpi::Threading;

use super::{job, Cluster, ClusterError};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// The watchdog's state, shared with its thread: since when this rank waits in a collective
/// (milliseconds since `epoch`, plus 1; 0 = not waiting), the armed limit, and the heartbeat:
/// its floor (`None`: off), the last beat (as `waiting_since_ms`) and the slowest interval
/// between two beats (ms; 0 = no whole round seen yet).
struct Watch {
    epoch: Instant,
    waiting_since_ms: AtomicU64,
    limit: Mutex<Option<(Instant, Duration)>>,
    heartbeat_floor: Option<Duration>,
    last_beat_ms: AtomicU64,
    slowest_round_ms: AtomicU64,
}

/// Why the watchdog gives up on a wait.
enum Overdue {
    /// Past the time budget's deadline plus the grace: (waited, past the deadline).
    Budget(Duration, Duration),
    /// Past the heartbeat's limit: (waited, the slowest round, the limit).
    Heartbeat(Duration, Duration, Duration),
}

/// Marks the rank as waiting in a collective while it lives.
struct InCollective<'a>(&'a Watch);

impl Drop for InCollective<'_> {
    fn drop(&mut self) {
        self.0.waiting_since_ms.store(0, Ordering::Relaxed);
    }
}

impl Watch {
    /// Now, in milliseconds since `epoch`, plus 1 (never 0).
    fn now_ms(&self) -> u64 {
        u64::try_from(self.epoch.elapsed().as_millis()).unwrap_or(u64::MAX - 1) + 1
    }

    fn enter(&self) -> InCollective<'_> {
        self.waiting_since_ms.store(self.now_ms(), Ordering::Relaxed);
        InCollective(self)
    }

    /// A beat: the interval since the last one is a whole round.
    fn beat(&self) {
        let now = self.now_ms();
        let last = self.last_beat_ms.swap(now, Ordering::Relaxed);
        if last > 0 {
            self.slowest_round_ms.fetch_max(now.saturating_sub(last), Ordering::Relaxed);
        }
    }

    /// The check of one tick: why and after how long, when a limit is passed.
    fn overdue(&self, now: Instant) -> Option<Overdue> {
        let since = self.waiting_since_ms.load(Ordering::Relaxed);
        if since == 0 {
            return None;
        }
        let entered = self.epoch + Duration::from_millis(since - 1);
        let waited = now.saturating_duration_since(entered);
        let limit = *self.limit.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((deadline, grace)) = limit {
            if job::watchdog_fires(now, entered, deadline, grace) {
                return Some(Overdue::Budget(waited, now.saturating_duration_since(deadline)));
            }
        }
        let slowest = match self.slowest_round_ms.load(Ordering::Relaxed) {
            0 => None,
            ms => Some(Duration::from_millis(ms)),
        };
        let beat = job::heartbeat_limit(self.heartbeat_floor, slowest)?;
        (waited > beat).then(|| Overdue::Heartbeat(waited, slowest.unwrap_or_default(), beat))
    }
}

/// Starts the watchdog thread of rank `rank` with the heartbeat's floor `heartbeat_floor` (a
/// warning, and no watchdog, if it cannot start).
fn start_watchdog(rank: usize, heartbeat_floor: Option<Duration>) -> Arc<Watch> {
    let watch = Arc::new(Watch {
        epoch: Instant::now(),
        waiting_since_ms: AtomicU64::new(0),
        limit: Mutex::new(None),
        heartbeat_floor,
        last_beat_ms: AtomicU64::new(0),
        slowest_round_ms: AtomicU64::new(0),
    });
    let w = Arc::clone(&watch);
    let spawned = std::thread::Builder::new().name("mpi-watchdog".into()).spawn(move || loop {
        std::thread::sleep(Duration::from_millis(200));
        if let Some(why) = w.overdue(Instant::now()) {
            let why = match why {
                Overdue::Budget(waited, past) => format!(
                    "waited {:.1} s in a collective, {:.1} s past the time budget",
                    waited.as_secs_f64(),
                    past.as_secs_f64()
                ),
                Overdue::Heartbeat(waited, slowest, limit) => format!(
                    "waited {:.1} s in a collective, past the heartbeat's {:.1} s (the larger of its floor, {}, \
                     and {} x the slowest round so far, {:.2} s)",
                    waited.as_secs_f64(),
                    limit.as_secs_f64(),
                    heartbeat_floor.map_or_else(String::new, |f| format!("{} s", f.as_secs_f64())),
                    job::HEARTBEAT_FACTOR,
                    slowest.as_secs_f64()
                ),
            };
            crate::errln!(
                "error: rank {rank} {why}: another rank stopped responding (stopped, hung or lost, or its network \
                 link is down); ending the job (MPI_Abort)"
            );
            // the message travels to mpiexec through this host's process manager, which the
            // abort tears down: give it half a second to get there (without it, 2 of 7 runs of
            // the netns link-down test ended with an empty stderr)
            std::thread::sleep(Duration::from_millis(500));
            // SAFETY: MPI_Abort on the world communicator, which outlives every rank's threads;
            // MPICH accepts it from any thread and ends every process of the job.
            unsafe {
                ::mpi::ffi::MPI_Abort(::mpi::ffi::RSMPI_COMM_WORLD, 1);
            }
            std::process::exit(1);
        }
    });
    if let Err(e) = spawned {
        crate::errln!("warning: rank {rank}: cannot start the MPI watchdog ({e}); a stopped rank would hold the job");
    }
    watch
}

/// Default largest chunk of one MPI call, in bytes (1 GiB, well below `i32::MAX`).
pub const DEFAULT_MAX_CHUNK_BYTES: usize = 1 << 30;

/// The MPI world as a [`Cluster`]. Dropping it finalises MPI.
pub struct MpiCluster {
    // Field order matters: `world` is dropped before `universe` (which calls MPI_Finalize).
    world: SimpleCommunicator,
    rank: usize,
    size: usize,
    provided: Threading,
    max_chunk_bytes: usize,
    watch: Arc<Watch>,
    _universe: Universe,
}

impl MpiCluster {
    /// Initialises MPI with `Threading::Funneled` and wraps the world communicator.
    ///
    /// Errors when MPI is already initialised in this process. Prints a warning on stderr
    /// when the library provides less than `Funneled` (the renderer still only calls MPI
    /// from the main thread, which works in practice).
    pub fn init() -> Result<Self, ClusterError> {
        let (universe, provided) =
            ::mpi::initialize_with_threading(Threading::Funneled).ok_or(ClusterError::AlreadyInitialised)?;
        if provided < Threading::Funneled {
            crate::errln!("warning: MPI provides thread level {provided:?}, asked for Funneled");
        }
        let world = universe.world();
        let bad_world = || ClusterError::BadWorld { rank: world.rank().into(), size: world.size().into() };
        let rank = usize::try_from(world.rank()).map_err(|_| bad_world())?;
        let size = usize::try_from(world.size()).map_err(|_| bad_world())?;
        if size == 0 || rank >= size {
            return Err(bad_world());
        }
        let floor = std::env::var(job::HEARTBEAT_ENV).ok();
        let watch = start_watchdog(rank, job::heartbeat_floor(floor.as_deref())?);
        Ok(MpiCluster {
            world,
            rank,
            size,
            provided,
            max_chunk_bytes: DEFAULT_MAX_CHUNK_BYTES,
            watch,
            _universe: universe,
        })
    }

    /// The thread level MPI actually provides.
    pub fn provided_threading(&self) -> Threading {
        self.provided
    }

    /// Sets the largest payload of one MPI call (clamped to `8..=i32::MAX`). Only useful to
    /// exercise the chunking in tests; must be set to the same value on every rank.
    pub fn set_max_chunk_bytes(&mut self, bytes: usize) {
        self.max_chunk_bytes = bytes.clamp(8, i32::MAX as usize);
    }

    /// Largest number of f64 elements per MPI call.
    fn chunk_f64(&self) -> usize {
        (self.max_chunk_bytes / std::mem::size_of::<f64>()).max(1)
    }

    /// Agrees on a slice length across ranks; panics on every rank if they differ.
    fn check_same_len(&self, what: &str, len: usize) {
        let len = len as u64;
        let mine = [len, u64::MAX - len];
        let mut agg = [0u64; 2];
        self.world.all_reduce_into(&mine[..], &mut agg[..], SystemOperation::max());
        let (max, min) = (agg[0], u64::MAX - agg[1]);
        if max != min {
            panic!(
                "{what}: ranks passed slices of different lengths (min {min}, max {max}; rank {} has {len})",
                self.rank
            );
        }
    }

    /// Rank 0 receives every other rank's blob by point-to-point messages, in chunks.
    /// Used when the blobs together exceed one chunk (so `MPI_Gatherv` counts and
    /// displacements could overflow `i32`).
    fn gather_point_to_point(&self, local: &[u8], lens: &[u64]) -> Option<Vec<Vec<u8>>> {
        let chunk = self.max_chunk_bytes;
        if self.rank != 0 {
            let root = self.world.process_at_rank(0);
            for piece in local.chunks(chunk) {
                root.send(piece);
            }
            return None;
        }
        let mut out = Vec::with_capacity(self.size);
        out.push(local.to_vec());
        for (r, &len) in lens.iter().enumerate().skip(1) {
            let mut blob = vec![0u8; usize::try_from(len).unwrap_or(usize::MAX)];
            let src = self.world.process_at_rank(r as i32);
            for piece in blob.chunks_mut(chunk) {
                src.receive_into(piece);
            }
            out.push(blob);
        }
        Some(out)
    }
}

impl Cluster for MpiCluster {
    fn rank(&self) -> usize {
        self.rank
    }

    fn size(&self) -> usize {
        self.size
    }

    fn broadcast_bytes(&self, bytes: &mut Vec<u8>) {
        let _waiting = self.watch.enter();
        let root = self.world.process_at_rank(0);
        let mut len = bytes.len() as u64;
        root.broadcast_into(&mut len);
        if self.rank != 0 {
            let n = usize::try_from(len)
                .unwrap_or_else(|_| panic!("broadcast_bytes: {len} bytes do not fit in this address space"));
            bytes.clear();
            bytes.resize(n, 0);
        }
        for piece in bytes.chunks_mut(self.max_chunk_bytes) {
            root.broadcast_into(piece);
        }
    }

    fn reduce_sum(&self, local: &[f64]) -> Option<Vec<f64>> {
        let _waiting = self.watch.enter();
        self.check_same_len("reduce_sum", local.len());
        let root = self.world.process_at_rank(0);
        let ce = self.chunk_f64();
        if self.rank == 0 {
            let mut out = vec![0.0f64; local.len()];
            for (send, recv) in local.chunks(ce).zip(out.chunks_mut(ce)) {
                root.reduce_into_root(send, recv, SystemOperation::sum());
            }
            Some(out)
        } else {
            for send in local.chunks(ce) {
                root.reduce_into(send, SystemOperation::sum());
            }
            None
        }
    }

    fn all_reduce_sum(&self, local: &[f64]) -> Vec<f64> {
        let _waiting = self.watch.enter();
        self.check_same_len("all_reduce_sum", local.len());
        let ce = self.chunk_f64();
        let mut out = vec![0.0f64; local.len()];
        for (send, recv) in local.chunks(ce).zip(out.chunks_mut(ce)) {
            self.world.all_reduce_into(send, recv, SystemOperation::sum());
        }
        out
    }

    fn all_reduce_max(&self, local: f64) -> f64 {
        let _waiting = self.watch.enter();
        let mut out = 0.0f64;
        self.world.all_reduce_into(&local, &mut out, SystemOperation::max());
        out
    }

    fn gather_bytes(&self, local: &[u8]) -> Option<Vec<Vec<u8>>> {
        let _waiting = self.watch.enter();
        // Every rank learns every length, so all take the same path below.
        let mine = local.len() as u64;
        let mut lens = vec![0u64; self.size];
        self.world.all_gather_into(&mine, &mut lens[..]);
        let total: u64 = lens.iter().sum();
        if total > self.max_chunk_bytes as u64 {
            return self.gather_point_to_point(local, &lens);
        }
        // total <= max_chunk_bytes <= i32::MAX, so counts and displacements fit in i32.
        let root = self.world.process_at_rank(0);
        if self.rank != 0 {
            root.gather_varcount_into(local);
            return None;
        }
        let counts: Vec<i32> = lens.iter().map(|&l| l as i32).collect();
        let displs: Vec<i32> = counts
            .iter()
            .scan(0i32, |acc, &c| {
                let d = *acc;
                *acc += c;
                Some(d)
            })
            .collect();
        let mut all = vec![0u8; total as usize];
        {
            let mut part = PartitionMut::new(&mut all[..], &counts[..], &displs[..]);
            root.gather_varcount_into_root(local, &mut part);
        }
        let mut out = Vec::with_capacity(self.size);
        let mut off = 0usize;
        for &l in &lens {
            let l = l as usize;
            out.push(all[off..off + l].to_vec());
            off += l;
        }
        Some(out)
    }

    fn barrier(&self) {
        let _waiting = self.watch.enter();
        self.world.barrier();
    }

    fn watch(&self, limit: Option<(Instant, Duration)>) {
        *self.watch.limit.lock().unwrap_or_else(|e| e.into_inner()) = limit;
        self.watch.last_beat_ms.store(0, Ordering::Relaxed);
        self.watch.slowest_round_ms.store(0, Ordering::Relaxed);
    }

    fn beat(&self) {
        self.watch.beat();
    }
}
