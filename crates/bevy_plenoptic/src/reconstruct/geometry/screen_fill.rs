//! The screen-space hole fill (thesis §8.2.3; `plenoptic_recon`'s `geometry::fill` ring
//! search) as a compute pass over the opaque pass's output.
//!
//! A proxy fragment can not read its neighbours' results, so the fragment hole fill
//! (`fill.wgsl`) reconstructs every ring pixel again: on the tour that is ~98 % of the
//! reconstruction's loads (`docs/results/measurements.md`). On a camera with the screen fill
//! ([`ScreenFill`]) every fragment drawn in the opaque pass instead leaves its pixel an entry
//! in the camera's entry buffer (`fill_entry.wgsl`): its lighting and non-diffuse terms where
//! its lookups answered, or its hole with its albedo and what it adds on top. After Bevy's
//! opaque pass a compute kernel (`screen_fill.wgsl`, one thread per pixel) fills each hole
//! from the nearest ring of pixels holding its own object, shades their mean terms with the
//! hole's albedo as the CPU does, and writes the pixel of the view's HDR target. A ring
//! pixel costs one 16-byte load. The entries are cleared before the opaque pass; the fill
//! runs before the transparent pass, so glazing blends over filled pixels. Glazing and glass
//! (drawn in the transparent pass) keep the fragment fill.
//!
//! The kernel writes the view target as a storage texture, as bevy_solari's realtime passes
//! do, so the fill needs an HDR camera (`Hdr`, an `Rgba16Float` target) without MSAA
//! (`Msaa::Off`), with its [`DepthPrepass`] (a fragment writes its entry only where the
//! prepass kept it). Other cameras use the fragment fill; both give the CPU's result.
//! [`ScreenFill::size`] is zero on them.

use std::borrow::Cow;

use bevy::asset::{RenderAssetUsages, load_embedded_asset};
use bevy::camera::{CameraMainTextureUsages, Hdr};
use bevy::core_pipeline::core_3d::{main_opaque_pass_3d, main_transparent_pass_3d};
use bevy::core_pipeline::prepass::DepthPrepass;
use bevy::core_pipeline::schedule::{Core3d, Core3dSystems};
use bevy::render::diagnostic::RecordDiagnostics;
use bevy::prelude::*;
use bevy::render::camera::ExtractedCamera;
use bevy::render::extract_component::{ExtractComponent, ExtractComponentPlugin};
use bevy::render::render_asset::RenderAssets;
use bevy::render::render_resource::binding_types::{
    storage_buffer_read_only_sized, storage_buffer_sized, texture_storage_2d, uniform_buffer,
};
use bevy::render::render_resource::{
    BindGroupEntries, BindGroupLayoutDescriptor, BindGroupLayoutEntries,
    CachedComputePipelineId, ComputePassDescriptor, ComputePipelineDescriptor, PipelineCache,
    ShaderStages, ShaderType, StorageTextureAccess, TextureFormat, TextureUsages, UniformBuffer,
};
use bevy::render::renderer::{RenderContext, RenderDevice, RenderQueue, ViewQuery};
use bevy::render::storage::{GpuShaderBuffer, ShaderBuffer};
use bevy::render::view::ViewTarget;
use bevy::render::{RenderApp, RenderStartup};

use crate::camera::PlenopticCamera;
use crate::reconstruct::counters::{CounterBuffer, TILE};
use crate::settings::{Backend, PlenopticSettings, ResolvedBackend};

/// Bytes of one pixel's entry (`fill_entry.wgsl`).
const ENTRY_BYTES: u64 = 16;
/// The kernel's workgroup: one counter tile, 8 × 4 pixels.
const GROUP: UVec2 = TILE;

/// A camera's screen-space hole fill (see the module doc): its entry buffer, which its
/// materials bind, and what the kernel needs. Extracted onto the camera's render-world view.
#[derive(Component, Debug, Clone, ExtractComponent)]
pub struct ScreenFill {
    /// One entry per pixel of the viewport (16 bytes, a placeholder while off).
    pub entries: Handle<ShaderBuffer>,
    /// The viewport's size in pixels; zero while the camera uses the fragment fill.
    pub size: UVec2,
    /// The ring search's largest radius (`ReconSettings::hole_fill_radius`).
    pub radius: u32,
    /// The camera's counter buffer, and its tiles across while counting (else 0).
    pub counters: Handle<ShaderBuffer>,
    /// Tiles across of the counter buffer while counting, else 0.
    pub tiles_x: u32,
}

impl ScreenFill {
    /// Whether the camera's opaque holes are filled by the kernel.
    pub fn on(&self) -> bool {
        self.size != UVec2::ZERO
    }
}

/// The kernel's uniform (`screen_fill.wgsl`'s `FillParams`).
#[derive(ShaderType, Clone, Debug)]
struct FillParams {
    size: UVec2,
    offset: UVec2,
    radius: u32,
    tiles_x: u32,
}

