//! The environment behind the proxy geometry: pixels no proxy covers show the heaviest key's
//! radiance cube in the pixel's viewing direction, as `plenoptic_recon` does for pixels
//! without geometry (sky through a window, say).
//!
//! Each GPU camera gets a child entity with a one-triangle mesh drawn by
//! [`PlenopticBackgroundMaterial`], whose vertex shader (`background.wgsl`) takes its
//! positions as clip-space corners of a full-screen triangle at depth 0, the far end of Bevy's
//! reverse-Z depth (no culling, not frustum-culled): it
//! passes the depth test only where nothing was drawn, so proxies and ordinary meshes stay
//! in front of it. It takes no part in the prepass or shadows.

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

use super::{KeyTextures, ResolvedBackend};
use crate::Backend;
use crate::camera::PlenopticCamera;

/// Adds the background material and keeps one background per GPU camera.
pub(super) fn build(app: &mut App) {
    embedded_asset!(app, "background.wgsl");
    app.add_plugins(MaterialPlugin::<PlenopticBackgroundMaterial>::default());
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
        "embedded://bevy_plenoptic/reconstruct/background.wgsl".into()
    }

    fn fragment_shader() -> ShaderRef {
        "embedded://bevy_plenoptic/reconstruct/background.wgsl".into()
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
}

/// Spawns a background child for each camera on the GPU backend whose pack's key texture
/// exists.
#[expect(clippy::too_many_arguments, reason = "a Bevy system's parameters")]
pub(super) fn spawn_backgrounds(
    mut commands: Commands,
    backend: Res<ResolvedBackend>,
    keys: Res<KeyTextures>,
    image_frame: Res<super::image::ImageFrame>,
    cameras: Query<(Entity, &PlenopticCamera)>,
    existing: Query<&PlenopticBackground>,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<PlenopticBackgroundMaterial>>,
) {
    if backend.0 != Backend::Gpu {
        return;
    }
    for (entity, cam) in &cameras {
        if existing.iter().any(|b| b.camera == entity) {
            continue;
        }
        let Some(tex) = keys.0.get(&cam.pack.id()) else {
            continue;
        };
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
        let material = materials.add(PlenopticBackgroundMaterial {
            cubes: tex.image.clone(),
            params: BackgroundParams::default(),
            image_frame: image_frame.0.clone(),
        });
        let child = commands
            .spawn((
                Name::new("plenoptic background"),
                PlenopticBackground { camera: entity },
                Mesh3d(meshes.add(mesh)),
                MeshMaterial3d(material),
                NoFrustumCulling,
                Transform::IDENTITY,
            ))
            .id();
        commands.entity(entity).add_child(child);
    }
}

/// Shows the heaviest key (`layer`: its first array layer) of the camera's pack, or black;
/// or, with `image_mode`, the image-mode frame.
pub(super) fn set_background(
    materials: &mut Assets<PlenopticBackgroundMaterial>,
    handle: &MeshMaterial3d<PlenopticBackgroundMaterial>,
    layer: Option<u32>,
    face: u32,
    image_mode: bool,
) {
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
