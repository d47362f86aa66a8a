//! The screen-space hole fill (thesis §8.2.3; `plenoptic_recon`'s `geometry::fill` ring
//! search) as a compute pass over the opaque pass's output.
//!
//! A proxy fragment can not read its neighbours' results, so the fragment hole fill
//! (`fill.wgsl`) reconstructs every ring pixel again: on the tour that is ~98 % of the
//! reconstruction's loads (`docs/results/measurements.md`). On a camera with the screen fill
//! ([`ScreenFill`]) every fragment drawn in the opaque pass instead leaves its pixel an entry
//! in the camera's entry buffer (`fill_entry.wgsl`): its lighting and non-diffuse terms where
//! its lookups answered, else its hole, whose record (its point, albedo and what it adds on
//! top) it appends to the camera's hole list. After Bevy's opaque pass a compute kernel
//! (`screen_fill.wgsl`, one thread per listed hole) fills each hole from the nearest ring of
//! pixels holding its own object, shading their mean terms with the hole's albedo as the CPU
//! does, else takes the later fallbacks (the object's nearby texels, the heaviest key's
//! texel) from the keys itself, and writes the filled colour over the hole's record; a
//! point per record ([`super::fill_composite`]) then writes it into the view's target, to the
//! samples its fragment covered that are no nearer than its surface (with MSAA two
//! fragments may share a pixel; a record is its fragment's own). A ring pixel costs one
//! 16-byte load. Entries and list are cleared before the opaque pass; the fill runs before
//! the transparent pass, so glazing blends over filled pixels. Glazing and glass (drawn in the
//! transparent pass) keep the fragment fill, as does a hole beyond the list's room
//! ([`HOLE_SHARE`] of the viewport's pixels).
//!
//! With the lookup kernel ([`super::lookup_kernel`], off by default) the fragments make no
//! lookups at all: every opaque fragment appends a record, the lookup kernel answers the
//! records it can and writes their entries (with the sparse lighting in three passes: the
//! anchors', the pixels between them, the pixels they refused), and the fill kernel fills
//! the rest.
//!
//! The fill needs the camera's [`DepthPrepass`] (every [`PlenopticCamera`] requires one), on a
//! device that forces early depth tests ([`EarlyDepthSupport`]): a fragment writes its entry
//! only where the prepass kept it. It takes HDR and 8-bit targets alike (the composite
//! tonemaps for the latter) and any MSAA. Other cameras use the fragment fill; both give the
//! CPU's result.
//! [`ScreenFill::size`] is zero on them.

use std::borrow::Cow;

use bevy::asset::{RenderAssetUsages, load_embedded_asset};
use bevy::core_pipeline::core_3d::{main_opaque_pass_3d, main_transparent_pass_3d};
use bevy::core_pipeline::prepass::DepthPrepass;
use bevy::core_pipeline::schedule::{Core3d, Core3dSystems};
use bevy::prelude::*;
use bevy::render::camera::ExtractedCamera;
use bevy::render::diagnostic::RecordDiagnostics;
use bevy::render::extract_component::{ExtractComponent, ExtractComponentPlugin};
use bevy::render::render_asset::RenderAssets;
use bevy::render::render_resource::binding_types::{
    storage_buffer_read_only_sized, storage_buffer_sized, texture_2d_array, uniform_buffer,
};
use bevy::render::render_resource::{
    BindGroup, BindGroupEntries, BindGroupLayoutDescriptor, BindGroupLayoutEntries,
    CachedComputePipelineId, ComputePassDescriptor, ComputePipelineDescriptor, PipelineCache,
    ShaderStages, ShaderType, TextureSampleType, UniformBuffer,
};
use bevy::render::renderer::{RenderContext, RenderDevice, RenderQueue, ViewQuery};
use bevy::render::settings::WgpuFeatures;
use bevy::render::storage::{GpuShaderBuffer, ShaderBuffer};
use bevy::render::texture::GpuImage;
use bevy::render::view::ExtractedView;
use bevy::render::{Render, RenderApp, RenderStartup, RenderSystems};
use bevy::shader::ShaderDefVal;

