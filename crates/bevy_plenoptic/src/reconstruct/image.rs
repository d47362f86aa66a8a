//! GPU image mode ([`ReconMode::Image`]): `plenoptic_recon`'s image-based warping in compute
//! passes (`image.wgsl`, beside this file), dispatched before the cameras render.
//!
//! Per weighted base view (the view-space weights of the nearest
//! `ReconSettings::max_views` views, at most [`MAX_IMAGE_VIEWS`]), every texel of the
//! view's nearest resident key with a finite distance is splatted into the camera as
//! `plenoptic_recon::warp` does (square splats of the texel's footprint, at most
//! `ReconSettings::max_splat_px` pixels), through a per-view z-buffer: the nearest surface
//! (splats within `ReconSettings::same_surface` of the nearest depth) wins, and among its splats the one whose centre is nearest the pixel. The CPU resolves
//! splats in texel order ("clearly in front, or same surface and nearer centre"); the GPU's
//! three atomic passes (nearest depth, nearest centre within the surface, winning texel) are
//! order-independent, so the two can differ where surfaces meet. A texel's radiance is the
//! view's keys blended with `plenoptic_recon`'s Bézier weights when all those keys are
//! resident, otherwise with inverse time-distance weights over the resident ones (the CPU's
//! fallback for unreadable keys). The views are then blended per pixel over those within
//! the depth tolerance of the nearest, and holes are filled from the farthest covered
//! neighbour, `ReconSettings::background_passes` times. Every tunable comes from the
//! camera's `ReconSettings`, in [`ImageParams`].
//!
//! The frame is written to the camera's [`ImageFrame`], an `Rgba32Float` storage texture
//! which the camera's proxy materials and background show in screen space while it is in
//! image mode (volume mode: [`super::volume_mode`] supplies each view's cube at t as its
//! single key).
//!
//! Every camera has its own work: the main world fills the camera's [`ImageJob`], which is
//! extracted onto the camera's render-world view entity; the view's bind groups
//! ([`ImageBindGroups`]) are prepared per view, and the passes run for each view in turn
//! before the cameras render. The scratch buffers are shared (the views' passes run one
//! after the other), sized for the largest view.

use std::borrow::Cow;

use bevy::asset::{RenderAssetUsages, embedded_asset, load_embedded_asset};
use bevy::core_pipeline::schedule::camera_driver;
use bevy::prelude::*;
use bevy::render::extract_component::{ExtractComponent, ExtractComponentPlugin};
use bevy::render::render_asset::RenderAssets;
use bevy::render::render_resource::binding_types::{
    storage_buffer_sized, texture_2d_array, texture_storage_2d, uniform_buffer,
};
use bevy::render::render_resource::{
    BindGroup, BindGroupEntries, BindGroupLayoutDescriptor, BindGroupLayoutEntries, Buffer,
    BufferDescriptor, BufferUsages, CachedComputePipelineId, ComputePassDescriptor,
    ComputePipelineDescriptor, Extent3d, PipelineCache, ShaderStages, ShaderType,
    StorageTextureAccess, TextureDimension, TextureFormat, TextureSampleType, TextureUsages,
    UniformBuffer,
};
use bevy::render::renderer::{RenderContext, RenderDevice, RenderGraph, RenderQueue};
use bevy::render::texture::GpuImage;
use bevy::render::{Render, RenderApp, RenderStartup, RenderSystems};
use plenoptic_recon::temporal::bezier_weights;

use super::background::{PlenopticBackground, PlenopticBackgroundMaterial};
use super::volume_mode::VolumeCubes;
use super::{KeyTextures, ResolvedBackend};
use crate::Backend;
use crate::asset::RadiancePack;
use crate::camera::{PlenopticCamera, ReconMode};
use crate::streaming::StreamCache;

/// Most base views warped per frame.
pub const MAX_IMAGE_VIEWS: usize = 8;
/// Most keys blended per view (the Bézier segment's four).
pub const KEYS_PER_VIEW: usize = 4;

