//! # bevy_plenoptic
//!
//! The Bevy plugin of plenoptic: it streams a radiance pack and reconstructs globally
//! illuminated frames for the camera's position and the current time (thesis chapters 6–7
//! and 8.2.3; `docs/architecture.md`, "The runtime plugin").
//!
//! - [`asset`]: the [`RadiancePack`] asset; its loader reads only the header, manifest and
//!   directory (and the small proxy meshes and tracks), never a cube.
//! - [`camera`]: the [`PlenopticCamera`] component (pack, time, mode, playback).
//! - [`proxy`]: the *geometry mask* of thesis §8.2.3 — the pack's proxy meshes spawned as
//!   ordinary Bevy mesh entities and placed from the animation tracks at the camera's time.
//!   Rasterising them gives each pixel its object and surface point and writes real depth,
//!   so ordinary Bevy meshes occlude, and are occluded by, the baked scene.
//! - [`streaming`]: the working set (weighted base views × time keys bracketing t, prefetch
//!   along the camera's motion and the playback direction) kept inside
//!   [`PlenopticSettings::memory_budget_bytes`] with LRU eviction; reads and decodes run on
//!   the I/O task pool; Bevy diagnostics report resident bytes, hits, misses, stalls
//!   and decode time.
//! - [`reconstruct`]: the reconstruction in WGSL. Geometry-assisted: a material on the proxy
//!   meshes that does `plenoptic_recon`'s geometry-mode lookups per fragment (with its
//!   volume, hole-fill and background fallbacks) and writes linear radiance times the camera's
//!   `Exposure`, unlit, into the camera's HDR target (tonemapped by the camera's
//!   `Tonemapping`, in the shader for cameras without an HDR target, as Bevy's PBR). Pixels
//!   no proxy covers show the pack's environment (sky, image, colour) at the camera's time. Image mode: compute passes (splats, key and view blends, background
//!   fill) whose frame the proxies show; volume mode: the same passes over cubes interpolated
//!   from the temporal volumes. [`cpu`] is the fallback backend ([`Backend`]) that runs
//!   `plenoptic_recon` itself on a worker thread, and the reference the GPU path is tested
//!   against.
//!
//! Layout: like bevy_solari, one folder per feature with its plugin and documented settings in
//! `mod.rs` and shaders beside the code. The geometry-assisted mode rides on Bevy's `Material`
//! pipeline (the material's bind group is the "prepare", the main opaque pass the "node"),
//! which is also what gives correct depth compositing with ordinary meshes for free; image
//! and volume modes add compute passes to the render graph (`reconstruct/image/`).
//!
//! Errors never panic the app: a pack that cannot be opened is an asset load failure whose
//! message names the section or chunk; a chunk that fails its checksum while streaming is a
//! [`PlenopticEvent::ChunkFailed`] message, and the frame is reconstructed from what is
//! resident.
//!
//! ```no_run
//! use bevy::prelude::*;
//! use bevy_plenoptic::prelude::*;
//!
//! fn setup(mut commands: Commands, assets: Res<AssetServer>) {
//!     commands.spawn((
//!         PlenopticCamera::new(assets.load("scene.pack")),
//!         Transform::from_xyz(0.0, 1.3, 1.0),
//!     ));
//! }
//!
//! App::new()
//!     .add_plugins((DefaultPlugins, PlenopticPlugin))
//!     .add_systems(Startup, setup)
//!     .run();
//! ```

pub mod asset;
pub mod camera;
pub mod lit;
pub mod proxy;
pub mod reconstruct;
pub mod streaming;

use bevy::asset::io::file::FileAssetReader;
use bevy::prelude::*;

pub use asset::{RadiancePack, RadiancePackLoader};
pub use camera::{Playback, PlenopticCamera, ReconMode, ReconSettings};
pub use reconstruct::cpu;

/// The usual imports.
pub mod prelude {
    pub use crate::{
        Backend, Playback, PlenopticCamera, PlenopticEvent, PlenopticPlugin, PlenopticSettings,
        PlenopticSystems, RadiancePack, ReconMode, ReconSettings,
    };
}

/// Adds plenoptic: the pack asset, cameras, proxy geometry and streaming. Add it after
/// `DefaultPlugins` (the loader resolves packs under the `AssetPlugin`'s directory).
#[derive(Debug, Default)]
pub struct PlenopticPlugin;

