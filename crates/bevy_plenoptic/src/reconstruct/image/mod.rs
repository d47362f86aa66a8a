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
//! image mode (volume mode: [`volume`] supplies each view's cube at t as its
//! single key).
//!
//! Every camera has its own work: the main world fills the camera's [`ImageJob`], which is
//! extracted onto the camera's render-world view entity; the view's bind groups
//! ([`prepare::ImageBindGroups`]) are prepared per view, and the passes run for each view in turn
//! before the cameras render. The scratch buffers are shared (the views' passes run one
//! after the other), sized for the largest view.
//!
//! - `mod.rs`: the plugin, the frame and the job; [`extract`]: each camera's job, filled in
//!   the main world and extracted onto its render-world view; [`prepare`]: the pipelines, the
//!   shared scratch buffers and each view's bind groups; [`node`]: the compute passes, run
//!   for each view before the cameras render; `image.wgsl`: the passes.

pub mod extract;
pub mod node;
pub mod prepare;
pub mod volume;

use bevy::asset::{RenderAssetUsages, embedded_asset};
use bevy::core_pipeline::schedule::camera_driver;
use bevy::prelude::*;
use bevy::render::extract_component::{ExtractComponent, ExtractComponentPlugin};
use bevy::render::render_resource::{
    Extent3d, ShaderType, TextureDimension, TextureFormat, TextureUsages,
};
use bevy::render::renderer::RenderGraph;
use bevy::render::{Render, RenderApp, RenderStartup, RenderSystems};

use plenoptic_pack::MAX_LIGHT_GROUPS;

use super::ReconstructSystems;
use super::frames::ImageFrame;
use crate::camera::PlenopticCamera;
#[cfg(doc)]
use crate::camera::ReconMode;
use crate::reconstruct::relight::LightLayerParams;
#[cfg(doc)]
use extract::prepare_jobs;

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
    /// Light groups ([`crate::reconstruct::relight`]): stored groups (x), layers blended (y),
    /// 1 where the keys' radiance is relit per texel (z: image mode at weights not as baked).
    pub light: UVec4,
    /// The blend's weight of the total (xyz).
    pub light_base: Vec4,
    /// The sky's multiplier (xyz).
    pub light_sky: Vec4,
    /// The layers blended.
    pub light_layers: [LightLayerParams; MAX_LIGHT_GROUPS],
}

/// A camera's image-mode work this frame: `Some` while it is in image (or volume) mode on
/// the GPU backend with keys to warp. Extracted onto the camera's render-world view.
#[derive(Component, Debug, Clone, Default, ExtractComponent)]
pub struct ImageJob(pub Option<ImageWork>);

/// What the image-mode passes read and write.
#[derive(Debug, Clone)]
pub struct ImageWork {
    /// The pack's key texture.
    pub cubes: Handle<Image>,
    /// The pack's shading texture (the keys' stored light, which relit radiance is scaled
    /// by).
    pub shading: Handle<Image>,
    /// The pack, whose group layers relight the keys ([`crate::reconstruct::relight`]).
    pub pack: AssetId<crate::asset::RadiancePack>,
    /// The output frame.
    pub output: Handle<Image>,
    /// The passes' uniform.
    pub params: ImageParams,
}

/// A frame texture of `width` × `height`.
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

/// Image mode on the GPU: `plenoptic_recon`'s warping in compute passes, per view (part of
/// [`super::PlenopticReconstructPlugin`]; volume mode warps its cubes with the same passes).
#[derive(Debug, Default)]
pub struct WarpPlugin;

impl Plugin for WarpPlugin {
    fn build(&self, app: &mut App) {
        embedded_asset!(app, "image.wgsl");
        app.add_plugins((
            ExtractComponentPlugin::<ImageJob>::default(),
            volume::VolumeModePlugin,
        ))
        .add_systems(
            Update,
            (
                add_frames.in_set(ReconstructSystems::Resources),
                extract::prepare_jobs.in_set(ReconstructSystems::Jobs),
            ),
        );
        if let Some(render_app) = app.get_sub_app_mut(RenderApp) {
            render_app
                .init_resource::<prepare::ImageBuffers>()
                .add_systems(RenderStartup, prepare::init_pipelines)
                .add_systems(
                    Render,
                    prepare::prepare_bind_groups.in_set(RenderSystems::PrepareBindGroups),
                )
                .add_systems(RenderGraph, node::run_passes.before(camera_driver));
        }
    }
}

/// Gives every plenoptic camera its [`ImageFrame`] and [`ImageJob`].
fn add_frames(
    mut commands: Commands,
    cameras: Query<Entity, (With<PlenopticCamera>, Without<ImageFrame>)>,
    mut images: ResMut<Assets<Image>>,
) {
    for camera in &cameras {
        let frame = images.add(frame_image(1, 1));
        commands.entity(camera).insert((
            ImageFrame {
                image: frame,
                active: false,
            },
            ImageJob::default(),
        ));
    }
}
