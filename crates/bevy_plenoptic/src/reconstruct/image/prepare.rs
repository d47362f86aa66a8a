//! The render-world side of image mode: the compute pipelines (one per pass of
//! `image.wgsl`), the scratch buffers the views share (sized for the largest view), and each
//! view's bind groups ([`ImageBindGroups`], on its render-world view entity).

use std::borrow::Cow;

use bevy::asset::load_embedded_asset;
use bevy::prelude::*;
use bevy::render::render_asset::RenderAssets;
use bevy::render::render_resource::binding_types::{
    storage_buffer_read_only_sized, storage_buffer_sized, texture_2d_array, texture_storage_2d,
    uniform_buffer,
};
use bevy::render::render_resource::{
    BindGroup, BindGroupEntries, BindGroupLayoutDescriptor, BindGroupLayoutEntries, Buffer,
    BufferDescriptor, BufferUsages, CachedComputePipelineId, ComputePipelineDescriptor,
    PipelineCache, ShaderStages, StorageTextureAccess, TextureFormat, TextureSampleType,
    UniformBuffer,
};
use bevy::render::renderer::{RenderDevice, RenderQueue};
use bevy::render::texture::GpuImage;

use super::{ImageJob, ImageParams, MAX_IMAGE_VIEWS};
use crate::reconstruct::relight::{GroupLayers, no_group_layers};

/// The image-mode pipelines and their bind group layout.
#[derive(Resource)]
pub(super) struct ImagePipelines {
    pub(super) layout: BindGroupLayoutDescriptor,
    /// Bound as the group layers of a pack without them (bindings may not be missing).
    no_layers: Buffer,
    /// clear, splat_depth, splat_centre, splat_texel, blend, fill, write_output.
    pub(super) passes: [CachedComputePipelineId; 7],
}

const ENTRY_POINTS: [&str; 7] = [
    "clear",
    "splat_depth",
    "splat_centre",
    "splat_texel",
    "blend",
    "fill",
    "write_output",
];

/// Queues the passes' pipelines.
pub(super) fn init_pipelines(
    mut commands: Commands,
    asset_server: Res<AssetServer>,
    pipeline_cache: Res<PipelineCache>,
    device: Res<RenderDevice>,
) {
    let layout = BindGroupLayoutDescriptor::new(
        "plenoptic image mode",
        &BindGroupLayoutEntries::sequential(
            ShaderStages::COMPUTE,
            (
                texture_2d_array(TextureSampleType::Uint),
                uniform_buffer::<ImageParams>(false),
                storage_buffer_sized(false, None),
                storage_buffer_sized(false, None),
                storage_buffer_sized(false, None),
                storage_buffer_sized(false, None),
                texture_storage_2d(TextureFormat::Rgba32Float, StorageTextureAccess::WriteOnly),
                texture_2d_array(TextureSampleType::Uint),
                storage_buffer_read_only_sized(false, None),
            ),
        ),
    );
    let shader = load_embedded_asset!(asset_server.as_ref(), "image.wgsl");
    let passes = ENTRY_POINTS.map(|e| {
        pipeline_cache.queue_compute_pipeline(ComputePipelineDescriptor {
            label: Some(format!("plenoptic image mode: {e}").into()),
            layout: vec![layout.clone()],
            shader: shader.clone(),
            entry_point: Some(Cow::from(e)),
            ..default()
        })
    });
    let no_layers = no_group_layers(&device);
    commands.insert_resource(ImagePipelines {
        layout,
        passes,
        no_layers,
    });
}

/// Scratch buffers, grown as needed: splat keys, splat texels, two frame buffers.
#[derive(Resource, Default)]
pub(super) struct ImageBuffers {
    buffers: Option<[Buffer; 4]>,
    /// Pixels of the largest frame they hold (splats: [`MAX_IMAGE_VIEWS`] per pixel).
    capacity: u64,
}

/// A view's image-mode bind groups this frame (on its render-world view entity).
#[derive(Component)]
pub struct ImageBindGroups {
    /// Frame buffers (a, b) and (b, a) as (in, out).
    pub(super) groups: [BindGroup; 2],
    pub(super) params: ImageParams,
}

/// Prepares each view's bind groups for its job.
#[expect(clippy::too_many_arguments, reason = "a Bevy system's parameters")]
pub(super) fn prepare_bind_groups(
    mut commands: Commands,
    views: Query<(Entity, &ImageJob)>,
    pipelines: Option<Res<ImagePipelines>>,
    images: Res<RenderAssets<GpuImage>>,
    group_layers: Res<GroupLayers>,
    mut buffers: ResMut<ImageBuffers>,
    device: Res<RenderDevice>,
    queue: Res<RenderQueue>,
    pipeline_cache: Res<PipelineCache>,
) {
    // The scratch buffers serve every view in turn: sized for the largest.
    let need = views
        .iter()
        .filter_map(|(_, job)| job.0.as_ref())
        .map(|w| u64::from(w.params.size.x) * u64::from(w.params.size.y))
        .max()
        .unwrap_or(0);
    if need > 0 && (buffers.capacity < need || buffers.buffers.is_none()) {
        let make = |label: &'static str, bytes: u64| {
            device.create_buffer(&BufferDescriptor {
                label: Some(label),
                size: bytes.max(16),
                usage: BufferUsages::STORAGE,
                mapped_at_creation: false,
            })
        };
        let splats = need * MAX_IMAGE_VIEWS as u64;
        buffers.buffers = Some([
            make("plenoptic image splat keys", splats * 8),
            make("plenoptic image splat texels", splats * 4),
            make("plenoptic image frame a", need * 16),
            make("plenoptic image frame b", need * 16),
        ]);
        buffers.capacity = need;
    }
    for (view, job) in &views {
        let groups = (|| {
            let (work, pipelines) = (job.0.as_ref()?, pipelines.as_ref()?);
            let (cubes, output) = (images.get(&work.cubes)?, images.get(&work.output)?);
            let shading = images.get(&work.shading)?;
            let layers = group_layers
                .0
                .get(&work.pack)
                .unwrap_or(&pipelines.no_layers);
            let p = work.params.size;
            if output.texture_descriptor.size.width != p.x
                || output.texture_descriptor.size.height != p.y
            {
                return None;
            }
            let [keys, texels, a, b] = buffers.buffers.as_ref()?;
            let mut uniform = UniformBuffer::from(work.params.clone());
            uniform.write_buffer(&device, &queue);
            let layout = pipeline_cache.get_bind_group_layout(&pipelines.layout);
            let group = |fin: &Buffer, fout: &Buffer| {
                device.create_bind_group(
                    "plenoptic image mode",
                    &layout,
                    &BindGroupEntries::sequential((
                        &cubes.texture_view,
                        &uniform,
                        keys.as_entire_binding(),
                        texels.as_entire_binding(),
                        fin.as_entire_binding(),
                        fout.as_entire_binding(),
                        &output.texture_view,
                        &shading.texture_view,
                        layers.as_entire_binding(),
                    )),
                )
            };
            Some(ImageBindGroups {
                groups: [group(a, b), group(b, a)],
                params: work.params.clone(),
            })
        })();
        match groups {
            Some(g) => commands.entity(view).insert(g),
            None => commands.entity(view).remove::<ImageBindGroups>(),
        };
    }
}
