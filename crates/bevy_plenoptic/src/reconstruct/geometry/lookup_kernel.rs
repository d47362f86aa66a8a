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
//! With [`ReconSettings::sparse_lighting`] (`plenoptic_recon`'s `geometry::sparse`, the
//! CPU's rule) a record shaded from its material is looked up only on an *anchor* (even row
//! and column), which leaves a cell for its neighbours: the keys that answered it with their
//! taps, its distance, normal and object. A second pass (`interpolate_records`) gives every
//! other such record its two or four anchors' mean where they stand for its own lookups
//! (the same object answered by the same keys with all their taps, no crease, no depth
//! step), a joint bilateral upsampling guided by object id, keys, normal and depth; the rest
//! (object edges, creases, occlusion edges in a base view) look themselves up at full
//! resolution. Albedo, the sun and reflections stay per pixel in the fragments.
//!
//! Measured on lavapipe (`docs/results/measurements.md`, "The plugin's work per pixel"): the
//! same frames, but more reads (each record is read back, 64 bytes) and a longer frame, so
//! the setting is off by default until a GPU's timings decide.
//!
//! [`PlenopticSettings::lookup_kernel`]: crate::settings::PlenopticSettings::lookup_kernel
//! [`ReconSettings::sparse_lighting`]: plenoptic_recon::ReconSettings::sparse_lighting

use bevy::asset::load_embedded_asset;
use bevy::prelude::*;
use bevy::render::render_asset::RenderAssets;
use bevy::render::render_resource::binding_types::{
    sampler, storage_buffer_read_only_sized, storage_buffer_sized, texture_2d_array,
};
use bevy::render::render_resource::{
    BindGroup, BindGroupEntries, BindGroupLayoutDescriptor, BindGroupLayoutEntries,
    CachedComputePipelineId, ComputePass, PipelineCache, Sampler, SamplerBindingType,
    SamplerDescriptor, ShaderStages, TextureSampleType,
};
use bevy::render::renderer::RenderDevice;
use bevy::render::storage::GpuShaderBuffer;
use bevy::render::texture::GpuImage;

use super::screen_fill::{ScreenFill, own_layout, queue_kernel};

/// The kernel's pipelines, without and with the cost counters: its lookups' and the sparse
/// lighting's interpolation.
struct Kernels {
    lookups: [CachedComputePipelineId; 2],
    interpolate: [CachedComputePipelineId; 2],
}

/// The kernel's pipelines, the layout of the materials' bindings it reads (group 1; group 0
/// is the fill's own) and the nearest sampler its gathers take.
#[derive(Resource)]
pub(super) struct LookupPipelines {
    layout: BindGroupLayoutDescriptor,
    kernels: Kernels,
    sampler: Sampler,
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
    let pipeline = |entry, label, counting| {
        queue_kernel(&pipeline_cache, (&shader, entry), &layouts, label, counting)
    };
    let kernels = Kernels {
        lookups: [
            pipeline("lookup_records", "plenoptic lookup kernel", false),
            pipeline("lookup_records", "plenoptic lookup kernel (counting)", true),
        ],
        interpolate: [
            pipeline("interpolate_records", "plenoptic sparse lighting", false),
            pipeline(
                "interpolate_records",
                "plenoptic sparse lighting (counting)",
                true,
            ),
        ],
    };
    let sampler = device.create_sampler(&SamplerDescriptor {
        label: Some("plenoptic lookup kernel gathers"),
        ..default()
    });
    commands.insert_resource(LookupPipelines {
        layout,
        kernels,
        sampler,
    });
}

/// Records the lookup kernel's dispatches for `fill` into `pass` (the sparse lighting's second
/// pass after the first where the fill has it), with the fill's own bind group `own` and
/// `workgroups` groups; nothing until its pipelines are compiled and its bindings on the GPU.
pub(super) fn dispatch_lookups(
    pass: &mut ComputePass,
    (fill, own, workgroups): (&ScreenFill, &BindGroup, u32),
    (pipelines, pipeline_cache): (&LookupPipelines, &PipelineCache),
    assets: (&RenderAssets<GpuShaderBuffer>, &RenderAssets<GpuImage>),
    device: &RenderDevice,
) {
    let counting = usize::from(fill.counting);
    let get = |id: CachedComputePipelineId| pipeline_cache.get_compute_pipeline(id);
    let (Some(lookups), Some(interpolate), Some(material)) = (
        get(pipelines.kernels.lookups[counting]),
        get(pipelines.kernels.interpolate[counting]),
        material_group(fill, (pipelines, pipeline_cache), assets, device),
    ) else {
        return;
    };
    pass.set_bind_group(0, own, &[]);
    pass.set_bind_group(1, &material, &[]);
    pass.set_pipeline(lookups);
    pass.dispatch_workgroups(workgroups, 1, 1);
    if fill.sparse {
        pass.set_pipeline(interpolate);
        pass.dispatch_workgroups(workgroups, 1, 1);
    }
}

/// The kernel's group 1 for `fill`: the keys, volumes, view buffer, counters and blended keys
/// the camera's materials bind; `None` until all are on the GPU.
fn material_group(
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
