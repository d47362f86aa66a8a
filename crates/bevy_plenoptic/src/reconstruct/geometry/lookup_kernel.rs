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
//! The records are appended in no spatial order, so the sparse lighting's work is sorted into
//! passes whose threads all do the same: a material's fragment leaves its record to the
//! sparse passes, `anchor_lookups` runs one thread per anchor pixel in 8 × 8 groups and
//! finds its record through the pixel's entry, `interpolate_records` interpolates or puts the
//! record on the work list (as every record without a material), and `listed_lookups` looks
//! the work list up. Each is a compute pass with its own time span.
//!
//! Measured on lavapipe (`docs/results/measurements.md`, "The plugin's work per pixel"): the
//! same frames, but more reads (each record is read back, 64 bytes) and a longer frame
//! (the tour: 1.19× the fragments' lookups with the sparse lighting, which reads 23.2 texels
//! and records per pixel, 1.36× without it, 28.6), so the setting is off by default until a
//! GPU's timings decide.
//!
//! [`PlenopticSettings::lookup_kernel`]: crate::settings::PlenopticSettings::lookup_kernel
//! [`ReconSettings::sparse_lighting`]: plenoptic_recon::ReconSettings::sparse_lighting

use bevy::asset::load_embedded_asset;
use bevy::prelude::*;
use bevy::render::diagnostic::{DiagnosticsRecorder, RecordDiagnostics};
use bevy::render::render_asset::RenderAssets;
use bevy::render::render_resource::binding_types::{
    sampler, storage_buffer_read_only_sized, storage_buffer_sized, texture_2d_array,
};
use bevy::render::render_resource::{
    BindGroup, BindGroupEntries, BindGroupLayoutDescriptor, BindGroupLayoutEntries,
    CachedComputePipelineId, CommandEncoder, ComputePassDescriptor, ComputePipeline, PipelineCache,
    Sampler, SamplerBindingType, SamplerDescriptor, ShaderStages, TextureSampleType,
};
use bevy::render::renderer::RenderDevice;
use bevy::render::storage::{GpuShaderBuffer, ShaderBuffer};
use bevy::render::texture::GpuImage;

use super::screen_fill::{ScreenFill, own_layout, queue_kernel};

/// The kernel's pipelines of one variant (with the cost counters or without): its lookups',
/// the sparse lighting's anchors', its interpolation's and its work list's.
struct Kernels {
    lookups: CachedComputePipelineId,
    anchors: CachedComputePipelineId,
    interpolate: CachedComputePipelineId,
    listed: CachedComputePipelineId,
}

impl Kernels {
    /// Queues the four pipelines of `shader` with `layouts`, counting their cost or not.
    fn queue(
        cache: &PipelineCache,
        shader: &Handle<Shader>,
        layouts: &[BindGroupLayoutDescriptor],
        counting: bool,
    ) -> Self {
        let pipeline =
            |entry, label| queue_kernel(cache, (shader, entry), layouts, label, counting);
        Kernels {
            lookups: pipeline("lookup_records", "plenoptic lookup kernel"),
            anchors: pipeline("anchor_lookups", "plenoptic sparse lighting anchors"),
            interpolate: pipeline("interpolate_records", "plenoptic sparse lighting"),
            listed: pipeline("listed_lookups", "plenoptic listed lookups"),
        }
    }
}

/// Threads per workgroup side of `anchor_lookups` (`screen_fill.wgsl`'s `ANCHOR_GROUP`).
const ANCHOR_GROUP: u32 = 8;

/// Bytes of an anchor's cell (`screen_fill.wgsl`'s `anchors`) and of the work list's header.
const CELL_BYTES: u64 = 16;
const WORK_HEADER_BYTES: u64 = 16;

/// A camera's buffers for the sparse lighting, beside the screen fill's: the anchors' cells
/// (one per 2 × 2 pixels) and the work list, the indices of the records whose lookups are
/// made in a pass of their own (`screen_fill.wgsl`'s `WorkList`, room for every record).
#[derive(Debug, Clone, PartialEq)]
pub struct SparseBuffers {
    /// The anchors' cells, 16 bytes each.
    pub anchors: Handle<ShaderBuffer>,
    /// The work list: a count, then one record index per entry.
    pub work: Handle<ShaderBuffer>,
}

impl SparseBuffers {
    /// The buffers of a viewport of `size` whose hole list has `room` records, made by
    /// `buffer` (from a size in bytes); placeholders where the lookup `kernel` is off.
    pub(super) fn new(
        size: UVec2,
        room: u64,
        kernel: bool,
        mut buffer: impl FnMut(u64) -> Handle<ShaderBuffer>,
    ) -> Self {
        let cells = u64::from(size.x.div_ceil(2)) * u64::from(size.y.div_ceil(2));
        let (cells, room) = if kernel { (cells, room) } else { (0, 0) };
        SparseBuffers {
            anchors: buffer(cells * CELL_BYTES),
            work: buffer(WORK_HEADER_BYTES + room * 4),
        }
    }