/// Adds the fill: the main-world entries, their extraction and the render-world passes.
pub(super) fn build(app: &mut App) {
    bevy::shader::load_shader_library!(app, "fill_entry.wgsl");
    bevy::asset::embedded_asset!(app, "screen_fill.wgsl");
    app.add_plugins(ExtractComponentPlugin::<ScreenFill>::default());
    let Some(render_app) = app.get_sub_app_mut(RenderApp) else {
        return;
    };
    render_app
        .add_systems(RenderStartup, init_pipelines)
        .add_systems(
            Core3d,
            (
                clear_entries
                    .in_set(Core3dSystems::MainPass)
                    .before(main_opaque_pass_3d),
                fill_holes
                    .in_set(Core3dSystems::MainPass)
                    .after(main_opaque_pass_3d)
                    .before(main_transparent_pass_3d),
            ),
        );
}

/// Whether a camera can take the screen fill: the GPU backend, an HDR target without MSAA,
/// a depth prepass.
fn fill_possible(backend: Backend, hdr: bool, msaa: Option<&Msaa>, prepass: bool) -> bool {
    backend == Backend::Gpu && hdr && msaa == Some(&Msaa::Off) && prepass
}

/// Gives every plenoptic camera its [`ScreenFill`], sized to its viewport where the app wants
/// the fill ([`PlenopticSettings::screen_fill`]) and the camera can take it (a new entry buffer when the size changes), and lets its main texture be written
/// by the kernel.
#[expect(clippy::type_complexity, reason = "a Bevy system's query")]
pub(super) fn prepare_screen_fill(
    mut commands: Commands,
    backend: Res<ResolvedBackend>,
    settings: Res<PlenopticSettings>,
    mut cameras: Query<
        (
            Entity,
            &Camera,
            &PlenopticCamera,
            &CounterBuffer,
            (Has<Hdr>, Option<&Msaa>, Has<DepthPrepass>),
            Option<&mut CameraMainTextureUsages>,
            Option<&mut ScreenFill>,
        ),
    >,
    mut buffers: ResMut<Assets<ShaderBuffer>>,
) {
    for (entity, camera, cam, counters, (hdr, msaa, prepass), usages, fill) in &mut cameras {
        let size = match camera.physical_viewport_size() {
            Some(s) if settings.screen_fill && fill_possible(backend.0, hdr, msaa, prepass) => s,
            _ => UVec2::ZERO,
        };
        let tiles_x = if settings.cost_counters {
            counters.tiles.x
        } else {
            0
        };
        let entries = |buffers: &mut Assets<ShaderBuffer>| {
            let bytes = (u64::from(size.x) * u64::from(size.y) * ENTRY_BYTES).max(ENTRY_BYTES);
            buffers.add(ShaderBuffer::with_size(
                bytes as usize,
                RenderAssetUsages::RENDER_WORLD,
            ))
        };
        let wanted = |entries: Handle<ShaderBuffer>| ScreenFill {
            entries,
            size,
            radius: cam.settings.hole_fill_radius,
            counters: counters.buffer.clone(),
            tiles_x,
        };
        match fill {
            None => {
                commands.entity(entity).insert(wanted(entries(&mut buffers)));
            }
            Some(mut f) => {
                let handle = if f.size == size {
                    f.entries.clone()
                } else {
                    entries(&mut buffers)
                };
                let w = wanted(handle);
                if f.entries != w.entries
                    || f.size != w.size
                    || f.radius != w.radius
                    || f.counters != w.counters
                    || f.tiles_x != w.tiles_x
                {
                    *f = w;
                }
            }
        }
        if size != UVec2::ZERO {
            match usages {
                Some(mut u) if !u.0.contains(TextureUsages::STORAGE_BINDING) => {
                    u.0 |= TextureUsages::STORAGE_BINDING;
                }
                Some(_) => {}
                None => {
                    commands.entity(entity).insert(
                        CameraMainTextureUsages::default().with(TextureUsages::STORAGE_BINDING),
                    );
                }
            }
        }
    }
}

/// The kernel's pipelines (without and with the cost counters) and their layout.
#[derive(Resource)]
struct FillPipelines {
    layout: BindGroupLayoutDescriptor,
    plain: CachedComputePipelineId,
    counting: CachedComputePipelineId,
}