use super::lookup_kernel::{LookupPipelines, SparseBuffers, dispatch_lookups};
use super::view::ViewBuffer;
use crate::camera::PlenopticCamera;
use crate::reconstruct::counters::CounterBuffer;
use crate::settings::{Backend, PlenopticSettings, ResolvedBackend};

/// Threads per workgroup of the kernel (`screen_fill.wgsl`'s `GROUP`).
const GROUP: u32 = 64;
/// Bytes of one pixel's entry (`fill_entry.wgsl`).
const ENTRY_BYTES: u64 = 16;
/// Bytes of a hole record (`HoleRecord`) and of the list's header (its count, aligned).
const RECORD_BYTES: u64 = 64;
const LIST_HEADER_BYTES: u64 = 16;
/// The share of a viewport's pixels the hole list has room for (a quarter; the tour's views
/// have 11 %, the room's densest 33 % at 8-texel faces, which then fill the rest in the
/// fragment).
pub const HOLE_SHARE: u64 = 4;

/// Whether the device can force the depth test before a fragment shader that writes storage
/// (wgpu's `SHADER_EARLY_DEPTH_TEST`: Vulkan, GL). The screen fill needs it: without it every
/// fragment hidden by the depth prepass would run the whole reconstruction and write its
/// entry. Decided when the plugin finishes.
#[derive(Resource, Debug, Clone, Copy, Default)]
pub struct EarlyDepthSupport(pub bool);

/// Inserts [`EarlyDepthSupport`] from the render device's features.
pub(super) fn finish(app: &mut App) {
    let supported = app
        .get_sub_app(RenderApp)
        .and_then(|r| r.world().get_resource::<RenderDevice>())
        .is_some_and(|d| d.features().contains(WgpuFeatures::SHADER_EARLY_DEPTH_TEST));
    app.insert_resource(EarlyDepthSupport(supported));
}

/// A camera's screen-space hole fill (see the module doc): its entry buffer, which its
/// materials bind, and what the kernel needs. Extracted onto the camera's render-world view.
#[derive(Component, Debug, Clone, ExtractComponent)]
pub struct ScreenFill {
    /// One entry per pixel of the viewport (16 bytes, a placeholder while off).
    pub entries: Handle<ShaderBuffer>,
    /// The hole list: a header and room for a [`HOLE_SHARE`] of the pixels' records.
    pub holes: Handle<ShaderBuffer>,
    /// The sparse lighting's anchor cells and work list (placeholders without the lookup
    /// kernel).
    pub sparse_buffers: SparseBuffers,
    /// The viewport's size in pixels; zero while the camera uses the fragment fill.
    pub size: UVec2,
    /// The ring search's largest radius (`ReconSettings::hole_fill_radius`).
    pub radius: u32,
    /// What the kernel's fallbacks read as the materials do: the pack's key texture and
    /// shading texture, the camera's view buffer and its counter buffer.
    pub keys: Option<(Handle<Image>, Handle<Image>)>,
    /// The camera's view buffer ([`super::view::ViewBuffer::buffer`]).
    pub view: Handle<ShaderBuffer>,
    /// The camera's counter buffer.
    pub counters: Handle<ShaderBuffer>,
    /// Whether the shaders count their cost ([`PlenopticSettings::cost_counters`]).
    pub counting: bool,
    /// Whether the opaque fragments leave their lookups to the lookup kernel
    /// ([`PlenopticSettings::lookup_kernel`]).
    pub kernel: bool,
    /// Whether the lookup kernel looks materials' lighting up at a quarter of the pixels and
    /// interpolates the rest ([`ReconSettings::sparse_lighting`]; only with `kernel`).
    ///
    /// [`ReconSettings::sparse_lighting`]: plenoptic_recon::ReconSettings::sparse_lighting
    pub sparse: bool,
    /// What the lookup kernel reads beside the keys: the pack's volume samples and bins, and
    /// the camera's blended keys.
    pub lookups: Option<LookupBindings>,
}

