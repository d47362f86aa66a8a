//! # plenoptic_recon
//!
//! The runtime core of reconstruction (docs/architecture.md, "Reconstruction"): frames from a
//! radiance pack on the CPU, the reference the GPU passes of `bevy_plenoptic` are tested
//! against, their fallback, and the pieces the plugin shares with it (temporal blending,
//! view-space weights, volumes, proxies and their motion). It depends on the pack format and
//! small numeric crates only: not on the tracer or the scene importer. The offline tools
//! (`plenoptic render`, `plenoptic compare`, frame files, plots, the ray-cast mask) are in
//! `plenoptic_eval`.
//!
//! From Nimeroff's thesis (1997):
//!
//! - [`temporal`]: the piecewise cubic Bézier blend of range images through time keys
//!   (appendix A.1, used by chapter 6's image-based system);
//! - [`warp`]: depth reprojection of a base view's cube into the camera with a z-buffer,
//!   footprint splats (foreground fill) and background fill (appendix A.2, §6.7);
//! - [`viewspace`]: blending base views by the camera's place in the view space (§6.7);
//! - [`volume`]: temporal volumes at t (§7.4): the baked (x, y, t) complex sliced at t, or
//!   the samples filtered around t and triangulated; [`delaunay3`]: that (x, y, t) Delaunay
//!   complex (the baker builds it with this module, reconstruction slices it);
//! - [`proxy`] and the geometry-assisted mode: geometry masks and motion-compensated lookups,
//!   the improvement the thesis proposes in §8.2.3; [`motion`]: the objects' tracks
//!   evaluated at any time.
//!
//! - [`background`]: the pack's environment (sky, image, colour) per pixel where no proxy
//!   is, at the camera's time.
//!
//! [`Reconstructor::render`] runs one of the three [`Mode`]s and returns a [`Frame`]
//! (radiance, depth, object id) and a [`Report`] (fallback fractions, missing chunks). A
//! damaged pack degrades the frame instead of failing it. [`path`] is the camera-path file
//! shared with the reference renderer.
//!
//! ```
//! use plenoptic_pack::*;
//! use plenoptic_pack::glam::{Quat, Vec3};
//! use plenoptic_recon::{Camera, Mode, Reconstructor};
//!
//! // A pack with one base view inside a 4 m box (object 1) whose walls shine like |dir|.
//! let dir = tempfile::tempdir().unwrap();
//! let path = dir.path().join("box.pack");
//! let mut image = RangeImage::new(16);
//! image.radiance = CubeImage::from_fn(16, |_, d| d.abs());
//! image.distance = CubeImage::from_fn(16, |_, d| 2.0 / d.abs().max_element());
//! image.object_id = CubeImage::filled(16, 1);
//! image.normal = CubeImage::from_fn(16, |_, d| {
//!     let a = d.abs();
//!     if a.x >= a.y && a.x >= a.z { Vec3::new(-d.x.signum(), 0.0, 0.0) }
//!     else if a.y >= a.z { Vec3::new(0.0, -d.y.signum(), 0.0) }
//!     else { Vec3::new(0.0, 0.0, -d.z.signum()) }
//! });
//! // The box's proxy: 8 corners, 12 triangles.
//! let positions: Vec<Vec3> = (0..8)
//!     .map(|i| Vec3::new([-2.0, 2.0][i & 1], [-2.0, 2.0][(i >> 1) & 1], [-2.0, 2.0][i >> 2]))
//!     .collect();
//! let indices = vec![
//!     0, 1, 3, 0, 3, 2, 4, 6, 7, 4, 7, 5, 0, 4, 5, 0, 5, 1,
//!     2, 3, 7, 2, 7, 6, 0, 2, 6, 0, 6, 4, 1, 5, 7, 1, 7, 3,
//! ];
//! let mut writer = PackWriter::create(&path).unwrap();
//! writer.add_range_image(0, 0, &image, CubeFormats::default()).unwrap();
//! writer.add_proxy_mesh(&ProxyMesh { object_id: 1, positions, indices, normals: None }).unwrap();
//! let mut manifest = Manifest::new(TimeRange { start: 0.0, end: 1.0 }, 0.5);
//! manifest.base_views.push(BaseView { id: 0, position: Vec3::ZERO, time_keys: vec![0.0] });
//! manifest.objects.push(ObjectEntry {
//!     id: 1, name: "box".into(), node_path: "/box".into(), motion: Motion::Static, proxy_mesh: Some(1), material: None, coverage: None,
//! });
//! writer.finish(&manifest).unwrap();
//!
//! // Reconstruct: at the base view, every pixel is a direct lookup of the range image.
//! let recon = Reconstructor::open(&path).unwrap();
//! let camera = Camera::new(Vec3::ZERO, Quat::IDENTITY, 1.0, 32, 24).unwrap();
//! let (frame, report) = recon.render(&camera, 0.0, Mode::GeometryAssisted).unwrap();
//! assert!(report.fallback.direct > 0.99, "{report:?}");
//! assert!(frame.depth.iter().all(|d| (2.0..3.5).contains(d)));
//! assert!(frame.radiance[12 * 32 + 16].abs_diff_eq(Vec3::new(0.0, 0.0, 1.0), 0.1));
//! ```

// The integration tests' pack writer, shared with unit tests that need a pack (it names
// this crate).
#[cfg(test)]
extern crate self as plenoptic_recon;

pub mod background;
pub mod brdf;
mod cache;
pub mod camera;
pub mod delaunay3;
pub mod flat_rays;
pub mod frame;
mod geometry;
#[cfg(test)]
#[path = "geometry_tests.rs"]
mod geometry_tests;
mod glazing;
pub mod lamps;
mod lookup;
mod material;
pub mod motion;
mod neighbour;
pub mod path;
pub mod proxy;
mod raster;
pub mod reconstructor;
mod reflected;
pub mod relight;
mod sample;
pub mod settings;
mod shading;
pub mod shadow;
pub mod specular;
pub mod streamed;
pub mod sun;
mod sun_edge;
mod surface;
pub mod temporal;
mod texels;
pub mod viewspace;
pub mod volume;
pub mod warp;

pub use camera::Camera;
pub use frame::{FallbackReport, Frame, Mode, Report};
pub use motion::ObjectMotion;
pub use neighbour::{NEIGHBOUR_TEXELS, NEIGHBOUR_TOLERANCE};
pub use path::{CameraPath, Keyframe, PathSample};
pub use proxy::{GeometryMask, ProxyGeometry, TriangleMesh};
pub use reconstructor::Reconstructor;
pub use settings::{CubeFilter, ReconSettings, Shading};
pub use specular::Specular;
pub use streamed::{KeySource, StreamedCube};

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