/// Queues the kernel's two pipelines.
fn init_pipelines(
    mut commands: Commands,
    asset_server: Res<AssetServer>,
    pipeline_cache: Res<PipelineCache>,
) {
    let layout = BindGroupLayoutDescriptor::new(
        "plenoptic screen fill",
        &BindGroupLayoutEntries::sequential(
            ShaderStages::COMPUTE,
            (
                storage_buffer_read_only_sized(false, None),
                texture_storage_2d(TextureFormat::Rgba16Float, StorageTextureAccess::WriteOnly),
                uniform_buffer::<FillParams>(false),
                storage_buffer_sized(false, None),
            ),
        ),
    );
    let shader = load_embedded_asset!(asset_server.as_ref(), "screen_fill.wgsl");
    let pipeline = |label: &'static str, defs: Vec<bevy::shader::ShaderDefVal>| {
        pipeline_cache.queue_compute_pipeline(ComputePipelineDescriptor {
            label: Some(label.into()),
            layout: vec![layout.clone()],
            shader: shader.clone(),
            shader_defs: defs,
            entry_point: Some(Cow::from("fill_holes")),
            ..default()
        })
    };
    let plain = pipeline("plenoptic screen fill", Vec::new());
    let counting = pipeline(
        "plenoptic screen fill (counting)",
        vec!["PLENOPTIC_COUNTERS".into()],
    );
    commands.insert_resource(FillPipelines {
        layout,
        plain,
        counting,
    });
}

/// Clears a view's entries before its opaque pass: a pixel no proxy covers holds nothing.
fn clear_entries(
    view: ViewQuery<&ScreenFill>,
    buffers: Res<RenderAssets<GpuShaderBuffer>>,
    mut ctx: RenderContext,
) {
    let fill = view.into_inner();
    if !fill.on() {
        return;
    }
    if let Some(b) = buffers.get(&fill.entries) {
        ctx.command_encoder().clear_buffer(&b.buffer, 0, None);
    }
}

/// Runs the kernel over a view's entries after its opaque pass, one thread per pixel.
#[expect(clippy::too_many_arguments, reason = "a Bevy system's parameters")]
fn fill_holes(
    view: ViewQuery<(&ScreenFill, &ViewTarget, &ExtractedCamera)>,
    pipelines: Option<Res<FillPipelines>>,
    pipeline_cache: Res<PipelineCache>,
    buffers: Res<RenderAssets<GpuShaderBuffer>>,
    device: Res<RenderDevice>,
    queue: Res<RenderQueue>,
    mut ctx: RenderContext,
) {
    let (fill, target, camera) = view.into_inner();
    let Some(pipelines) = pipelines else {
        return;
    };
    let id = if fill.tiles_x > 0 {
        pipelines.counting
    } else {
        pipelines.plain
    };
    // The entries of this size, a single-sampled HDR target, the pipeline compiled.
    let (Some(entries), Some(counters), Some(pipeline)) = (
        buffers.get(&fill.entries),
        buffers.get(&fill.counters),
        pipeline_cache.get_compute_pipeline(id),
    ) else {
        return;
    };
    let pixels = u64::from(fill.size.x) * u64::from(fill.size.y);
    if !fill.on()
        || entries.buffer.size() < pixels * ENTRY_BYTES
        || target.main_texture_format() != TextureFormat::Rgba16Float
        || target.sampled_main_texture().is_some()
    {
        return;
    }
    let offset = camera
        .viewport
        .as_ref()
        .map_or(UVec2::ZERO, |v| v.physical_position);
    let mut uniform = UniformBuffer::from(FillParams {
        size: fill.size,
        offset,
        radius: fill.radius,
        tiles_x: fill.tiles_x,
    });
    uniform.write_buffer(&device, &queue);
    let Some(params) = uniform.binding() else {
        return;
    };
    let group = device.create_bind_group(
        "plenoptic screen fill",
        &pipeline_cache.get_bind_group_layout(&pipelines.layout),
        &BindGroupEntries::sequential((
            entries.buffer.as_entire_binding(),
            target.main_texture_view(),
            params,
            counters.buffer.as_entire_binding(),
        )),
    );
    let diagnostics = ctx.diagnostic_recorder();
    let diagnostics = diagnostics.as_deref();
    let mut pass = ctx
        .command_encoder()
        .begin_compute_pass(&ComputePassDescriptor {
            label: Some("plenoptic screen fill"),
            ..default()
        });
    let span = diagnostics.pass_span(&mut pass, "plenoptic/screen_fill");
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, &group, &[]);
    pass.dispatch_workgroups(fill.size.x.div_ceil(GROUP.x), fill.size.y.div_ceil(GROUP.y), 1);
    span.end(&mut pass);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_fill_needs_the_gpu_an_hdr_target_without_msaa_and_a_prepass() {
        let off = Some(&Msaa::Off);
        assert!(fill_possible(Backend::Gpu, true, off, true));
        assert!(!fill_possible(Backend::Cpu, true, off, true));
        assert!(!fill_possible(Backend::Gpu, false, off, true));
        assert!(!fill_possible(Backend::Gpu, true, Some(&Msaa::Sample4), true));
        assert!(!fill_possible(Backend::Gpu, true, None, true));
        assert!(!fill_possible(Backend::Gpu, true, off, false));
    }
}