/// The lookup kernel's buffers and textures besides the fill's.
#[derive(Debug, Clone, PartialEq)]
pub struct LookupBindings {
    /// The pack's volume samples and bin offsets ([`super::volume::PackVolumes`]).
    pub volumes: (Handle<ShaderBuffer>, Handle<ShaderBuffer>),
    /// The camera's blended keys ([`super::blend::BlendedKeys`]).
    pub blended: (Handle<Image>, Handle<Image>),
}

impl ScreenFill {
    /// Whether the camera's opaque holes are filled by the kernel.
    pub fn on(&self) -> bool {
        self.size != UVec2::ZERO
    }

    /// The hole list's room: how many records it holds.
    pub(super) fn room(&self) -> u32 {
        list_room(self.size, self.kernel) as u32
    }
}

/// The pixels of a viewport of `size`.
fn pixels_of(size: UVec2) -> u64 {
    u64::from(size.x) * u64::from(size.y)
}

/// The records a viewport of `size` has room for in its hole list: a [`HOLE_SHARE`] of its
/// pixels, or with the lookup `kernel` one per pixel and a [`HOLE_SHARE`] more (MSAA gives an
/// edge pixel two fragments); at least one.
fn list_room(size: UVec2, kernel: bool) -> u64 {
    let share = pixels_of(size) / HOLE_SHARE;
    if kernel {
        pixels_of(size) + share
    } else {
        share
    }
    .max(1)
}

/// The fill passes' uniform (`fill_entry.wgsl`'s `FillParams`).
#[derive(ShaderType, Clone, Debug)]
pub(super) struct FillParams {
    size: UVec2,
    offset: UVec2,
    radius: u32,
    exposure: f32,
    eye: Vec4,
}

impl FillParams {
    /// The uniform of `fill` on `camera`'s view, seen from `eye`.
    pub(super) fn new(fill: &ScreenFill, camera: &ExtractedCamera, eye: Vec3) -> Self {
        Self {
            eye: eye.extend(1.0),
            size: fill.size,
            offset: camera
                .viewport
                .as_ref()
                .map_or(UVec2::ZERO, |v| v.physical_position),
            radius: fill.radius,
            exposure: camera.exposure,
        }
    }
}

/// Adds the fill: the main-world entries, their extraction and the render-world passes.
pub(super) fn build(app: &mut App) {
    bevy::shader::load_shader_library!(app, "fill_entry.wgsl");
    bevy::asset::embedded_asset!(app, "screen_fill.wgsl");
    bevy::asset::embedded_asset!(app, "fill_composite.wgsl");
    app.add_plugins(ExtractComponentPlugin::<ScreenFill>::default());
    let Some(render_app) = app.get_sub_app_mut(RenderApp) else {
        return;
    };
    render_app
        .add_systems(
            RenderStartup,
            (
                init_pipelines,
                super::lookup_kernel::init_pipelines,
                super::fill_composite::init_composite,
            ),
        )
        .add_systems(
            Render,
            super::lookup_kernel::queue_wanted.in_set(RenderSystems::Queue),
        )
        .add_systems(
            Core3d,
            (
                clear_entries
                    .in_set(Core3dSystems::MainPass)
                    .before(main_opaque_pass_3d),
                (fill_holes, super::fill_composite::composite_fill)
                    .chain()
                    .in_set(Core3dSystems::MainPass)
                    .after(main_opaque_pass_3d)
                    .before(main_transparent_pass_3d),
            ),
        );
}

/// Whether a camera can take the screen fill: the GPU backend and a depth prepass.
fn fill_possible(backend: Backend, prepass: bool) -> bool {
    backend == Backend::Gpu && prepass
}

