//! The environment behind the proxy geometry: pixels no proxy covers (sky through a window or
//! a skylight, anything beyond the view space's geometry) show the pack's environment for the
//! pixel's own viewing direction at the camera's time, as `plenoptic_recon::background` does:
//! a uniform colour, the Hosek–Wilkie sky (its coefficients computed here on the CPU per view
//! from the pack's sun track at the camera's time, [`EnvironmentUniform`], the formula
//! evaluated per pixel in `background.wgsl`), or the equirectangular image (a texture, read
//! bilinearly as on the CPU). Packs without an environment show the heaviest key's radiance
//! cube in the pixel's direction, as before. Output is multiplied by the camera's exposure.
//!
//! Each GPU camera gets a child entity with a one-triangle mesh drawn by
//! [`PlenopticBackgroundMaterial`], whose vertex shader (`background.wgsl`) takes its
//! positions as clip-space corners of a full-screen triangle at depth 0, the far end of Bevy's
//! reverse-Z depth (no culling, not frustum-culled): it
//! passes the depth test only where nothing was drawn, so proxies and ordinary meshes stay
//! in front of it. It takes no part in the prepass or shadows, and is drawn on the camera's
//! own render layer ([`crate::camera::layers`]), so no other camera sees it.

use bevy::asset::{RenderAssetUsages, embedded_asset};
use bevy::camera::visibility::NoFrustumCulling;
use bevy::mesh::MeshVertexBufferLayoutRef;
use bevy::mesh::{Indices, PrimitiveTopology};
use bevy::pbr::{MaterialPipeline, MaterialPipelineKey};
use bevy::prelude::*;
use bevy::render::render_resource::{
    AsBindGroup, RenderPipelineDescriptor, ShaderType, SpecializedMeshPipelineError,
};
use bevy::shader::ShaderRef;

use bevy::render::render_resource::{
    Extent3d, TextureDimension, TextureFormat, TextureViewDescriptor, TextureViewDimension,
};
use plenoptic_recon::background::PlacedEnvironment;

use super::environment::{EnvironmentImages, EnvironmentUniform};
use super::frames::{CpuFrameImage, FrameReplaced, ImageFrame, ViewDisplay};
use super::relight::RelitKeys;
use super::{KeyTextures, ReconstructSystems};
use crate::asset::RadiancePack;
use crate::camera::PlenopticCamera;
use crate::camera::layers::ViewLayer;
use crate::settings::Backend;
use crate::settings::ResolvedBackend;

/// The background behind the proxies: its material, and one background per camera kept at
/// the camera's time (the GPU backend) or showing its CPU frame (the CPU backend).
#[derive(Debug, Default)]
pub struct BackgroundPlugin;

impl Plugin for BackgroundPlugin {
    fn build(&self, app: &mut App) {
        embedded_asset!(app, "background.wgsl");
        app.add_plugins(MaterialPlugin::<PlenopticBackgroundMaterial>::default())
            .add_systems(
                Update,
                (
                    spawn_backgrounds.in_set(ReconstructSystems::Attach),
                    spawn_cpu_backgrounds.in_set(ReconstructSystems::Views),
                    (update_backgrounds, rebind_frames).in_set(ReconstructSystems::Materials),
                ),
            );
    }
}

/// Draws the environment where no geometry is (see the module doc).
#[derive(Asset, TypePath, AsBindGroup, Debug, Clone)]
pub struct PlenopticBackgroundMaterial {
    /// The pack's key texture.
    #[texture(0, dimension = "2d_array", sample_type = "u_int")]
    pub cubes: Handle<Image>,
    /// Which key to show.
    #[uniform(1)]
    pub params: BackgroundParams,
    /// The camera's displayed frame: its [`ImageFrame`] (shown while the camera is in image
    /// or volume mode) or its [`CpuFrameImage`].
    #[texture(2, sample_type = "float", filterable = false)]
    pub image_frame: Handle<Image>,
    /// The pack's environment at the camera's time.
    #[uniform(3)]
    pub environment: EnvironmentUniform,
    /// The pack's environment image (`Rgba32Float`; 1 × 1 black when it has none).
    #[texture(4, sample_type = "float", filterable = false)]
    pub environment_image: Handle<Image>,
}

/// The uniform of a [`PlenopticBackgroundMaterial`].
#[derive(ShaderType, Debug, Clone, Default)]
pub struct BackgroundParams {
    /// x: first array layer of the key shown, y: face size, z: 1 if a key is shown (else
    /// black), w: 1 to show the image-mode frame instead.
    pub key: Vec4,
}

impl Material for PlenopticBackgroundMaterial {
    fn vertex_shader() -> ShaderRef {
        "embedded://bevy_plenoptic/reconstruct/background/background.wgsl".into()
    }

    fn fragment_shader() -> ShaderRef {
        "embedded://bevy_plenoptic/reconstruct/background/background.wgsl".into()
    }