impl Plugin for PlenopticPlugin {
    fn build(&self, app: &mut App) {
        let asset_root = app
            .get_added_plugins::<AssetPlugin>()
            .first()
            .map(|p| FileAssetReader::get_base_path().join(&p.file_path));
        app.init_resource::<PlenopticSettings>()
            .init_asset::<RadiancePack>()
            .register_asset_loader(RadiancePackLoader { asset_root })
            .add_message::<PlenopticEvent>()
            .configure_sets(
                Update,
                (PlenopticSystems::Playback, PlenopticSystems::Streaming).chain(),
            )
            .add_plugins((
                camera::PlenopticCameraPlugin,
                proxy::PlenopticProxyPlugin,
                streaming::PlenopticStreamingPlugin,
                reconstruct::PlenopticReconstructPlugin,
                reconstruct::cpu::PlenopticCpuPlugin,
                lit::PlenopticLitPlugin,
            ));
    }
}

/// Global settings of the plugin.
#[derive(Resource, Debug, Clone, PartialEq)]
pub struct PlenopticSettings {
    /// Upper bound, in bytes, on decoded pack data kept resident (including reads in flight).
    /// Larger budgets keep more base views and time keys around the camera and stall less.
    pub memory_budget_bytes: u64,
    /// How far ahead, in seconds, to prefetch along the camera's velocity and the playback
    /// direction. Longer hides more latency but spends budget on data that may not be used.
    pub prefetch_seconds: f32,
    /// Where frames are reconstructed. Read when a pack's proxy geometry is first shown.
    pub backend: Backend,
    /// The first render layer given to plenoptic cameras: each camera draws its own proxy
    /// geometry on a layer of its own, with a shadow-only layer above it, the lowest free pair
    /// from here up ([`camera::layers`]). Choose it above the layers the app uses itself.
    pub first_render_layer: usize,
    /// Light the app's own meshes with the pack: each plenoptic camera without an
    /// environment light of its own gets one made from the pack's radiance around it at its
    /// time ([`lit`]).
    pub environment_light: bool,
}

/// Where frames are reconstructed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Backend {
    /// The WGSL material on the proxy meshes (per-fragment lookups; cost scales with the
    /// covered pixels × base views × 2 keys, more where the volume fallback or the hole fill
    /// runs). Image mode runs as compute passes ([`reconstruct::image`]: splats of the
    /// weighted views' cube texels, view blend, background fill) shown through the proxies
    /// and the background. Volume mode ([`reconstruct::volume`]) interpolates each
    /// weighted view's cube at t from its resident temporal-volume blocks on the CPU (off
    /// the main thread, when the time or views change) and warps those cubes with the same
    /// passes. Every camera in image or volume mode has its own passes and frame; until its
    /// volume cubes exist a volume-mode camera is shown geometry-assisted.
    Gpu,
    /// `plenoptic_recon`'s CPU reconstructor on a worker thread, its frame shown through the
    /// proxy meshes (screen-space texture; depth still from the rasterised proxies). Far
    /// slower; a frame lags the camera while it is computed. The reference to compare with.
    Cpu,
    /// The GPU unless the device lacks what it needs (then the CPU, with a warning).
    #[default]
    Auto,
}

impl Default for PlenopticSettings {
    fn default() -> Self {
        Self {
            memory_budget_bytes: 256 * 1024 * 1024,
            prefetch_seconds: 0.5,
            backend: Backend::Auto,
            first_render_layer: 16,
            environment_light: true,
        }
    }
}

/// The system sets plenoptic runs in `Update`, in this order. Order your own systems
/// against them, e.g. set the playback time `.before(PlenopticSystems::Playback)`.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PlenopticSystems {
    /// Advances or applies the playback time of each plenoptic camera and places the proxy
    /// geometry.
    Playback,
    /// Decides the working set and issues reads and decodes off the main thread.
    Streaming,
}

/// Something that went wrong while streaming; the app keeps running.
#[derive(Message, Debug, Clone, PartialEq)]
pub enum PlenopticEvent {
    /// A chunk could not be read or decoded (checksum mismatch, truncated file, bad KTX2).
    ChunkFailed {
        /// The chunk (kind, base view, key).
        chunk: String,
        /// Why.
        reason: String,
    },
}

/// The README's code samples, compiled as doc tests so the README stays true.
#[cfg(doctest)]
#[doc = include_str!("../../../README.md")]
pub struct ReadmeDoctests;