    /// Clears the anchors' cells and the work list's count, before a frame's opaque pass.
    pub(super) fn clear(
        &self,
        encoder: &mut CommandEncoder,
        buffers: &RenderAssets<GpuShaderBuffer>,
    ) {
        if let (Some(anchors), Some(work)) = (buffers.get(&self.anchors), buffers.get(&self.work)) {
            encoder.clear_buffer(&anchors.buffer, 0, None);
            encoder.clear_buffer(&work.buffer, 0, Some(WORK_HEADER_BYTES));
        }
    }
}

/// The kernel's pipelines (queued when a camera first wants them: an app that never turns
/// the lookup kernel on compiles none), the layout of the materials' bindings it reads (group
/// 1; group 0 is the fill's own), its shader and the nearest sampler its gathers take.
#[derive(Resource)]
pub(super) struct LookupPipelines {
    layout: BindGroupLayoutDescriptor,
    shader: Handle<Shader>,
    /// Without and with the cost counters.
    kernels: [Option<Kernels>; 2],
    sampler: Sampler,
}

/// Makes the kernel's layout and sampler; its pipelines wait for [`queue_wanted`].
pub(super) fn init_pipelines(
    mut commands: Commands,
    asset_server: Res<AssetServer>,
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
    let sampler = device.create_sampler(&SamplerDescriptor {
        label: Some("plenoptic lookup kernel gathers"),
        ..default()
    });
    commands.insert_resource(LookupPipelines {
        layout,
        shader: load_embedded_asset!(asset_server.as_ref(), "screen_fill.wgsl"),
        kernels: [None, None],
        sampler,
    });
}

/// Queues the kernel's pipelines of a variant (counting or not) the first time a view's fill
/// takes the lookup kernel with it.
pub(super) fn queue_wanted(
    pipelines: Option<ResMut<LookupPipelines>>,
    cache: Res<PipelineCache>,
    fills: Query<&ScreenFill>,
) {
    let Some(mut pipelines) = pipelines else {
        return;
    };
    for fill in fills.iter().filter(|f| f.kernel) {
        let counting = usize::from(fill.counting);
        if pipelines.kernels[counting].is_none() {
            let layouts = [own_layout(), pipelines.layout.clone()];
            let kernels = Kernels::queue(&cache, &pipelines.shader, &layouts, fill.counting);
            pipelines.kernels[counting] = Some(kernels);
        }
    }
}

/// Records the lookup kernel's compute passes for `fill` into `encoder`, each with a span of
/// the render `diagnostics` (`plenoptic/lookups`; where the fill has the sparse lighting,
/// `plenoptic/sparse_anchors`, `plenoptic/sparse_interpolate` and `plenoptic/sparse_lookups`
/// instead), with the fill's
/// own bind group `own` and `workgroups` groups over the records; nothing until its pipelines
/// are compiled and its bindings on the GPU.
pub(super) fn dispatch_lookups(
    (encoder, diagnostics): (&mut CommandEncoder, Option<&DiagnosticsRecorder>),
    (fill, own, workgroups): (&ScreenFill, &BindGroup, u32),
    (pipelines, pipeline_cache): (&LookupPipelines, &PipelineCache),
    assets: (&RenderAssets<GpuShaderBuffer>, &RenderAssets<GpuImage>),
    device: &RenderDevice,
) {
    let Some(k) = &pipelines.kernels[usize::from(fill.counting)] else {
        return;
    };
    let get = |id: CachedComputePipelineId| pipeline_cache.get_compute_pipeline(id);
    let (Some(lookups), Some(anchors), Some(interpolate), Some(listed), Some(material)) = (
        get(k.lookups),
        get(k.anchors),
        get(k.interpolate),
        get(k.listed),
        material_group(fill, (pipelines, pipeline_cache), assets, device),
    ) else {
        return;
    };
    let mut stage = |name: &'static str, pipeline: &ComputePipeline, grid: UVec2| {
        let mut pass = encoder.begin_compute_pass(&ComputePassDescriptor {
            label: Some(name),
            ..default()
        });
        let span = diagnostics.pass_span(&mut pass, name);
        pass.set_bind_group(0, own, &[]);
        pass.set_bind_group(1, &material, &[]);
        pass.set_pipeline(pipeline);
        pass.dispatch_workgroups(grid.x, grid.y, 1);
        span.end(&mut pass);
    };
    let records = UVec2::new(workgroups, 1);
    if !fill.sparse {
        stage("plenoptic/lookups", lookups, records);
    } else {
        // One thread per anchor, the pixels of even row and column.
        let side = 2 * ANCHOR_GROUP;
        stage(
            "plenoptic/sparse_anchors",
            anchors,
            (fill.size + (side - 1)) / side,
        );
        stage("plenoptic/sparse_interpolate", interpolate, records);
        stage("plenoptic/sparse_lookups", listed, records);
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
