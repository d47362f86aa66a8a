//! The baker's error type.

use std::path::PathBuf;

use plenoptic_pack::PackError;
use plenoptic_scene::{RecipeError, SceneError};
use plenoptic_trace::TraceError;

/// Result of the baker.
pub type Result<T, E = BakeError> = std::result::Result<T, E>;

/// Everything that can stop a bake, each naming where it comes from.
#[derive(Debug, thiserror::Error)]
pub enum BakeError {
    /// The recipe could not be read or is invalid.
    #[error(transparent)]
    Recipe(#[from] RecipeError),
    /// A scene file could not be loaded.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// The tracer refused the scene or a setting.
    #[error("tracer: {0}")]
    Trace(#[from] TraceError),
    /// Writing or reading a pack failed.
    #[error("pack: {0}")]
    Pack(#[from] PackError),
    /// A file or directory could not be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file or directory.
        path: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// A plan or work-dir JSON file is malformed.
    #[error("{}: {message}", path.display())]
    Json {
        /// The file.
        path: PathBuf,
        /// What serde said.
        message: String,
    },
    /// The work directory holds a plan for different inputs, or an item file is damaged.
    #[error("work directory {}: {problem}", path.display())]
    WorkDir {
        /// The work directory or file.
        path: PathBuf,
        /// What is wrong.
        problem: String,
    },
    /// A merge found work items missing (shards not all finished).
    #[error("work directory {}: {missing} of {total} work items missing (first: {first}); finish every shard before merging", path.display())]
    Incomplete {
        /// The work directory.
        path: PathBuf,
        /// Items missing.
        missing: usize,
        /// Items in the plan.
        total: usize,
        /// Name of the first missing item.
        first: String,
    },
    /// The bake stopped on request after this many work items (the `--stop-after` hook used to
    /// test resuming); `--resume` continues it.
    #[error("bake interrupted after {completed} work items; run again with --resume")]
    Interrupted {
        /// Items written in this run.
        completed: usize,
    },
    /// A command-line value or setting is invalid.
    #[error("{0}")]
    Invalid(String),
    /// An environment image that cannot be used.
    #[error("environment image {}: {message}", path.display())]
    Environment {
        /// The file.
        path: std::path::PathBuf,
        /// What is wrong with it.
        message: String,
    },
}

impl BakeError {
    /// An [`BakeError::Io`] for `path`.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        BakeError::Io {
            path: path.into(),
            source,
        }
    }
}
