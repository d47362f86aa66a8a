//! The GPU reconstruction, one folder per feature (`docs/architecture.md`, "The runtime
//! plugin"), each with its plugin in `mod.rs`, its main-world and render-world stages in
//! files of their own and its shaders beside them:
//!
//! - [`geometry`]: geometry-assisted mode (thesis §8.2.3), the proxy material whose fragment
//!   shader does `plenoptic_recon`'s lookups, with each camera's lookups in its view buffer;
//! - [`image`]: image mode, `plenoptic_recon`'s warping in compute passes per view, whose
//!   frame the proxy materials and the background show;
//! - [`image::volume`]: volume mode, cubes at t interpolated on the CPU from the temporal volumes and
//!   warped by the image-mode passes;
//! - [`background`]: the pack's environment (or the heaviest key's cube) behind the proxies;
//! - [`cpu`]: the CPU backend, `plenoptic_recon` run off the main thread and shown in screen
//!   space.
//!
//! Shared here: the key textures and their uploads ([`upload`]), the backend in use, and the
//! order of the main-world systems ([`ReconstructSystems`]). Every plenoptic camera has its
//! own proxies, materials, background, image-mode frame and sun, on its own render layer
//! ([`crate::camera::layers`]): any number of cameras, each with its own pack, time and mode,
//! render in one app.
//!
//! Resident keys live in one `Rgba32Uint` 2D-array texture per pack: texel = (radiance as
//! RGB9E5, distance as f32 bits, object id, oct-encoded RG16Snorm normal), six layers per
//! streaming slot: the pack's own texel bytes interleaved, one binding and `textureLoad` only
//! (distances and ids are not filterable anyway).

pub mod background;
pub mod counters;
pub mod cpu;
pub mod environment;
pub mod frames;
pub mod geometry;
pub mod image;
pub mod relight;
pub mod upload;

use std::collections::{HashMap, HashSet};

use bevy::prelude::*;

use crate::asset::RadiancePack;
use crate::settings::{GpuSupport, PlenopticSystems};

/// Most lookups (view × key) per fragment.
pub const MAX_LOOKUPS: usize = 16;
/// Most array layers of the key texture (a common device limit is 2048).
const MAX_LAYERS: u32 = 2046;

/// The order of the reconstruction's main-world systems each frame, after streaming.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ReconstructSystems {
    /// Resident keys uploaded to the key textures.
    Upload,
    /// Keys and volume blocks uploaded; every camera given its frame, view buffer and ray
    /// placements.
    Resources,
    /// Materials attached to new proxies, backgrounds spawned.
    Attach,
    /// Per-camera work: volume-mode cubes, image-mode jobs, the runtime suns.
    Jobs,
    /// Each camera's view buffer filled for this frame.
    Views,
    /// Materials and backgrounds kept bound to their camera.
    Materials,
}

/// Adds what the GPU reconstruction's features share: the key textures, the environment's
/// textures, the shader libraries and the order of their systems. The features' own plugins
/// are added beside it ([`crate::PlenopticPlugin`]).
#[derive(Debug, Default)]
pub struct PlenopticReconstructPlugin;

impl Plugin for PlenopticReconstructPlugin {
    fn build(&self, app: &mut App) {
        // Cube helpers the reconstruction shaders import (`plenoptic::cube`) and the pack's
        // environment (`plenoptic::environment`).
        bevy::shader::load_shader_library!(app, "cube.wgsl");
        bevy::shader::load_shader_library!(app, "environment.wgsl");
        // The cost counters (`plenoptic::counters`).
        bevy::shader::load_shader_library!(app, "counters.wgsl");
        bevy::shader::load_shader_library!(app, "relight.wgsl");
        upload::build(app);
        counters::build(app);
        app.init_resource::<KeyTextures>()
            .init_resource::<environment::EnvironmentImages>()
            .add_message::<frames::FrameReplaced>()
            .configure_sets(
                Update,
                (
                    ReconstructSystems::Upload,
                    ReconstructSystems::Resources,
                    ReconstructSystems::Attach,
                    ReconstructSystems::Jobs,
                    ReconstructSystems::Views,
                    ReconstructSystems::Materials,
                )
                    .chain()
                    .after(PlenopticSystems::Streaming),
            )
            .add_systems(
                Update,
                upload::upload_keys.in_set(ReconstructSystems::Upload),
            );
    }
    fn finish(&self, app: &mut App) {
        // Like bevy_solari: check the device once; a missing capability is a warning and the
        // CPU backend, never a panic.
        let layers = app
            .get_sub_app(bevy::render::RenderApp)
            .and_then(|r| {
                r.world()
                    .get_resource::<bevy::render::renderer::RenderDevice>()
            })
            .map(|d| d.limits().max_texture_array_layers);
        let supported = layers.is_some_and(|l| l >= 6);
        if !supported {
            warn!(
                "plenoptic: the GPU reconstruction needs 2D array textures of at least 6 layers \
                 (device: {layers:?}); Backend::Auto uses the CPU backend"
            );
        }
        app.insert_resource(GpuSupport(supported));
    }
}

/// The key texture of each pack and which key each slot holds.
#[derive(Resource, Debug, Default)]
pub struct KeyTextures(pub HashMap<AssetId<RadiancePack>, KeyTexture>);

/// One pack's key texture.
#[derive(Debug, Clone)]
pub struct KeyTexture {
    /// The texture.
    pub image: Handle<Image>,
    /// The shading texture beside it, same layers: per texel the lighting and the non-diffuse
    /// radiance (RGB9E5 each) of pack 2.0.
    pub shading: Handle<Image>,
    /// Face size.
    pub face: u32,
    /// Slots it has room for.
    pub slots: u32,
    /// (view, key) uploaded in each slot.
    pub uploaded: HashMap<u32, (u32, u32)>,
    /// Slots whose key came with normals (an all-zero texel is the +Z normal, so presence
    /// cannot be read from the texels).
    pub normals: HashSet<u32>,
}
