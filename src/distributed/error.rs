//! `ClusterError`: why the cluster could not start, why the ranks disagree on the job, why a
//! collective's data is malformed, or the errors of the failing ranks as rank 0 gathered them
//! ([`super::agree`]). `Display` is the message users see.

/// Why a cluster operation failed; each variant keeps the figures its message names. `Display`
/// is the message.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ClusterError {
    /// A build without the cargo feature `mpi` started by a launcher (`mpirun`, `srun`) as one of
    /// several ranks: each would render the whole image alone and write the same files.
    NoMpiFeature {
        /// The launcher's variable that announced the ranks (`PMI_SIZE`, …).
        var: &'static str,
        /// The number of ranks it announced.
        ranks: usize,
    },
    /// MPI was already initialised in this process (`distributed::init` called twice).
    AlreadyInitialised,
    /// MPI reported a world that cannot be: a negative rank or size, no rank, or a rank not
    /// below the size.
    BadWorld {
        /// The rank MPI reported.
        rank: i64,
        /// The size MPI reported.
        size: i64,
    },
    /// The ranks were started with different jobs ([`super::job::agree_job`]): each differing
    /// field with every rank's value, in words (`--method differs (rank 0 `pt`, rank 1 `iws`)`).
    JobMismatch {
        /// One entry per differing field.
        differences: Vec<String>,
    },
    /// A broadcast value whose bytes are not what was sent ([`super::broadcast_u64`]).
    BadBroadcast {
        /// What was broadcast (`resume`, `light-path`).
        what: String,
        /// The number of bytes received.
        len: usize,
    },
    /// The cluster's rank and size are inconsistent ([`super::self_test`]).
    BadTopology {
        /// This process's rank.
        rank: usize,
        /// The cluster's size.
        size: usize,
    },
    /// Checks of [`super::self_test`] failed.
    SelfTest {
        /// How many checks failed, over all ranks.
        failures: u64,
        /// Every failure, one line each (`rank r: …`), on rank 0; `None` on the other ranks.
        report: Option<String>,
    },
    /// The errors of the failing ranks, gathered on rank 0 ([`super::agree`]).
    Failed {
        /// Each distinct message with the ranks that had it, in rank order.
        failures: Vec<(Vec<usize>, String)>,
        /// The number of ranks.
        ranks: usize,
    },
    /// `FORECAST_MPI_HEARTBEAT` holds neither a number of seconds in `(0, 10^6]` nor `off`
    /// ([`super::job::heartbeat_floor`]).
    BadHeartbeat {
        /// The variable's value as set.
        value: String,
    },
    /// The stand-in error of the ranks other than 0 when the job failed ([`super::agree`]); rank
    /// 0 reports the real one.
    FailedElsewhere,
}

impl std::fmt::Display for ClusterError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        use ClusterError::*;
        match self {
            NoMpiFeature { var, ranks } => write!(
                f,
                "this binary was built without the `mpi` feature but was started as one of {ranks} ranks \
                 ({var}={ranks}); rebuild with `cargo build --release --features mpi` \
                 (needs .ci/install-mpi.sh) or run it without mpirun"
            ),
            AlreadyInitialised => {
                write!(f, "MPI is already initialised in this process; call distributed::init() only once")
            }
            BadWorld { rank, .. } if *rank < 0 => write!(f, "negative MPI rank {rank}"),
            BadWorld { size, .. } if *size < 0 => write!(f, "bad MPI size {size}"),
            BadWorld { rank, size } => write!(f, "inconsistent MPI world: rank {rank}, size {size}"),
            JobMismatch { differences } => write!(
                f,
                "the MPI ranks were started with different jobs: {}; start every rank with the same scene and \
                 options",
                differences.join("; ")
            ),
            BadBroadcast { what, .. } => write!(f, "bad {what} broadcast"),
            BadTopology { rank, size } => write!(f, "bad topology: rank {rank}, size {size}"),
            SelfTest { report: Some(report), .. } => write!(f, "{report}"),
            SelfTest { failures, report: None } => write!(f, "{failures} check(s) failed (details on rank 0)"),
            Failed { failures, ranks } => match failures.as_slice() {
                // one message: as it is when every rank (or rank 0 alone) had it
                [(who, msg)] if who.len() == *ranks || who == &[0] => write!(f, "{msg}"),
                _ => {
                    for (i, (who, msg)) in failures.iter().enumerate() {
                        let who = who.iter().map(|r| r.to_string()).collect::<Vec<_>>().join(",");
                        write!(f, "{}rank {who}: {msg}", if i == 0 { "" } else { "; " })?;
                    }
                    Ok(())
                }
            },
            BadHeartbeat { value } => write!(
                f,
                "{}=`{value}`: expected the MPI heartbeat's floor in seconds (a number in (0, 1000000], e.g. 60) \
                 or `off`",
                super::job::HEARTBEAT_ENV
            ),
            FailedElsewhere => write!(f, "the job failed on another rank (rank 0 reports it)"),
        }
    }
}

impl std::error::Error for ClusterError {}

/// For the callers whose own errors are still messages.
impl From<ClusterError> for String {
    fn from(e: ClusterError) -> String {
        e.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The messages are the ones users (and the tests in `tests/`) have always seen.
    #[test]
    fn messages_word_for_word() {
        let cases: Vec<(ClusterError, &str)> = vec![
            (
                ClusterError::NoMpiFeature { var: "PMI_SIZE", ranks: 2 },
                "this binary was built without the `mpi` feature but was started as one of 2 ranks (PMI_SIZE=2); \
                 rebuild with `cargo build --release --features mpi` (needs .ci/install-mpi.sh) or run it without \
                 mpirun",
            ),
            (ClusterError::BadWorld { rank: -1, size: 2 }, "negative MPI rank -1"),
            (ClusterError::BadWorld { rank: 0, size: -2 }, "bad MPI size -2"),
            (ClusterError::BadWorld { rank: 3, size: 2 }, "inconsistent MPI world: rank 3, size 2"),
            (
                ClusterError::JobMismatch { differences: vec!["a differs (x)".into(), "b differs (y)".into()] },
                "the MPI ranks were started with different jobs: a differs (x); b differs (y); start every rank \
                 with the same scene and options",
            ),
            (ClusterError::BadBroadcast { what: "resume".into(), len: 3 }, "bad resume broadcast"),
            (ClusterError::BadTopology { rank: 2, size: 1 }, "bad topology: rank 2, size 1"),
            (
                ClusterError::BadHeartbeat { value: "soon".into() },
                "FORECAST_MPI_HEARTBEAT=`soon`: expected the MPI heartbeat's floor in seconds (a number in \
                 (0, 1000000], e.g. 60) or `off`",
            ),
            (ClusterError::SelfTest { failures: 2, report: None }, "2 check(s) failed (details on rank 0)"),
            (ClusterError::SelfTest { failures: 1, report: Some("rank 1: x".into()) }, "rank 1: x"),
        ];
        for (e, want) in cases {
            assert_eq!(e.to_string(), want, "{e:?}");
        }
    }
}
