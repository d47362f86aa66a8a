//! # plenoptic_eval
//!
//! Offline evaluation of reconstruction (docs/architecture.md, "Measuring"): what the
//! runtime does not need, kept out of `plenoptic_recon` so that a game that embeds the
//! runtime links neither the tracer nor the image and plotting crates.
//!
//! - [`tools`]: `plenoptic render` (frames along a camera path from a pack) and
//!   `plenoptic compare` (per-frame metrics against a reference, variance-corrected when the
//!   reference comes as two independent halves);
//! - [`metrics`]: relative LRMS and PSNR (the tracer's) and the variance-corrected relative
//!   LRMS against a noisy two-half reference;
//! - [`frame_io`]: frame files: OpenEXR through the `exr` crate (any compression, half or
//!   float channels) and tonemapped PNG;
//! - [`maps`]: pictures of where a candidate's low-frequency error lies;
//! - [`plot`]: error-along-path plots (thesis figures 6.29 and 6.31) as SVG and PNG;
//! - [`mask`]: the geometry mask by ray casting through the tracer's BVH, the reference the
//!   runtime's rasterized mask is tested against;
//! - [`camera`]: the reconstruction camera as the tracer's pinhole and back.

pub mod camera;
pub mod frame_io;
pub mod low_frequency;
pub mod maps;
pub mod mask;
pub mod metrics;
pub mod plot;
pub mod tools;

use std::path::{Path, PathBuf};

/// Errors of the evaluation tools. Every file error names the file.
#[derive(Debug, thiserror::Error)]
pub enum EvalError {
    /// A file or directory could not be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// An OpenEXR file could not be read or written.
    #[error("{}: OpenEXR: {message}", path.display())]
    Exr {
        /// The file.
        path: PathBuf,
        /// What the `exr` crate reported.
        message: String,
    },
    /// A PNG could not be written.
    #[error("{}: PNG: {message}", path.display())]
    Png {
        /// The file.
        path: PathBuf,
        /// What the encoder reported.
        message: String,
    },
    /// A plot could not be drawn.
    #[error("{}: plot: {message}", path.display())]
    Plot {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// A file's content does not fit what was asked (sizes, names, missing frames).
    #[error("{}: {message}", path.display())]
    Invalid {
        /// The file or directory.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// Reconstruction failed.
    #[error("reconstruction: {0}")]
    Recon(#[from] plenoptic_recon::Error),
    /// The tracer failed (building the BVH, a bad camera).
    #[error("tracer: {0}")]
    Trace(#[from] plenoptic_trace::TraceError),
}

impl EvalError {
    /// An I/O error on `path`.
    pub fn io(path: impl AsRef<Path>, source: std::io::Error) -> Self {
        EvalError::Io {
            path: path.as_ref().to_path_buf(),
            source,
        }
    }

    /// A content error on `path`.
    pub fn invalid(path: impl AsRef<Path>, message: impl Into<String>) -> Self {
        EvalError::Invalid {
            path: path.as_ref().to_path_buf(),
            message: message.into(),
        }
    }
}

/// Result of the evaluation tools.
pub type Result<T, E = EvalError> = std::result::Result<T, E>;