    fn enable_prepass() -> bool {
        false
    }

    fn enable_shadows() -> bool {
        false
    }

    fn specialize(
        _pipeline: &MaterialPipeline,
        descriptor: &mut RenderPipelineDescriptor,
        _layout: &MeshVertexBufferLayoutRef,
        _key: MaterialPipelineKey<Self>,
    ) -> Result<(), SpecializedMeshPipelineError> {
        descriptor.primitive.cull_mode = None;
        Ok(())
    }
}

/// The background entity of a camera.
#[derive(Component, Debug, Clone, Copy)]
pub struct PlenopticBackground {
    /// The camera it is drawn for.
    pub camera: Entity,
    /// Drawn for the CPU backend: it shows the CPU frame (whose pixels without geometry
    /// `plenoptic_recon` filled with the environment) and is not updated by the GPU path.
    pub cpu: bool,
}

/// A full-screen triangle at depth 0 drawn with `material` for `camera`, as its child.
fn spawn_background(
    commands: &mut Commands,
    meshes: &mut Assets<Mesh>,
    (camera, layer): (Entity, ViewLayer),
    cpu: bool,
    material: Handle<PlenopticBackgroundMaterial>,
) {
    // A triangle covering the screen, its positions in clip space (used as such by the
    // vertex shader).
    let mesh = Mesh::new(
        PrimitiveTopology::TriangleList,
        RenderAssetUsages::RENDER_WORLD,
    )
    .with_inserted_attribute(
        Mesh::ATTRIBUTE_POSITION,
        vec![[-1.0f32, -1.0, 0.0], [3.0, -1.0, 0.0], [-1.0, 3.0, 0.0]],
    )
    .with_inserted_attribute(Mesh::ATTRIBUTE_NORMAL, vec![[0.0f32, 0.0, 1.0]; 3])
    .with_inserted_indices(Indices::U32(vec![0, 1, 2]));
    let child = commands
        .spawn((
            Name::new("plenoptic background"),
            PlenopticBackground { camera, cpu },
            Mesh3d(meshes.add(mesh)),
            MeshMaterial3d(material),
            NoFrustumCulling,
            Transform::IDENTITY,
            layer.layers(),
        ))
        .id();
    commands.entity(camera).add_child(child);
}

/// Spawns a background child for each camera on the CPU backend whose pack has an
/// environment: it shows the CPU frame (`frame`: the pack's displayed CPU frame, if any)
/// where no proxy is, so that the sky `plenoptic_recon` put there is seen.
#[expect(clippy::too_many_arguments, reason = "a Bevy system's parameters")]
fn spawn_cpu_backgrounds(
    mut commands: Commands,
    backend: Res<ResolvedBackend>,
    cameras: Query<(Entity, &PlenopticCamera, &ViewLayer, &CpuFrameImage)>,
    existing: Query<&PlenopticBackground>,
    packs: Res<Assets<RadiancePack>>,
    mut images: ResMut<Assets<Image>>,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<PlenopticBackgroundMaterial>>,
) {
    if backend.0 != Backend::Cpu {
        return;
    }
    for (entity, cam, layer, frame) in &cameras {
        if existing.iter().any(|b| b.camera == entity) {
            continue;
        }
        let Some(pack) = packs.get(cam.pack.id()) else {
            continue;
        };
        if pack.environment.is_none() {
            continue;
        }
        // The shader's key texture binding needs a 2D array; the CPU path has no keys.
        let mut cubes = Image::new_fill(
            Extent3d {
                width: 1,
                height: 1,
                depth_or_array_layers: 6,
            },
            TextureDimension::D2,
            &[0; 16],
            TextureFormat::Rgba32Uint,
            RenderAssetUsages::RENDER_WORLD,
        );
        cubes.texture_view_descriptor = Some(TextureViewDescriptor {
            dimension: Some(TextureViewDimension::D2Array),
            ..default()
        });
        let black = Image::new_fill(
            Extent3d::default(),
            TextureDimension::D2,
            &[0; 16],
            TextureFormat::Rgba32Float,
            RenderAssetUsages::RENDER_WORLD,
        );
        let material = materials.add(PlenopticBackgroundMaterial {
            cubes: images.add(cubes),
            params: BackgroundParams {
                key: Vec4::new(0.0, 1.0, 0.0, 1.0),
            },
            image_frame: frame.0.clone(),
            environment: EnvironmentUniform::default(),
            environment_image: images.add(black),
        });
        spawn_background(&mut commands, &mut meshes, (entity, *layer), true, material);
    }
}

