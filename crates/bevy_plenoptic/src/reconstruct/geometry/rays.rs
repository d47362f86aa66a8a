//! Reflected rays cast against the proxies on the GPU, as `plenoptic_recon::specular` casts
//! them on the CPU (docs/architecture.md, "The runtime plugin"): before a reflected ray is
//! marched through the distance cubes, it is tested against the proxies; one that meets none
//! within the march distance has left the scene and sees the pack's environment. Without the
//! test, a ray leaving through a window passes behind the wall beside it as every base view
//! but one on its line sees it, so no view answers and the window's reflection is cut short.
//!
//! The geometry is `plenoptic_recon::flat_rays`'s layout (built once per pack by the asset
//! loader, [`RadiancePack::rays`]), one storage buffer per pack; each camera has a second,
//! small buffer with the pack's moving objects placed at its time ([`CameraRays`], rewritten
//! when they move). `rays.wgsl` walks both exactly as `FlatRays::occluded` does.

use std::collections::HashMap;

use bevy::asset::RenderAssetUsages;
use bevy::math::Affine3A;
use bevy::prelude::*;
use bevy::render::storage::ShaderBuffer;

use crate::asset::RadiancePack;
use crate::camera::PlenopticCamera;

/// The ray-cast geometry buffer of each pack.
#[derive(Resource, Debug, Default)]
pub struct PackRays(HashMap<AssetId<RadiancePack>, Handle<ShaderBuffer>>);

impl PackRays {
    /// The buffer of `pack` (id `id`), made on first use.
    pub(crate) fn get(
        &mut self,
        id: AssetId<RadiancePack>,
        pack: &RadiancePack,
        buffers: &mut Assets<ShaderBuffer>,
    ) -> Handle<ShaderBuffer> {
        self.0
            .entry(id)
            .or_insert_with(|| buffers.add(words(pack.rays.words())))
            .clone()
    }
}

/// A camera's moving proxies placed at its time: the rows of each one's world → object
/// transform (`plenoptic_recon::flat_rays::FlatRays::placements`).
#[derive(Component, Debug, Clone)]
pub struct CameraRays {
    /// The buffer the materials of the camera bind.
    pub buffer: Handle<ShaderBuffer>,
    /// What it holds now.
    placed: Vec<Vec4>,
}

fn words(w: &[Vec4]) -> ShaderBuffer {
    let bytes: Vec<u8> = w
        .iter()
        .flat_map(|v| v.to_array())
        .flat_map(f32::to_le_bytes)
        .collect();
    ShaderBuffer::new(&bytes, RenderAssetUsages::RENDER_WORLD)
}

/// Gives every plenoptic camera its placement buffer.
pub(super) fn add_camera_rays(
    mut commands: Commands,
    cameras: Query<Entity, (With<PlenopticCamera>, Without<CameraRays>)>,
    mut buffers: ResMut<Assets<ShaderBuffer>>,
) {
    for camera in &cameras {
        let placed = vec![Vec4::ZERO];
        commands.entity(camera).insert(CameraRays {
            buffer: buffers.add(words(&placed)),
            placed,
        });
    }
}

/// Places each camera's moving proxies at its time (the buffer is rewritten only when they
/// moved).
pub(super) fn place_rays(
    packs: Res<Assets<RadiancePack>>,
    mut cameras: Query<(&PlenopticCamera, &mut CameraRays)>,
    mut buffers: ResMut<Assets<ShaderBuffer>>,
) {
    for (cam, mut rays) in &mut cameras {
        let Some(pack) = packs.get(cam.pack.id()) else {
            continue;
        };
        let placed = pack.rays.placements(|id| {
            pack.proxy(id).map_or(Affine3A::IDENTITY, |p| {
                p.transform_at(cam.time).compute_affine()
            })
        });
        if placed != rays.placed {
            if let Some(mut buffer) = buffers.get_mut(&rays.buffer) {
                *buffer = words(&placed);
            }
            rays.placed = placed;
        }
    }
}