/// Gives every plenoptic camera its [`ScreenFill`], sized to its viewport where the app wants
/// the fill ([`PlenopticSettings::screen_fill`]) and the camera can take it (new buffers when
/// the size changes).
#[expect(clippy::type_complexity, reason = "a Bevy system's query")]
pub(super) fn prepare_screen_fill(
    mut commands: Commands,
    backend: Res<ResolvedBackend>,
    (settings, early_depth): (Res<PlenopticSettings>, Option<Res<EarlyDepthSupport>>),
    mut cameras: Query<(
        Entity,
        &Camera,
        &PlenopticCamera,
        (&CounterBuffer, &ViewBuffer),
        Has<DepthPrepass>,
        Option<&mut ScreenFill>,
    )>,
    mut buffers: ResMut<Assets<ShaderBuffer>>,
    volumes: Res<super::volume::VolumeBuffers>,
) {
    for (entity, camera, cam, (counters, view), prepass, fill) in &mut cameras {
        let kernel = settings.lookup_kernel;
        let size = match camera.physical_viewport_size() {
            Some(s)
                if settings.screen_fill
                    && early_depth.as_ref().is_some_and(|e| e.0)
                    && fill_possible(backend.0, prepass) =>
            {
                s
            }
            _ => UVec2::ZERO,
        };
        let new_buffers = |buffers: &mut Assets<ShaderBuffer>| {
            let room = list_room(size, kernel);
            let list = LIST_HEADER_BYTES + room * RECORD_BYTES;
            let mut buffer = |bytes: u64| {
                let bytes = bytes.max(ENTRY_BYTES) as usize;
                buffers.add(ShaderBuffer::with_size(
                    bytes,
                    RenderAssetUsages::RENDER_WORLD,
                ))
            };
            let (entries, holes) = (buffer(pixels_of(size) * ENTRY_BYTES), buffer(list));
            (
                entries,
                holes,
                SparseBuffers::new(size, room, kernel, buffer),
            )
        };
        let wanted = |(entries, holes, sparse_buffers)| ScreenFill {
            entries,
            holes,
            sparse_buffers,
            size,
            radius: cam.settings.hole_fill_radius,
            keys: view.keys.clone(),
            view: view.buffer.clone(),
            counters: counters.buffer.clone(),
            counting: settings.cost_counters,
            kernel,
            sparse: kernel && cam.settings.sparse_lighting,
            lookups: volumes
                .0
                .get(&cam.pack.id())
                .zip(view.blended.as_ref())
                .map(|(v, b)| LookupBindings {
                    volumes: (v.samples.clone(), v.bins.clone()),
                    blended: b.clone(),
                }),
        };
        match fill {
            None => {
                commands
                    .entity(entity)
                    .insert(wanted(new_buffers(&mut buffers)));
            }
            Some(mut f) => {
                let handles = if f.size == size && f.kernel == kernel {
                    (f.entries.clone(), f.holes.clone(), f.sparse_buffers.clone())
                } else {
                    new_buffers(&mut buffers)
                };
                let w = wanted(handles);
                if !same_fill(&f, &w) {
                    *f = w;
                }
            }
        }
    }
}

/// Whether two fills bind and size the same (written only when not, so that change detection
/// sees only real changes).
fn same_fill(a: &ScreenFill, b: &ScreenFill) -> bool {
    a.entries == b.entries
        && a.holes == b.holes
        && a.sparse_buffers == b.sparse_buffers
        && a.sparse == b.sparse
        && a.size == b.size
        && a.radius == b.radius
        && a.keys == b.keys
        && a.view == b.view
        && a.counters == b.counters
        && a.counting == b.counting
        && a.kernel == b.kernel
        && a.lookups == b.lookups
}

/// The kernel's pipelines (without and with the cost counters) and their layouts: the fill's
/// own bindings (group 0) and the materials' that the fallbacks read (group 1).
#[derive(Resource)]
struct FillPipelines {
    layouts: [BindGroupLayoutDescriptor; 2],
    plain: CachedComputePipelineId,
    counting: CachedComputePipelineId,
}

