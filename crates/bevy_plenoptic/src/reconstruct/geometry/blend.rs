//! A view's two time keys blended once per frame where they agree (thesis §8.2.3's time
//! blend, `w_time`, moved out of the pixel).
//!
//! A camera looks up each base view it blends in the two time keys around its time, and the
//! point of an object that stands still between the two key times (a static object, or an
//! animated one with the same transform at both) falls on the same texel of both. Where that texel (and the rest of a
//! lookup's footprint) shows the same surface in both keys, same object, distance and normal,
//! the two lookups pass and refuse together, and their blend is the keys' colours blended with
//! their time weights. Once per frame, before the camera's opaque pass, a compute pass
//! (`blend.wgsl`) writes each such pair of keys into the camera's blended keys: per texel the
//! first key's id, distance and normal (or an id that marks the texel as changing), and the
//! two keys' lighting and non-diffuse terms blended, as half floats. The fragment of such an
//! object shaded from its material then looks a pair up once (`lookup.wgsl`, `pair_lookup`) instead of twice, and
//! takes the two keys apart only where a texel of its footprint changes between them.
//! The result is the same blend: weights `w_0 + w_1` and colours `(w_0 c_0 + w_1 c_1) /
//! (w_0 + w_1)`, to the precision of half floats.

use std::borrow::Cow;

use bevy::asset::load_embedded_asset;
use bevy::core_pipeline::core_3d::main_opaque_pass_3d;
use bevy::core_pipeline::schedule::{Core3d, Core3dSystems};
use bevy::prelude::*;
use bevy::render::extract_component::{ExtractComponent, ExtractComponentPlugin};
use bevy::render::render_asset::RenderAssets;
use bevy::render::render_resource::binding_types::texture_storage_2d_array;
use bevy::render::render_resource::{
    BindGroupEntries, BindGroupLayoutDescriptor, BindGroupLayoutEntries, CachedComputePipelineId,
    ComputePipelineDescriptor, PipelineCache, ShaderStages, StorageTextureAccess, TextureFormat,
};
use bevy::render::renderer::{RenderContext, RenderDevice, ViewQuery};
use bevy::render::storage::{GpuShaderBuffer, ShaderBuffer};
use bevy::render::texture::GpuImage;
use bevy::render::{RenderApp, RenderStartup};
use bevy::shader::ShaderDefVal;

use super::key_pass::{dispatch_faces, keys_group, keys_layout};
use super::view::ViewBuffer;
use crate::camera::{PlenopticCamera, ReconSettings};
use crate::reconstruct::relight::storage_image;
use crate::reconstruct::{KeyTextures, MAX_LOOKUPS};
use crate::settings::{Backend, ResolvedBackend};

/// Key pairs a camera blends at most (two lookups each).
pub const MAX_PAIRS: u32 = (MAX_LOOKUPS / 2) as u32;

/// A camera's blended keys (see the module doc), which its materials bind: two textures of
/// 16 bytes per texel, six faces per pair (at face 64 and 4 views, 1.5 MiB each). Extracted
/// onto its render-world view with what the pass reads.
#[derive(Component, Debug, Clone, ExtractComponent)]
pub struct BlendedKeys {
    /// Per pair, six faces: the first key's id, distance and normal (x: unused).
    pub geometry: Handle<Image>,
    /// Per pair, six faces: the blended lighting and non-diffuse terms (`fill_entry.wgsl`'s
    /// `pack_pair`).
    pub terms: Handle<Image>,
    /// The keys' face size.
    pub face: u32,
    /// Pairs the textures have room for: the camera's `max_views`, at most [`MAX_PAIRS`].
    pub room: u32,
    /// Pairs to blend this frame (the view buffer's `pair_count`).
    pub pairs: u32,
    /// The pack's key texture and shading texture.
    pub keys: Option<(Handle<Image>, Handle<Image>)>,
    /// The camera's view buffer (the pairs, their keys and weights).
    pub view: Handle<ShaderBuffer>,
}

/// Pairs a camera's blended keys have room for: one per base view it blends, at most
/// [`MAX_PAIRS`].
pub(crate) fn pair_room(settings: &ReconSettings) -> u32 {
    (settings.max_views as u32).clamp(1, MAX_PAIRS)
}

/// Adds the blended keys, their extraction and the pass.
pub(super) fn build(app: &mut App) {
    bevy::asset::embedded_asset!(app, "blend.wgsl");
    app.add_plugins(ExtractComponentPlugin::<BlendedKeys>::default());
    let Some(render_app) = app.get_sub_app_mut(RenderApp) else {
        return;
    };
    render_app
        .add_systems(RenderStartup, init_pipeline)
        .add_systems(
            Core3d,
            blend_keys
                .in_set(Core3dSystems::MainPass)
                .before(main_opaque_pass_3d),
        );
}

