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
pub mod settings;
pub mod streaming;

use bevy::asset::io::file::FileAssetReader;
use bevy::prelude::*;

pub use asset::{RadiancePack, RadiancePackLoader};
pub use camera::{LightSettings, Playback, PlenopticCamera, ReconMode, ReconSettings};
pub use reconstruct::cpu;
pub use settings::{
    Backend, GpuSupport, PlenopticEvent, PlenopticSettings, PlenopticSystems, ResolvedBackend,
};

/// The usual imports.
pub mod prelude {
    pub use crate::{
        Backend, LightSettings, Playback, PlenopticCamera, PlenopticEvent, PlenopticPlugin,
        PlenopticSettings, PlenopticSystems, RadiancePack, ReconMode, ReconSettings,
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
            .init_resource::<ResolvedBackend>()
            .add_systems(PreUpdate, settings::resolve_backend)
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
                reconstruct::geometry::GeometryAssistedPlugin,
                reconstruct::image::WarpPlugin,
                reconstruct::background::BackgroundPlugin,
                reconstruct::cpu::PlenopticCpuPlugin,
                lit::PlenopticLitPlugin,
            ));
    }
}

/// The README's code samples, compiled as doc tests so the README stays true.
#[cfg(doctest)]
#[doc = include_str!("../../../README.md")]
pub struct ReadmeDoctests;
