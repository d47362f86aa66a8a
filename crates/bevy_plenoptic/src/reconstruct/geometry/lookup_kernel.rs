//! The lookup kernel (thesis §8.2.3's direct lookups and their temporal-volume fallback, as a
//! compute pass): on a camera with the screen fill and [`PlenopticSettings::lookup_kernel`],
//! an opaque proxy fragment (or lit mesh's) makes no lookup; it computes what only it can
//! (its material, emission, reflection and the runtime sun) and appends a record to the
//! camera's hole list (`fill_entry.wgsl`'s `HoleRecord`: its point in its object's frame and
//! in the world, its object, albedo, face normal, sample mask and what it adds). After the
//! opaque pass `screen_fill.wgsl`'s `lookup_records` makes each record's lookups with
//! `lookup.wgsl`'s functions, one thread per record, writes an answered point's terms into
//! its pixel's entry and its colour over its record, and turns the rest into holes; the fill
//! kernel then fills the holes from those entries, and the point composite
//! ([`super::fill_composite`]) draws every record. So the lookups run in a compute pass
//! where every thread does the same work, not in a fragment shader compiled for its worst
//! path, and a fragment's registers are the material's. A fragment past the list's room
//! makes its own lookups, as a hole past it fills itself.
//!
//! Measured on lavapipe (`docs/results/measurements.md`, "The plugin's work per pixel"): the
//! same frames, but more reads (each record is read back, 64 bytes) and a longer frame, so
//! the setting is off by default until a GPU's timings decide.
//!
//! [`PlenopticSettings::lookup_kernel`]: crate::settings::PlenopticSettings::lookup_kernel

use bevy::asset::load_embedded_asset;
use bevy::prelude::*;
use bevy::render::render_asset::RenderAssets;
use bevy::render::render_resource::binding_types::{
    sampler, storage_buffer_read_only_sized, storage_buffer_sized, texture_2d_array,
};
use bevy::render::render_resource::{
    BindGroup, BindGroupEntries, BindGroupLayoutDescriptor, BindGroupLayoutEntries,
    CachedComputePipelineId, PipelineCache, Sampler, SamplerBindingType, SamplerDescriptor,
    ShaderStages, TextureSampleType,
};
use bevy::render::renderer::RenderDevice;
use bevy::render::storage::GpuShaderBuffer;
use bevy::render::texture::GpuImage;

use super::screen_fill::{ScreenFill, own_layout, queue_kernel};

/// The kernel's pipelines (without and with the cost counters), the layout of the materials'
/// bindings it reads (group 1; group 0 is the fill's own) and the nearest sampler its gathers
/// take.
#[derive(Resource)]
pub(super) struct LookupPipelines {
    layout: BindGroupLayoutDescriptor,
    plain: CachedComputePipelineId,
    counting: CachedComputePipelineId,
    sampler: Sampler,
}

impl LookupPipelines {
    /// The pipeline for a fill counting its cost or not.
    pub(super) fn id(&self, counting: bool) -> CachedComputePipelineId {
        if counting { self.counting } else { self.plain }
    }
}

/// Queues the kernel's pipelines.
pub(super) fn init_pipelines(
    mut commands: Commands,
    asset_server: Res<AssetServer>,
    pipeline_cache: Res<PipelineCache>,
    device: Res<RenderDevice>,
) {
    // The material's binding numbers (bindings.wgsl, counters.wgsl).
    let layout = BindGroupLayoutDescriptor::new(
        "plenoptic lookup kernel",
        &BindGroupLayoutEntries::with_indices(
            ShaderStages::COMPUTE,
            (
                (0, texture_2d_array(TextureSampleType::Uint)),
                (2, storage_buffer_read_only_sized(false, None)),
                (3, storage_buffer_read_only_sized(false, None)),
                (5, texture_2d_array(TextureSampleType::Uint)),
                (10, storage_buffer_read_only_sized(false, None)),
                (18, storage_buffer_sized(false, None)),
                (19, sampler(SamplerBindingType::NonFiltering)),
                (22, texture_2d_array(TextureSampleType::Uint)),
                (23, texture_2d_array(TextureSampleType::Uint)),
            ),
        ),
    );
    let shader = load_embedded_asset!(asset_server.as_ref(), "screen_fill.wgsl");
    let layouts = [own_layout(), layout.clone()];
    let pipeline = |label, counting| {
        queue_kernel(
            &pipeline_cache,
            (&shader, "lookup_records"),
            &layouts,
            label,
            counting,
        )
    };
    let plain = pipeline("plenoptic lookup kernel", false);
    let counting = pipeline("plenoptic lookup kernel (counting)", true);
    let sampler = device.create_sampler(&SamplerDescriptor {
        label: Some("plenoptic lookup kernel gathers"),
        ..default()
    });
    commands.insert_resource(LookupPipelines {
        layout,
        plain,
        counting,
        sampler,
    });
}

/// The kernel's group 1 for `fill`: the keys, volumes, view buffer, counters and blended keys
/// the camera's materials bind; `None` until all are on the GPU.
pub(super) fn material_group(
    fill: &ScreenFill,
    (pipelines, pipeline_cache): (&LookupPipelines, &PipelineCache),
    (buffers, images): (&RenderAssets<GpuShaderBuffer>, &RenderAssets<GpuImage>),
    device: &RenderDevice,
) -> Option<BindGroup> {
    let (cubes, shading) = fill.keys.as_ref()?;
    let lookups = fill.lookups.as_ref()?;
    let buffer = |h| {
        buffers
            .get(h)
            .map(|b: &GpuShaderBuffer| b.buffer.as_entire_binding())
    };
    let image = |h| images.get(h).map(|i: &GpuImage| &i.texture_view);
    Some(device.create_bind_group(
        "plenoptic lookup kernel",
        &pipeline_cache.get_bind_group_layout(&pipelines.layout),
        &BindGroupEntries::with_indices((
            (0, image(cubes)?),
            (2, buffer(&lookups.volumes.0)?),
            (3, buffer(&lookups.volumes.1)?),
            (5, image(shading)?),
            (10, buffer(&fill.view)?),
            (18, buffer(&fill.counters)?),
            (19, &pipelines.sampler),
            (22, image(&lookups.blended.0)?),
            (23, image(&lookups.blended.1)?),
        )),
    ))
}