/// The uniform of the image-mode passes.
#[derive(ShaderType, Debug, Clone, Default)]
pub struct ImageParams {
    /// Eye (xyz), focal length in pixels (w).
    pub eye: Vec4,
    /// Camera right (xyz), tan of half the horizontal field of view (w).
    pub right: Vec4,
    /// Camera up (xyz), tan of half the vertical field of view (w).
    pub up: Vec4,
    /// Viewing direction (xyz), relative depth tolerance of the blend (w).
    pub forward: Vec4,
    /// Width, height, face size, view count.
    pub size: UVec4,
    /// x: background-fill passes.
    pub misc: UVec4,
    /// x: relative depth under which two splats are the same surface, y: largest splat edge
    /// in pixels.
    pub splat: Vec4,
    /// Per view: position (xyz), view weight (w).
    pub views: [Vec4; MAX_IMAGE_VIEWS],
    /// Per view: first array layer of each key blended.
    pub layers: [UVec4; MAX_IMAGE_VIEWS],
    /// Per view: each key's weight (0 for unused).
    pub key_weights: [Vec4; MAX_IMAGE_VIEWS],
    /// Per view: x: first layer of the nearest key (distances), y: key count.
    pub nearest: [UVec4; MAX_IMAGE_VIEWS],
}

/// The frame a camera's image-mode passes write (an `Rgba32Float` storage texture, resized
/// to the camera); every plenoptic camera has one.
#[derive(Component, Debug, Clone)]
pub struct ImageFrame(pub Handle<Image>);

/// A camera's image-mode work this frame: `Some` while it is in image (or volume) mode on
/// the GPU backend with keys to warp. Extracted onto the camera's render-world view.
#[derive(Component, Debug, Clone, Default, ExtractComponent)]
pub struct ImageJob(pub Option<ImageWork>);

/// What the image-mode passes read and write.
#[derive(Debug, Clone)]
pub struct ImageWork {
    /// The pack's key texture.
    pub cubes: Handle<Image>,
    /// The output frame.
    pub output: Handle<Image>,
    /// The passes' uniform.
    pub params: ImageParams,
}

fn frame_image(width: u32, height: u32) -> Image {
    let mut image = Image::new_fill(
        Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
        TextureDimension::D2,
        &[0; 16],
        TextureFormat::Rgba32Float,
        RenderAssetUsages::RENDER_WORLD,
    );
    image.texture_descriptor.usage =
        TextureUsages::COPY_DST | TextureUsages::STORAGE_BINDING | TextureUsages::TEXTURE_BINDING;
    image
}

pub(super) fn build(app: &mut App) {
    embedded_asset!(app, "image.wgsl");
    app.add_plugins(ExtractComponentPlugin::<ImageJob>::default());
    if let Some(render_app) = app.get_sub_app_mut(RenderApp) {
        render_app
            .init_resource::<ImageBuffers>()
            .add_systems(RenderStartup, init_pipelines)
            .add_systems(
                Render,
                prepare_bind_groups.in_set(RenderSystems::PrepareBindGroups),
            )
            .add_systems(RenderGraph, run_passes.before(camera_driver));
    }
}

/// Gives every plenoptic camera its [`ImageFrame`] and [`ImageJob`].
pub(super) fn add_frames(
    mut commands: Commands,
    cameras: Query<Entity, (With<PlenopticCamera>, Without<ImageFrame>)>,
    mut images: ResMut<Assets<Image>>,
) {
    for camera in &cameras {
        let frame = images.add(frame_image(1, 1));
        commands
            .entity(camera)
            .insert((ImageFrame(frame), ImageJob::default()));
    }
}

/// A camera in image or volume mode: the components [`prepare_jobs`] reads.
type WarpCamera<'a> = (
    Entity,
    &'a PlenopticCamera,
    &'a Camera,
    &'a Projection,
    &'a GlobalTransform,
    &'a ImageFrame,
    Option<&'a VolumeCubes>,
);