/// Gives every plenoptic camera its [`BlendedKeys`] at its pack's face size, and keeps what
/// the pass reads up to date.
pub(super) fn prepare_blended_keys(
    mut commands: Commands,
    backend: Res<ResolvedBackend>,
    keys: Res<KeyTextures>,
    mut cameras: Query<(
        Entity,
        &PlenopticCamera,
        &ViewBuffer,
        Option<&mut BlendedKeys>,
    )>,
    mut images: ResMut<Assets<Image>>,
) {
    for (entity, cam, view, blended) in &mut cameras {
        let tex = keys.0.get(&cam.pack.id());
        let face = tex.map_or(1, |t| t.face);
        let room = pair_room(&cam.settings);
        let new_images = |images: &mut Assets<Image>| {
            let layers = 6 * room;
            (
                images.add(storage_image(face, layers, TextureFormat::Rgba32Uint)),
                images.add(storage_image(face, layers, TextureFormat::Rgba32Uint)),
            )
        };
        // The CPU backend draws no proxy material that would read them.
        let pairs = if backend.0 == Backend::Gpu {
            view.params().pair_count
        } else {
            0
        };
        let key_images = view.keys.clone();
        match blended {
            None => {
                let (geometry, terms) = new_images(&mut images);
                commands.entity(entity).insert(BlendedKeys {
                    geometry,
                    terms,
                    face,
                    room,
                    pairs,
                    keys: key_images,
                    view: view.buffer.clone(),
                });
            }
            Some(mut b) => {
                if b.face != face || b.room != room {
                    let (geometry, terms) = new_images(&mut images);
                    b.geometry = geometry;
                    b.terms = terms;
                    b.face = face;
                    b.room = room;
                }
                if b.pairs != pairs || b.keys != key_images || b.view != view.buffer {
                    b.pairs = pairs;
                    b.keys = key_images;
                    b.view = view.buffer.clone();
                }
            }
        }
    }
}

/// The pass's pipeline and layouts: its outputs (group 0) and the keys and view buffer at
/// the materials' binding numbers (group 1).
#[derive(Resource)]
pub(super) struct BlendPipeline {
    layouts: [BindGroupLayoutDescriptor; 2],
    id: CachedComputePipelineId,
}

/// Queues the pass's pipeline.
fn init_pipeline(
    mut commands: Commands,
    asset_server: Res<AssetServer>,
    pipeline_cache: Res<PipelineCache>,
) {
    let out =
        || texture_storage_2d_array(TextureFormat::Rgba32Uint, StorageTextureAccess::WriteOnly);
    let outputs = BindGroupLayoutDescriptor::new(
        "plenoptic key blend",
        &BindGroupLayoutEntries::sequential(ShaderStages::COMPUTE, (out(), out())),
    );
    let layouts = [outputs, keys_layout("plenoptic key blend keys")];
    let id = pipeline_cache.queue_compute_pipeline(ComputePipelineDescriptor {
        label: Some("plenoptic key blend".into()),
        layout: layouts.to_vec(),
        shader: load_embedded_asset!(asset_server.as_ref(), "blend.wgsl"),
        shader_defs: vec![ShaderDefVal::UInt("MATERIAL_BIND_GROUP".into(), 1)],
        entry_point: Some(Cow::from("blend_keys")),
        ..default()
    });
    commands.insert_resource(BlendPipeline { layouts, id });
}

/// Blends a view's key pairs before its opaque pass: one thread per texel of each pair's six
/// faces.
pub(super) fn blend_keys(
    view: ViewQuery<&BlendedKeys>,
    pipeline: Option<Res<BlendPipeline>>,
    pipeline_cache: Res<PipelineCache>,
    buffers: Res<RenderAssets<GpuShaderBuffer>>,
    images: Res<RenderAssets<GpuImage>>,
    device: Res<RenderDevice>,
    mut ctx: RenderContext,
) {
    let blended = view.into_inner();
    let (Some(p), Some((cubes, shading))) = (pipeline, blended.keys.as_ref()) else {
        return;
    };
    if blended.pairs == 0 {
        return;
    }
    let (Some(compute), Some(cubes), Some(shading), Some(view), Some(geometry), Some(terms)) = (
        pipeline_cache.get_compute_pipeline(p.id),
        images.get(cubes),
        images.get(shading),
        buffers.get(&blended.view),
        images.get(&blended.geometry),
        images.get(&blended.terms),
    ) else {
        return;
    };
    if geometry.texture_descriptor.size.width != blended.face
        || geometry.texture_descriptor.size.depth_or_array_layers != 6 * blended.room
    {
        return;
    }
    let outputs = device.create_bind_group(
        "plenoptic key blend",
        &pipeline_cache.get_bind_group_layout(&p.layouts[0]),
        &BindGroupEntries::sequential((&geometry.texture_view, &terms.texture_view)),
    );
    let keys = keys_group(
        (&device, &pipeline_cache),
        ("plenoptic key blend keys", &p.layouts[1]),
        (cubes, shading),
        view,
    );
    dispatch_faces(
        &mut ctx,
        ("plenoptic key blend", "plenoptic/key_blend"),
        (compute, [&outputs, &keys]),
        blended.face,
        6 * blended.pairs.min(blended.room),
    );
}
