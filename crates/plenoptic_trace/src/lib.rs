//! # plenoptic_trace
//!
//! Ray tracing for the baker (docs/architecture.md, Baking steps 2–3):
//!
//! - [`accel`]: a BVH per mesh in object space ([`SceneAccel`], built once with obvhs's
//!   compressed wide BVH) and a top level over the objects placed at time t
//!   ([`PlacedScene`]): rigid animation costs a top-level rebuild only. Closest-hit and
//!   shadow queries; id-images.
//! - [`alpha`]: glTF `alphaMode` MASK (cut-outs) and BLEND (coverage: rays pass with
//!   probability 1 − alpha, decided by a hash of the ray) as an any-hit filter of every
//!   intersection and shadow query; [`texture`]: bilinear lookups with the sampler's wrap
//!   modes and `KHR_texture_transform`, and `COLOR_0`.
//! - [`camera`]: pinhole, cube (KTX2/Vulkan face order and orientation) and fisheye cameras.
//! - [`pathtrace`]: the reference path tracer (next-event estimation, multiple importance
//!   sampling, GGX, transmission thin-walled as glTF's default or a refracting solid with
//!   `KHR_materials_volume`), the ground truth for every metric.
//! - [`multistage`]: the multi-stage renderer of Nimeroff's thesis, chapter 5 ("Computing the
//!   radiance distribution for an environment – multi-stage rendering", figure 5.1): indirect
//!   diffuse light comes from an *ambient field* gathered on a scene simplified by a quality
//!   parameter (area pruning and tessellation, §5.3) and stored per object in object space
//!   (§5.3.4), while direct light and specular reflection/refraction are ray traced per sample
//!   (§5.3.5). Fields at two key times interpolate linearly (chapter 6's temporal
//!   interpolation of indirect illumination).
//! - [`metrics`]: relative LRMS (the thesis's measure, table 5.2) and PSNR.
//!
//! Every image is parallel over rows with one deterministic random stream per pixel sample,
//! so the same inputs give the same pixels for any thread count.
//!
//! ```
//! use glam::{Quat, Vec3};
//! use plenoptic_scene::NO_OBJECT;
//! use plenoptic_trace::{PinholeCamera, SceneAccel, shapes};
//!
//! // A unit box at the origin, seen from +Z.
//! let mut builder = shapes::SceneBuilder::default();
//! let grey = builder.material(shapes::diffuse(Vec3::splat(0.5)));
//! builder.object("box", shapes::cuboid(Vec3::ONE), grey, Vec3::ZERO);
//! let scene = builder.build();
//!
//! let accel = SceneAccel::new(&scene)?;
//! let placed = accel.at_time(0.0);
//! let camera = PinholeCamera::new(Vec3::new(0.0, 0.0, 5.0), Quat::IDENTITY, 0.8, 16, 16)?;
//! let ids = placed.id_image(&camera);
//! assert_eq!(*ids.get(8, 8), 0);
//! assert_eq!(*ids.get(0, 0), NO_OBJECT);
//! # Ok::<(), plenoptic_trace::TraceError>(())
//! ```

pub mod accel;
pub mod alpha;
pub mod camera;
pub mod environment;
pub mod image;
pub mod light;
pub mod material;
pub mod metrics;
pub mod multistage;
pub mod pathtrace;
pub mod render;
pub mod sampling;
pub mod shapes;
pub mod texture;

pub use accel::{FlatBvh, Hit, PlacedScene, Ray, SceneAccel};
pub use camera::{
    CUBE_FACES, Camera, CubeCamera, CubeFace, CubeFaceCamera, FisheyeCamera, PinholeCamera,
};
/// The glam this crate uses (the workspace's one).
pub use glam;
pub use image::Image;
pub use multistage::{AmbientField, AmbientSettings, MultiStageRenderer, MultiStageSettings};
/// The obvhs this crate uses.
pub use obvhs;
pub use pathtrace::{PathTracer, PathTracerSettings};
pub use render::{PixelFilter, RadianceSample};

/// Errors of the tracer.
#[derive(Debug, thiserror::Error)]
pub enum TraceError {
    /// The scene has no object with triangles.
    #[error("the scene has no object with triangles to trace")]
    EmptyScene,
    /// Camera parameters out of range.
    #[error("invalid camera: {0}")]
    InvalidCamera(String),
    /// Invalid renderer settings.
    #[error("invalid settings: {0}")]
    InvalidSettings(String),
    /// Two ambient fields that cannot be interpolated.
    #[error("ambient fields differ in topology: {0}")]
    FieldMismatch(String),
    /// Writing an image failed.
    #[error("cannot write image {path}: {message}")]
    Image {
        /// The file.
        path: String,
        /// What went wrong.
        message: String,
    },
}

/// Result of the tracer.
pub type Result<T, E = TraceError> = std::result::Result<T, E>;