/// Spawns a background child for each camera on the GPU backend whose pack's key texture
/// exists.
#[expect(clippy::too_many_arguments, reason = "a Bevy system's parameters")]
pub(super) fn spawn_backgrounds(
    mut commands: Commands,
    backend: Res<ResolvedBackend>,
    keys: Res<KeyTextures>,
    cameras: Query<(Entity, &PlenopticCamera, &ViewLayer, &ImageFrame)>,
    existing: Query<&PlenopticBackground>,
    packs: Res<Assets<RadiancePack>>,
    mut env_images: ResMut<EnvironmentImages>,
    mut images: ResMut<Assets<Image>>,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<PlenopticBackgroundMaterial>>,
) {
    if backend.0 != Backend::Gpu {
        return;
    }
    for (entity, cam, layer, image_frame) in &cameras {
        if existing.iter().any(|b| b.camera == entity) {
            continue;
        }
        let (Some(tex), Some(pack)) = (keys.0.get(&cam.pack.id()), packs.get(cam.pack.id())) else {
            continue;
        };
        let environment_image = env_images.get(cam.pack.id(), pack, &mut images);
        let material = materials.add(PlenopticBackgroundMaterial {
            cubes: tex.image.clone(),
            params: BackgroundParams::default(),
            image_frame: image_frame.image.clone(),
            environment: EnvironmentUniform::default(),
            environment_image,
        });
        spawn_background(
            &mut commands,
            &mut meshes,
            (entity, *layer),
            false,
            material,
        );
    }
}

/// Shows the pack's environment `env` (placed at the camera's time) or, without one, the
/// heaviest key (`layer`: its first array layer) of the camera's pack, or black; or, with
/// `image_mode`, the image-mode frame.
pub(super) fn set_background(
    materials: &mut Assets<PlenopticBackgroundMaterial>,
    handle: &MeshMaterial3d<PlenopticBackgroundMaterial>,
    env: &PlacedEnvironment,
    layer: Option<u32>,
    face: u32,
    image_mode: bool,
) {
    let environment = EnvironmentUniform::new(env);
    if materials
        .get(&handle.0)
        .is_some_and(|m| m.environment != environment)
        && let Some(mut m) = materials.get_mut(&handle.0)
    {
        m.environment = environment;
    }
    let mut key = match layer {
        Some(l) => Vec4::new(l as f32, face as f32, 1.0, 0.0),
        None => Vec4::ZERO,
    };
    if image_mode {
        key.w = 1.0;
    }
    if materials
        .get(&handle.0)
        .is_some_and(|m| m.params.key != key)
        && let Some(mut m) = materials.get_mut(&handle.0)
    {
        m.params.key = key;
    }
}

/// Keeps every background's environment and key (the heaviest lookup's cube) at its camera's
/// time.
pub(super) fn update_backgrounds(
    keys: Res<KeyTextures>,
    packs: Res<Assets<RadiancePack>>,
    cameras: Query<(&PlenopticCamera, &ViewDisplay, Option<&RelitKeys>)>,
    backgrounds: Query<(
        &PlenopticBackground,
        &MeshMaterial3d<PlenopticBackgroundMaterial>,
    )>,
    mut background_materials: ResMut<Assets<PlenopticBackgroundMaterial>>,
) {
    for (bg, handle) in &backgrounds {
        let Ok((cam, display, relit)) = cameras.get(bg.camera) else {
            continue;
        };
        if bg.cpu {
            continue;
        }
        let id = cam.pack.id();
        let tex = keys.0.get(&id);
        let face = tex.map_or(1, |t| t.face);
        // The heaviest key is in the camera's relit keys when it has them.
        let cubes = relit.map(|r| &r.image).or(tex.map(|t| &t.image));
        if let Some(cubes) = cubes
            && background_materials
                .get(&handle.0)
                .is_some_and(|m| m.cubes != *cubes)
            && let Some(mut m) = background_materials.get_mut(&handle.0)
        {
            m.cubes = cubes.clone();
        }
        let layer = display.heaviest_layer;
        let sky = |p: &RadiancePack| cam.lights.relight(p.reader.manifest()).sky;
        let env = packs
            .get(id)
            .map(|p| p.environment.at(cam.time).scaled(sky(p)))
            .unwrap_or_default();
        set_background(
            &mut background_materials,
            handle,
            &env,
            layer,
            face,
            display.image_mode,
        );
    }
}

/// Marks the backgrounds that show a replaced frame texture modified, so that Bevy prepares
/// their bind groups again with the new texture.
fn rebind_frames(
    mut replaced: MessageReader<FrameReplaced>,
    mut materials: ResMut<Assets<PlenopticBackgroundMaterial>>,
) {
    for FrameReplaced(image) in replaced.read() {
        let users: Vec<_> = materials
            .iter()
            .filter(|(_, m)| m.image_frame.id() == *image)
            .map(|(id, _)| id)
            .collect();
        for id in users {
            // A bare `get_mut` marks the asset modified only once dereferenced mutably.
            if let Some(m) = materials.get_mut(id) {
                m.into_inner();
            }
        }
    }
}
