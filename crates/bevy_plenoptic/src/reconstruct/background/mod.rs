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
use plenoptic_recon::background::{Environment, PlacedEnvironment};

use super::geometry::view::ViewBuffer;
use super::{KeyTextures, ReconstructSystems, ResolvedBackend};
use crate::Backend;
use crate::asset::RadiancePack;
use crate::camera::PlenopticCamera;
use crate::camera::layers::ViewLayer;

/// The background behind the proxies: its material, and one background per GPU camera kept
/// at the camera's time (part of [`super::PlenopticReconstructPlugin`]).
#[derive(Debug, Default)]
pub struct BackgroundPlugin;

impl Plugin for BackgroundPlugin {
    fn build(&self, app: &mut App) {
        embedded_asset!(app, "background.wgsl");
        app.add_plugins(MaterialPlugin::<PlenopticBackgroundMaterial>::default())
            .init_resource::<EnvironmentImages>()
            .add_systems(
                Update,
                (
                    spawn_backgrounds.in_set(ReconstructSystems::Attach),
                    update_backgrounds.in_set(ReconstructSystems::Materials),
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
    /// The image-mode frame ([`super::image::ImageFrame`]), shown while the camera is in
    /// image mode.
    #[texture(2, sample_type = "float", filterable = false)]
    pub image_frame: Handle<Image>,
    /// The pack's environment at the camera's time.
    #[uniform(3)]
    pub environment: EnvironmentUniform,
    /// The pack's environment image (`Rgba32Float`; 1 × 1 black when it has none).
    #[texture(4, sample_type = "float", filterable = false)]
    pub environment_image: Handle<Image>,
}

/// The environment of a [`PlenopticBackgroundMaterial`] at one time (see `background.wgsl`).
#[derive(ShaderType, Debug, Clone, Default, PartialEq)]
pub struct EnvironmentUniform {
    /// x: kind (0 none: show the key's cube, 1 uniform, 2 sky, 3 image), y: image
    /// intensity, z and w: cosine and sine of the image's turn about +Y.
    pub kind: Vec4,
    /// Uniform colour (xyz).
    pub colour: Vec4,
    /// The sky's 27 Hosek–Wilkie coefficients (A–I of R, G, B), four per vector.
    pub sky: [Vec4; 7],
    /// The sky's radiance scale per channel (xyz).
    pub sky_radiance: Vec4,
    /// Unit direction towards the sun (xyz).
    pub sun: Vec4,
    /// The sky's radiance below the horizon: its ground (xyz; zero without one).
    pub ground: Vec4,
}

impl EnvironmentUniform {
    /// The uniform for `env` (an environment placed at a time).
    pub fn new(env: &PlacedEnvironment) -> Self {
        let mut u = EnvironmentUniform::default();
        match env {
            PlacedEnvironment::None => {}
            PlacedEnvironment::Uniform(c) => {
                u.kind.x = 1.0;
                u.colour = c.extend(0.0);
            }
            PlacedEnvironment::Sky(sky) => {
                let c = sky.coefficients();
                u.kind.x = 2.0;
                for (i, p) in c.params.iter().enumerate() {
                    u.sky[i / 4][i % 4] = *p;
                }
                u.sky_radiance = Vec3::from_array(c.radiances).extend(0.0);
                u.sun = c.sun.extend(0.0);
                u.ground = Vec3::from_array(c.ground).extend(0.0);
            }
            PlacedEnvironment::Image {
                intensity,
                to_image,
                ..
            } => {
                // `to_image` turns about +Y only: its angle, sign from the axis.
                let (axis, angle) = to_image.to_axis_angle();
                let angle = angle * axis.y.signum();
                u.kind = Vec4::new(3.0, *intensity, angle.cos(), angle.sin());
            }
        }
        u
    }
}

/// The environment image of each pack as a texture (`Rgba32Float`, row 0 at +Y), and the
/// 1 × 1 black texture of packs without one.
#[derive(Resource, Debug, Default)]
pub struct EnvironmentImages {
    images: std::collections::HashMap<AssetId<RadiancePack>, Handle<Image>>,
}

impl EnvironmentImages {
    /// The texture of `pack`'s environment image, made on first use.
    pub(crate) fn get(
        &mut self,
        id: AssetId<RadiancePack>,
        pack: &RadiancePack,
        images: &mut Assets<Image>,
    ) -> Handle<Image> {
        self.images
            .entry(id)
            .or_insert_with(|| {
                let (w, h, texels): (u32, u32, Vec<Vec3>) = match &pack.environment.environment {
                    Environment::Image { image, .. } => {
                        (image.width, image.height, image.texels.clone())
                    }
                    _ => (1, 1, vec![Vec3::ZERO]),
                };
                let data = texels
                    .iter()
                    .flat_map(|t| [t.x, t.y, t.z, 1.0])
                    .flat_map(f32::to_le_bytes)
                    .collect();
                images.add(Image::new(
                    Extent3d {
                        width: w,
                        height: h,
                        depth_or_array_layers: 1,
                    },
                    TextureDimension::D2,
                    data,
                    TextureFormat::Rgba32Float,
                    RenderAssetUsages::RENDER_WORLD,
                ))
            })
            .clone()
    }
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
pub(super) fn spawn_cpu_backgrounds(
    mut commands: Commands,
    backend: Res<ResolvedBackend>,
    frames: Res<super::cpu::CpuFrames>,
    cameras: Query<(Entity, &PlenopticCamera, &ViewLayer)>,
    existing: Query<&PlenopticBackground>,
    packs: Res<Assets<RadiancePack>>,
    mut images: ResMut<Assets<Image>>,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<PlenopticBackgroundMaterial>>,
) {
    if backend.0 != Backend::Cpu {
        return;
    }
    for (entity, cam, layer) in &cameras {
        if existing.iter().any(|b| b.camera == entity) {
            continue;
        }
        let (Some(pack), Some(frame)) = (packs.get(cam.pack.id()), frames.image(entity)) else {
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
            image_frame: frame,
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
    cameras: Query<(
        Entity,
        &PlenopticCamera,
        &ViewLayer,
        &super::image::ImageFrame,
    )>,
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
            image_frame: image_frame.0.clone(),
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
    cameras: Query<(&PlenopticCamera, &ViewBuffer)>,
    backgrounds: Query<(
        &PlenopticBackground,
        &MeshMaterial3d<PlenopticBackgroundMaterial>,
    )>,
    mut background_materials: ResMut<Assets<PlenopticBackgroundMaterial>>,
) {
    for (bg, handle) in &backgrounds {
        let Ok((cam, view)) = cameras.get(bg.camera) else {
            continue;
        };
        if bg.cpu {
            continue;
        }
        let id = cam.pack.id();
        let face = keys.0.get(&id).map_or(1, |t| t.face);
        let layer = view.lookups.heaviest_layer();
        let env = packs
            .get(id)
            .map(|p| p.environment.at(cam.time))
            .unwrap_or_default();
        set_background(
            &mut background_materials,
            handle,
            &env,
            layer,
            face,
            view.params().fill.z == 1.0,
        );
    }
}