/// The layout of the fill's own bindings (group 0 of its kernels): the entries (which the
/// lookup kernel writes), the uniform, the hole list and the sparse lighting's anchors and
/// work list.
pub(super) fn own_layout() -> BindGroupLayoutDescriptor {
    BindGroupLayoutDescriptor::new(
        "plenoptic screen fill",
        &BindGroupLayoutEntries::sequential(
            ShaderStages::COMPUTE,
            (
                storage_buffer_sized(false, None),
                uniform_buffer::<FillParams>(false),
                storage_buffer_sized(false, None),
                storage_buffer_sized(false, None),
                storage_buffer_sized(false, None),
            ),
        ),
    )
}

/// Queues the pipeline of `screen_fill.wgsl`'s entry point `entry` with `layouts`, counting
/// its cost or not.
pub(super) fn queue_kernel(
    pipeline_cache: &PipelineCache,
    (shader, entry): (&Handle<Shader>, &'static str),
    layouts: &[BindGroupLayoutDescriptor],
    label: &'static str,
    counting: bool,
) -> CachedComputePipelineId {
    let mut shader_defs = vec![ShaderDefVal::UInt("MATERIAL_BIND_GROUP".into(), 1)];
    if counting {
        shader_defs.push("PLENOPTIC_COUNTERS".into());
    }
    pipeline_cache.queue_compute_pipeline(ComputePipelineDescriptor {
        label: Some(label.into()),
        layout: layouts.to_vec(),
        shader: shader.clone(),
        shader_defs,
        entry_point: Some(Cow::from(entry)),
        ..default()
    })
}

/// Queues the kernel's two pipelines.
fn init_pipelines(
    mut commands: Commands,
    asset_server: Res<AssetServer>,
    pipeline_cache: Res<PipelineCache>,
) {
    let own = own_layout();
    // The material's binding numbers (bindings.wgsl, counters.wgsl).
    let material = BindGroupLayoutDescriptor::new(
        "plenoptic screen fill lookups",
        &BindGroupLayoutEntries::with_indices(
            ShaderStages::COMPUTE,
            (
                (0, texture_2d_array(TextureSampleType::Uint)),
                (5, texture_2d_array(TextureSampleType::Uint)),
                (10, storage_buffer_read_only_sized(false, None)),
                (18, storage_buffer_sized(false, None)),
            ),
        ),
    );
    let layouts = [own, material];
    let shader = load_embedded_asset!(asset_server.as_ref(), "screen_fill.wgsl");
    let pipeline = |label, counting| {
        queue_kernel(
            &pipeline_cache,
            (&shader, "fill_holes"),
            &layouts,
            label,
            counting,
        )
    };
    let plain = pipeline("plenoptic screen fill", false);
    let counting = pipeline("plenoptic screen fill (counting)", true);
    commands.insert_resource(FillPipelines {
        layouts,
        plain,
        counting,
    });
}

/// Clears a view's entries and its hole list's count before its opaque pass: a pixel no
/// proxy covers holds nothing.
fn clear_entries(
    view: ViewQuery<&ScreenFill>,
    buffers: Res<RenderAssets<GpuShaderBuffer>>,
    mut ctx: RenderContext,
) {
    let fill = view.into_inner();
    if !fill.on() {
        return;
    }
    let (Some(entries), Some(holes)) = (buffers.get(&fill.entries), buffers.get(&fill.holes))
    else {
        return;
    };
    let encoder = ctx.command_encoder();
    encoder.clear_buffer(&entries.buffer, 0, None);
    encoder.clear_buffer(&holes.buffer, 0, Some(LIST_HEADER_BYTES));
    if fill.sparse {
        fill.sparse_buffers.clear(encoder, &buffers);
    }
}

/// A view's bind groups for the kernel (its own, the lookups'); `None` until
/// everything is on the GPU, or while the entries have another size than the view.
fn bind_groups(
    fill: &ScreenFill,
    params: FillParams,
    (pipelines, pipeline_cache): (&FillPipelines, &PipelineCache),
    (buffers, images): (&RenderAssets<GpuShaderBuffer>, &RenderAssets<GpuImage>),
    (device, queue): (&RenderDevice, &RenderQueue),
) -> Option<[BindGroup; 2]> {
    let entries = buffers.get(&fill.entries)?;
    let (cubes, shading) = fill.keys.as_ref()?;
    if !fill.on() || entries.buffer.size() < pixels_of(fill.size) * ENTRY_BYTES {
        return None;
    }
    let mut uniform = UniformBuffer::from(params);
    uniform.write_buffer(device, queue);
    let own = device.create_bind_group(
        "plenoptic screen fill",
        &pipeline_cache.get_bind_group_layout(&pipelines.layouts[0]),
        &BindGroupEntries::sequential((
            entries.buffer.as_entire_binding(),
            uniform.binding()?,
            buffers.get(&fill.holes)?.buffer.as_entire_binding(),
            buffers
                .get(&fill.sparse_buffers.anchors)?
                .buffer
                .as_entire_binding(),
            buffers
                .get(&fill.sparse_buffers.work)?
                .buffer
                .as_entire_binding(),
        )),
    );
    let material = device.create_bind_group(
        "plenoptic screen fill lookups",
        &pipeline_cache.get_bind_group_layout(&pipelines.layouts[1]),
        &BindGroupEntries::with_indices((
            (0, &images.get(cubes)?.texture_view),
            (5, &images.get(shading)?.texture_view),
            (10, buffers.get(&fill.view)?.buffer.as_entire_binding()),
            (18, buffers.get(&fill.counters)?.buffer.as_entire_binding()),
        )),
    );
    Some([own, material])
}

/// Runs the kernel over a view's hole list after its opaque pass, one thread per record of the
/// list's room.
#[expect(clippy::too_many_arguments, reason = "a Bevy system's parameters")]
fn fill_holes(
    view: ViewQuery<(&ScreenFill, &ExtractedCamera, &ExtractedView)>,
    (pipelines, lookup): (Option<Res<FillPipelines>>, Option<Res<LookupPipelines>>),
    pipeline_cache: Res<PipelineCache>,
    buffers: Res<RenderAssets<GpuShaderBuffer>>,
    images: Res<RenderAssets<GpuImage>>,
    device: Res<RenderDevice>,
    queue: Res<RenderQueue>,
    mut ctx: RenderContext,
) {
    let (fill, camera, extracted) = view.into_inner();
    let Some(pipelines) = pipelines else {
        return;
    };
    let id = if fill.counting {
        pipelines.counting
    } else {
        pipelines.plain
    };
    let Some(pipeline) = pipeline_cache.get_compute_pipeline(id) else {
        return;
    };
    let Some(groups) = bind_groups(
        fill,
        FillParams::new(fill, camera, extracted.world_from_view.translation()),
        (&pipelines, &pipeline_cache),
        (&buffers, &images),
        (&device, &queue),
    ) else {
        return;
    };
    // One thread per record of the list's room; those past the holes listed return at once.
    let recorder = ctx.diagnostic_recorder();
    let diagnostics = recorder.as_deref();
    let workgroups = fill.room().div_ceil(GROUP);
    // The lookup kernel first: its answered records' entries are what the ring search reads.
    if fill.kernel
        && let Some(lookup) = lookup.as_deref()
    {
        dispatch_lookups(
            (ctx.command_encoder(), diagnostics),
            (fill, &groups[0], workgroups),
            (lookup, &pipeline_cache),
            (&buffers, &images),
            &device,
        );
    }
    let mut pass = ctx
        .command_encoder()
        .begin_compute_pass(&ComputePassDescriptor {
            label: Some("plenoptic screen fill"),
            ..default()
        });
    let span = diagnostics.pass_span(&mut pass, "plenoptic/screen_fill");
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, &groups[0], &[]);
    pass.set_bind_group(1, &groups[1], &[]);
    pass.dispatch_workgroups(workgroups, 1, 1);
    span.end(&mut pass);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_fill_needs_the_gpu_and_a_prepass() {
        assert!(fill_possible(Backend::Gpu, true));
        assert!(!fill_possible(Backend::Cpu, true));
        assert!(!fill_possible(Backend::Gpu, false));
    }
}