/// Fills each camera's [`ImageJob`] (warping its [`VolumeCubes`] in volume mode) and resizes
/// its [`ImageFrame`] to it.
#[expect(clippy::too_many_arguments, reason = "a Bevy system's parameters")]
pub(super) fn prepare_jobs(
    backend: Res<ResolvedBackend>,
    keys: Res<KeyTextures>,
    cache: Res<StreamCache>,
    packs: Res<Assets<RadiancePack>>,
    mut cameras: Query<(WarpCamera, &mut ImageJob)>,
    mut images: ResMut<Assets<Image>>,
    backgrounds: Query<(
        &PlenopticBackground,
        &MeshMaterial3d<PlenopticBackgroundMaterial>,
    )>,
    mut background_materials: ResMut<Assets<PlenopticBackgroundMaterial>>,
) {
    for (camera, mut job) in &mut cameras {
        let work = job_for(&backend, &keys, &cache, &packs, camera);
        let (entity, frame) = (camera.0, camera.5);
        if let Some(w) = &work {
            let size = UVec2::new(w.params.size.x, w.params.size.y);
            if images.get(&frame.0).is_some_and(|i| i.size() != size) {
                images.insert(&frame.0, frame_image(size.x, size.y)).ok();
                // Touch the camera's background so that its bind group takes the new texture
                // (the proxies and lit meshes see it in their camera's
                // `view::ViewBuffer::bindings`).
                for (bg, handle) in &backgrounds {
                    if bg.camera == entity
                        && let Some(m) = background_materials.get_mut(&handle.0)
                    {
                        // Marks it modified (a bare `get_mut` does not).
                        m.into_inner();
                    }
                }
            }
        }
        job.0 = work;
    }
}

/// The image-mode work of one camera, if it is in image or volume mode on the GPU backend.
fn job_for(
    backend: &ResolvedBackend,
    keys: &KeyTextures,
    cache: &StreamCache,
    packs: &Assets<RadiancePack>,
    (_, cam, camera, projection, transform, frame, volume): WarpCamera,
) -> Option<ImageWork> {
    if backend.0 != Backend::Gpu || !matches!(cam.mode, ReconMode::Image | ReconMode::Volume) {
        return None;
    }
    let id = cam.pack.id();
    let (pack, tex) = (packs.get(id)?, keys.0.get(&id)?);
    let volume_mode = cam.mode == ReconMode::Volume;
    let size = camera.physical_viewport_size()?;
    let vfov = match projection {
        Projection::Perspective(p) => p.fov,
        _ => std::f32::consts::FRAC_PI_4,
    };
    let (_, rotation, position) = transform.to_scale_rotation_translation();
    let basis = plenoptic_recon::Camera::new(position, rotation, vfov, size.x, size.y)
        .ok()?
        .basis();
    let mut params = ImageParams {
        eye: basis.position.extend(basis.focal_px),
        right: basis.right.extend(basis.tan_x),
        up: basis.up.extend(basis.tan_y),
        forward: basis.forward.extend(cam.settings.depth_tolerance),
        size: UVec4::new(size.x, size.y, tex.face, 0),
        misc: UVec4::new(cam.settings.background_passes, 0, 0, 0),
        splat: Vec4::new(
            cam.settings.same_surface,
            cam.settings.max_splat_px,
            0.0,
            0.0,
        ),
        ..default()
    };
    if volume_mode {
        // Each view's cube at t is its single key.
        let volume = volume?;
        let image = volume.image.clone()?;
        params.size.z = volume.face;
        for (n, &(v, w)) in volume.views.iter().enumerate() {
            let layer = 6 * n as u32;
            params.views[n] = pack.reader.manifest().base_views[v].position.extend(w);
            params.nearest[n] = UVec4::new(layer, 1, 0, 0);
            params.layers[n][0] = layer;
            params.key_weights[n][0] = 1.0;
        }
        params.size.w = volume.views.len() as u32;
        return Some(ImageWork {
            cubes: image,
            output: frame.0.clone(),
            params,
        });
    }
    let m = pack.reader.manifest();
    let t = cam.time;
    let views = cam.settings.view_weights(m, &pack.usable_views, position);
    let mut n = 0;
    for (v, w) in views {
        if n == MAX_IMAGE_VIEWS {
            break;
        }
        let times = &m.base_views[v].time_keys;
        let wanted = bezier_weights(times, t);
        let resident: Vec<(usize, f32, u32)> = wanted
            .iter()
            .filter_map(|&(k, wk)| {
                let r = cache.get(id, (v as u32, k as u32))?;
                (tex.uploaded.get(&r.slot) == Some(&(v as u32, k as u32)))
                    .then_some((k, wk, r.slot))
            })
            .take(KEYS_PER_VIEW)
            .collect();
        if resident.is_empty() {
            continue;
        }
        let weights: Vec<f32> = if resident.len() == wanted.len() {
            resident.iter().map(|r| r.1).collect()
        } else {
            resident
                .iter()
                .map(|r| 1.0 / ((times[r.0] - t).abs() + 1e-4))
                .collect()
        };
        let total: f32 = weights.iter().sum();
        let nearest = resident
            .iter()
            .min_by(|a, b| (times[a.0] - t).abs().total_cmp(&(times[b.0] - t).abs()))?;
        params.views[n] = m.base_views[v].position.extend(w);
        params.nearest[n] = UVec4::new(nearest.2 * 6, resident.len() as u32, 0, 0);
        for (k, (r, wk)) in resident.iter().zip(&weights).enumerate() {
            params.layers[n][k] = r.2 * 6;
            params.key_weights[n][k] = wk / total;
        }
        n += 1;
    }
    if n == 0 {
        return None;
    }
    params.size.w = n as u32;
    Some(ImageWork {
        cubes: tex.image.clone(),
        output: frame.0.clone(),
        params,
    })
}

