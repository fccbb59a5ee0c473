//! `RenderError`: why a render failed, wrapping the typed errors of the modules it calls
//! (`Display` is the message rank 0 prints).

use crate::atomic_io::AtomicIoError;
use crate::distributed::ClusterError;
use crate::image_io::ImageError;
use crate::integrators::MethodError;
use crate::scene::SceneError;
use std::path::PathBuf;

/// Why a render failed; `Display` is the message (the one rank 0 prints).
#[derive(Debug)]
pub enum RenderError {
    /// The scene file: its file, line and key.
    Scene(SceneError),
    /// An option of the scene's `[render]` table refused: where (`at`), and the method's
    /// refusal when it is one (`None`: the value does not parse).
    SceneOption {
        /// The option's file, line and key; its message is the whole refusal.
        at: SceneError,
        /// The method's refusal of it (a flag of another method, a value out of range).
        cause: Option<Box<MethodError>>,
    },
    /// The method refused its options, or its preprocess product.
    Method(MethodError),
    /// The checkpoint to resume cannot be read.
    Checkpoint(crate::checkpoint::CheckpointError),
    /// The checkpoint to resume belongs to another render.
    Resume {
        /// The checkpoint (`--resume`).
        path: PathBuf,
        /// Every difference.
        mismatch: crate::checkpoint::ResumeMismatch,
    },
    /// The images cannot be encoded or written.
    Image(ImageError),
    /// An output refused before any work (`--out`'s prefix, the output guard), or the outputs
    /// (`PREFIX.{exr,png,json}` as one set) could not be written.
    Output(AtomicIoError),
    /// The ranks: a job that differs between them, a malformed broadcast, or an error agreed
    /// across ranks that is not this rank's own (`distributed::agree`: it names the failing
    /// ranks).
    Cluster(ClusterError),
    /// Anything else, as its message.
    Other(String),
}

impl RenderError {
    /// The flag of another method this error refuses, if it is one (from the command line or
    /// the scene's `[render]` table): a [`MethodError::ForeignFlag`].
    pub fn foreign_flag(&self) -> Option<&MethodError> {
        let e = match self {
            RenderError::Method(e) => e,
            RenderError::SceneOption { cause: Some(e), .. } => e.as_ref(),
            _ => return None,
        };
        matches!(e, MethodError::ForeignFlag { .. }).then_some(e)
    }
}

impl std::fmt::Display for RenderError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RenderError::Scene(e) | RenderError::SceneOption { at: e, .. } => write!(f, "{e}"),
            RenderError::Method(e) => write!(f, "{e}"),
            RenderError::Checkpoint(e) => write!(f, "{e}"),
            RenderError::Resume { path, mismatch } => write!(f, "{}: cannot resume: {mismatch}", path.display()),
            RenderError::Image(e) => write!(f, "{e}"),
            RenderError::Output(e) => write!(f, "{e}"),
            RenderError::Cluster(e) => write!(f, "{e}"),
            RenderError::Other(m) => write!(f, "{m}"),
        }
    }
}

impl std::error::Error for RenderError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            RenderError::Scene(e) => Some(e),
            RenderError::SceneOption { cause, .. } => cause.as_deref().map(|e| e as _),
            RenderError::Method(e) => Some(e),
            RenderError::Checkpoint(e) => Some(e),
            RenderError::Resume { mismatch, .. } => Some(mismatch),
            RenderError::Image(e) => Some(e),
            RenderError::Output(e) => Some(e),
            RenderError::Cluster(e) => Some(e),
            RenderError::Other(_) => None,
        }
    }
}

impl From<String> for RenderError {
    fn from(m: String) -> RenderError {
        RenderError::Other(m)
    }
}

impl From<SceneError> for RenderError {
    fn from(e: SceneError) -> RenderError {
        RenderError::Scene(e)
    }
}

impl From<MethodError> for RenderError {
    fn from(e: MethodError) -> RenderError {
        RenderError::Method(e)
    }
}

impl From<crate::checkpoint::CheckpointError> for RenderError {
    fn from(e: crate::checkpoint::CheckpointError) -> RenderError {
        RenderError::Checkpoint(e)
    }
}

impl From<ImageError> for RenderError {
    fn from(e: ImageError) -> RenderError {
        RenderError::Image(e)
    }
}

impl From<AtomicIoError> for RenderError {
    fn from(e: AtomicIoError) -> RenderError {
        RenderError::Output(e)
    }
}

impl From<ClusterError> for RenderError {
    fn from(e: ClusterError) -> RenderError {
        RenderError::Cluster(e)
    }
}

/// For the callers whose own errors are still messages (`compare`, `reference`).
impl From<RenderError> for String {
    fn from(e: RenderError) -> String {
        e.to_string()
    }
}
