//! The light-group relight pass of the geometry-assisted path
//! ([`crate::reconstruct::relight`] says what it does and why per key): the camera's
//! [`RelitKeys`] kept in step with its lookups, the view buffer's light-group fields, and the
//! compute pass (`relight.wgsl`) that writes each looked-up key relit before the key blend
//! and the opaque pass read it.

use std::borrow::Cow;

use bevy::asset::load_embedded_asset;
use bevy::core_pipeline::core_3d::main_opaque_pass_3d;
use bevy::core_pipeline::schedule::{Core3d, Core3dSystems};
use bevy::prelude::*;
use bevy::render::extract_component::ExtractComponentPlugin;
use bevy::render::render_asset::RenderAssets;
use bevy::render::render_resource::binding_types::{
    storage_buffer_read_only_sized, texture_storage_2d_array,
};
use bevy::render::render_resource::{
    BindGroupEntries, BindGroupLayoutDescriptor, BindGroupLayoutEntries, Buffer,
    CachedComputePipelineId, ComputePipelineDescriptor, PipelineCache, ShaderStages,
    StorageTextureAccess, TextureFormat,
};
use bevy::render::renderer::{RenderContext, RenderDevice, ViewQuery};
use bevy::render::storage::GpuShaderBuffer;
use bevy::render::texture::GpuImage;
use bevy::render::{RenderApp, RenderStartup};
use bevy::shader::ShaderDefVal;
use plenoptic_recon::relight::Relight;

use super::key_pass::{dispatch_faces, keys_group, keys_layout};
use super::view::{ViewBuffer, ViewParams};
use crate::asset::RadiancePack;
use crate::camera::PlenopticCamera;
use crate::reconstruct::relight::{
    BlendUniforms, GroupLayers, RelitKeys, no_group_layers, stored_groups,
};
use crate::reconstruct::{KeyTextures, MAX_LOOKUPS};
use crate::settings::{Backend, ResolvedBackend};

/// Adds the relit keys' extraction and the pass.
pub(super) fn build(app: &mut App) {
    bevy::asset::embedded_asset!(app, "relight_keys.wgsl");
    app.add_plugins(ExtractComponentPlugin::<RelitKeys>::default());
    let Some(render_app) = app.get_sub_app_mut(RenderApp) else {
        return;
    };
    render_app
        .add_systems(RenderStartup, init_pipeline)
        .add_systems(
            Core3d,
            relight_keys
                .in_set(Core3dSystems::MainPass)
                .before(super::blend::blend_keys)
                .before(main_opaque_pass_3d),
        );
}

/// Gives every GPU camera whose pack stores light-group layers, or whose lights are not as
/// baked, its [`RelitKeys`] (at the pack's face size), and takes them from the others.
pub(super) fn add_relit_keys(
    mut commands: Commands,
    backend: Res<ResolvedBackend>,
    keys: Res<KeyTextures>,
    packs: Res<Assets<RadiancePack>>,
    cameras: Query<(Entity, &PlenopticCamera, Option<&RelitKeys>)>,
    mut images: ResMut<Assets<Image>>,
) {
    for (entity, cam, relit) in &cameras {
        let id = cam.pack.id();
        let (Some(pack), Some(tex)) = (packs.get(id), keys.0.get(&id)) else {
            continue;
        };
        let groups = stored_groups(pack.reader.manifest());
        if backend.0 != Backend::Gpu || (groups == 0 && cam.lights.is_identity()) {
            if relit.is_some() {
                commands.entity(entity).remove::<RelitKeys>();
            }
            continue;
        }
        if relit.is_some_and(|r| r.face == tex.face && r.pack == id) {
            continue;
        }
        let (image, shading) = RelitKeys::textures(tex.face, &mut images);
        commands.entity(entity).insert(RelitKeys {
            image,
            shading,
            face: tex.face,
            pack: id,
            keys: Some((tex.image.clone(), tex.shading.clone())),
            lookups: 0,
            groups,
            view: Handle::default(),
        });
    }
}

/// Keeps what the pass reads up to date with the camera's view buffer.
pub(super) fn update_relit_keys(mut cameras: Query<(&ViewBuffer, &mut RelitKeys)>) {
    for (view, mut relit) in &mut cameras {
        let lookups = view.params().lookup_count;
        if relit.lookups != lookups || relit.view != view.buffer {
            relit.lookups = lookups;
            relit.view = view.buffer.clone();
        }
    }
}