#[derive(Resource)]
struct ImagePipelines {
    layout: BindGroupLayoutDescriptor,
    /// clear, splat_depth, splat_centre, splat_texel, blend, fill, write_output.
    passes: [CachedComputePipelineId; 7],
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

fn init_pipelines(
    mut commands: Commands,
    asset_server: Res<AssetServer>,
    pipeline_cache: Res<PipelineCache>,
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
    commands.insert_resource(ImagePipelines { layout, passes });
}

/// Scratch buffers, grown as needed: splat keys, splat texels, two frame buffers.
#[derive(Resource, Default)]
struct ImageBuffers {
    buffers: Option<[Buffer; 4]>,
    /// Pixels of the largest frame they hold (splats: [`MAX_IMAGE_VIEWS`] per pixel).
    capacity: u64,
}

/// A view's image-mode bind groups this frame (on its render-world view entity).
#[derive(Component)]
pub struct ImageBindGroups {
    /// Frame buffers (a, b) and (b, a) as (in, out).
    groups: [BindGroup; 2],
    params: ImageParams,
}

#[expect(clippy::too_many_arguments, reason = "a Bevy system's parameters")]
fn prepare_bind_groups(
    mut commands: Commands,
    views: Query<(Entity, &ImageJob)>,
    pipelines: Option<Res<ImagePipelines>>,
    images: Res<RenderAssets<GpuImage>>,
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

fn run_passes(
    mut render_context: RenderContext,
    views: Query<&ImageBindGroups>,
    pipelines: Option<Res<ImagePipelines>>,
    pipeline_cache: Res<PipelineCache>,
) {
    let Some(pipelines) = pipelines else {
        return;
    };
    let Some(passes) = pipelines
        .passes
        .iter()
        .map(|&id| pipeline_cache.get_compute_pipeline(id))
        .collect::<Option<Vec<_>>>()
    else {
        return;
    };
    for groups in &views {
        let p = &groups.params;
        let (w, h, face, views) = (p.size.x, p.size.y, p.size.z, p.size.w);
        let texels = 6 * face * face;
        let mut pass =
            render_context
                .command_encoder()
                .begin_compute_pass(&ComputePassDescriptor {
                    label: Some("plenoptic image mode"),
                    ..default()
                });
        pass.set_bind_group(0, &groups.groups[0], &[]);
        pass.set_pipeline(passes[0]);
        pass.dispatch_workgroups((w * h).div_ceil(64), views, 1);
        for splat in &passes[1..4] {
            pass.set_pipeline(splat);
            pass.dispatch_workgroups(texels.div_ceil(64), views, 1);
        }
        pass.set_pipeline(passes[4]);
        pass.dispatch_workgroups(w.div_ceil(8), h.div_ceil(8), 1);
        pass.set_pipeline(passes[5]);
        for k in 0..p.misc.x {
            pass.set_bind_group(0, &groups.groups[k as usize % 2], &[]);
            pass.dispatch_workgroups(w.div_ceil(8), h.div_ceil(8), 1);
        }
        pass.set_bind_group(0, &groups.groups[p.misc.x as usize % 2], &[]);
        pass.set_pipeline(passes[6]);
        pass.dispatch_workgroups(w.div_ceil(8), h.div_ceil(8), 1);
    }
}
