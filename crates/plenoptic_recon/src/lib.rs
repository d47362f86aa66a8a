//! # plenoptic_recon
//!
//! CPU reconstruction of frames from a radiance pack (design.md, "Reconstruction"), the
//! reference for the GPU passes of `bevy_plenoptic`, its fallback, and the quality tools.

pub mod camera;
pub mod frame;
pub mod frame_io;
mod geometry;
pub mod path;
pub mod plot;
pub mod proxy;
pub mod reconstructor;
pub mod temporal;
pub mod tools;
pub mod viewspace;
pub mod volume;
pub mod warp;

pub use camera::Camera;
pub use frame::{FallbackReport, Frame, Mode, Report};
pub use path::{CameraPath, Keyframe, PathSample};
pub use proxy::{GeometryMask, ProxyGeometry};
pub use reconstructor::{ReconSettings, Reconstructor};

/// Errors of reconstruction.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The pack cannot be used at all.
    #[error("pack: {0}")]
    Pack(#[from] plenoptic_pack::PackError),
    /// Nothing in the pack is usable for this frame.
    #[error("nothing to reconstruct from: {0}")]
    Unusable(String),
    /// Bad camera parameters.
    #[error("invalid camera: {0}")]
    Camera(String),
    /// A bad camera path.
    #[error("camera path: {0}")]
    Path(String),
    /// A file could not be read or written.
    #[error("i/o: {0}")]
    Io(String),
}

/// Result of reconstruction.
pub type Result<T, E = Error> = std::result::Result<T, E>;