/// The light-group fields of `params` for a camera with relit keys on a pack that stores
/// `groups` layers (sun, lamps, environment and emission are scaled where they are filled):
/// the blend of its relit keys (the lookups' layers moved to the relit keys: lookup `k` at
/// `6k`), and the volume fallback's blend of its samples' layers.
pub(super) fn fill(params: &mut ViewParams, relight: &Relight, groups: u32) {
    params.light_groups = groups;
    let b = BlendUniforms::new(relight);
    params.light_base = b.base;
    params.light_sky = b.sky;
    params.light_layers = b.layers;
    params.light_layer_count = b.count;
    for k in 0..(params.lookup_count as usize).min(MAX_LOOKUPS) {
        params.lookups[k].source_layer = params.lookups[k].first_layer;
        params.lookups[k].first_layer = (6 * k) as u32;
    }
}

/// The pass's pipeline and layouts: its outputs and the group layers (group 0) and the keys
/// and view buffer at the materials' binding numbers (group 1).
#[derive(Resource)]
struct RelightPipeline {
    layouts: [BindGroupLayoutDescriptor; 2],
    id: CachedComputePipelineId,
    /// Bound as the group layers of a pack without them (bindings may not be missing).
    no_layers: Buffer,
}

/// Queues the pass's pipeline.
fn init_pipeline(
    mut commands: Commands,
    asset_server: Res<AssetServer>,
    pipeline_cache: Res<PipelineCache>,
    device: Res<RenderDevice>,
) {
    let out = |format| texture_storage_2d_array(format, StorageTextureAccess::WriteOnly);
    let outputs = BindGroupLayoutDescriptor::new(
        "plenoptic relight",
        &BindGroupLayoutEntries::sequential(
            ShaderStages::COMPUTE,
            (
                out(TextureFormat::Rgba32Uint),
                out(TextureFormat::Rg32Uint),
                storage_buffer_read_only_sized(false, None),
            ),
        ),
    );
    let layouts = [outputs, keys_layout("plenoptic relight keys")];
    let id = pipeline_cache.queue_compute_pipeline(ComputePipelineDescriptor {
        label: Some("plenoptic relight".into()),
        layout: layouts.to_vec(),
        shader: load_embedded_asset!(asset_server.as_ref(), "relight_keys.wgsl"),
        shader_defs: vec![ShaderDefVal::UInt("MATERIAL_BIND_GROUP".into(), 1)],
        entry_point: Some(Cow::from("relight_keys")),
        ..default()
    });
    let no_layers = no_group_layers(&device);
    commands.insert_resource(RelightPipeline {
        layouts,
        id,
        no_layers,
    });
}

/// Relights the keys a view looks up, before its key blend and opaque pass: one thread per
/// texel of each lookup's six faces.
#[expect(clippy::too_many_arguments, reason = "a Bevy system's parameters")]
fn relight_keys(
    view: ViewQuery<&RelitKeys>,
    pipeline: Option<Res<RelightPipeline>>,
    pipeline_cache: Res<PipelineCache>,
    buffers: Res<RenderAssets<GpuShaderBuffer>>,
    images: Res<RenderAssets<GpuImage>>,
    groups: Res<GroupLayers>,
    device: Res<RenderDevice>,
    mut ctx: RenderContext,
) {
    let relit = view.into_inner();
    let (Some(p), Some((cubes, shading))) = (pipeline, relit.keys.as_ref()) else {
        return;
    };
    if relit.lookups == 0 {
        return;
    }
    let found = (
        pipeline_cache.get_compute_pipeline(p.id),
        (images.get(cubes), images.get(shading)),
        buffers.get(&relit.view),
        (images.get(&relit.image), images.get(&relit.shading)),
        groups.0.get(&relit.pack).or(Some(&p.no_layers)),
    );
    let (
        Some(compute),
        (Some(cubes), Some(shading)),
        Some(view),
        (Some(out), Some(out_shading)),
        Some(layers),
    ) = found
    else {
        return;
    };
    if out.texture_descriptor.size.width != relit.face {
        return;
    }
    let outputs = device.create_bind_group(
        "plenoptic relight",
        &pipeline_cache.get_bind_group_layout(&p.layouts[0]),
        &BindGroupEntries::sequential((
            &out.texture_view,
            &out_shading.texture_view,
            layers.as_entire_binding(),
        )),
    );
    let keys = keys_group(
        (&device, &pipeline_cache),
        ("plenoptic relight keys", &p.layouts[1]),
        (cubes, shading),
        view,
    );
    dispatch_faces(
        &mut ctx,
        ("plenoptic relight", "plenoptic/relight"),
        (compute, [&outputs, &keys]),
        relit.face,
        6 * relit.lookups.min(MAX_LOOKUPS as u32),
    );
}
