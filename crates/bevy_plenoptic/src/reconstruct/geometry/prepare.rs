//! The main-world side of the geometry-assisted path (`docs/architecture.md`, "The runtime
//! plugin"): every proxy of a camera gets a [`PlenopticMaterial`] bound to its pack's key
//! textures and its camera's view buffer, and is kept bound to them. Its uniform holds only
//! its object, so it is written again only when the camera's settings or bindings change.

use bevy::prelude::*;
use bevy::render::storage::ShaderBuffer;

use super::{
    ObjectParams, PlenopticMaterial, blend, frame, material_factors, object_coverage, rays,
    screen_fill, view, volume,
};
use crate::asset::RadiancePack;
use crate::camera::PlenopticCamera;
use crate::proxy::{PlenopticScene, ProxyOf};
use crate::reconstruct::KeyTextures;
use crate::reconstruct::counters::CounterBuffer;
use crate::reconstruct::environment::EnvironmentImages;
use crate::reconstruct::frames::ImageFrame;
use crate::settings::{Backend, PlenopticSettings, ResolvedBackend};

/// Gives every proxy of a camera on the GPU backend its proxy material.
#[expect(clippy::too_many_arguments, reason = "a Bevy system's parameters")]
pub(super) fn attach_materials(
    mut commands: Commands,
    backend: Res<ResolvedBackend>,
    keys: Res<KeyTextures>,
    volumes: Res<volume::VolumeBuffers>,
    cameras: Query<(
        &ImageFrame,
        &rays::CameraRays,
        &view::ViewBuffer,
        &CounterBuffer,
        &blend::BlendedKeys,
    )>,
    (settings, early_depth): (Res<PlenopticSettings>, Res<screen_fill::EarlyDepthSupport>),
    packs: Res<Assets<RadiancePack>>,
    roots: Query<&PlenopticScene>,
    proxies: Query<(Entity, &ChildOf, &ProxyOf), With<MeshMaterial3d<StandardMaterial>>>,
    mut materials: ResMut<Assets<PlenopticMaterial>>,
    mut env_images: ResMut<EnvironmentImages>,
    mut images: ResMut<Assets<Image>>,
    (mut pack_rays, mut buffers): (ResMut<rays::PackRays>, ResMut<Assets<ShaderBuffer>>),
) {
    if backend.0 != Backend::Gpu {
        return;
    }
    for (entity, parent, of) in &proxies {
        let Ok(scene) = roots.get(parent.parent()) else {
            continue;
        };
        let Ok((image_frame, camera_rays, view_buffer, counters, blended)) =
            cameras.get(scene.camera)
        else {
            continue;
        };
        let (Some(tex), Some(vol), Some(pack)) = (
            keys.0.get(&scene.pack.id()),
            volumes.0.get(&scene.pack.id()),
            packs.get(scene.pack.id()),
        ) else {
            continue;
        };
        let factors = material_factors(pack, of.id);
        let transmissive = factors
            .as_ref()
            .is_some_and(|f| f.material.transmission > 0.0);
        let environment_image = env_images.get(scene.pack.id(), pack, &mut images);
        let m = materials.add(PlenopticMaterial {
            cubes: tex.image.clone(),
            params: ObjectParams::default(),
            volume_samples: vol.samples.clone(),
            volume_bins: vol.bins.clone(),
            image_frame: image_frame.image.clone(),
            shading_cubes: tex.shading.clone(),
            base_colour_texture: factors.as_ref().and_then(|f| f.base_colour.clone()),
            metallic_roughness_texture: factors.as_ref().and_then(|f| f.metallic_roughness.clone()),
            normal_texture: factors.as_ref().and_then(|f| f.normal.clone()),
            emissive_texture: factors.as_ref().and_then(|f| f.emissive.clone()),
            view: view_buffer.buffer.clone(),
            environment_image,
            rays: pack_rays.get(scene.pack.id(), pack, &mut buffers),
            ray_placements: camera_rays.buffer.clone(),
            counters: counters.buffer.clone(),
            fill_entries: view_buffer.fill_entries.clone(),
            hole_list: view_buffer.hole_list.clone(),
            blended_geometry: blended.geometry.clone(),
            blended_terms: blended.terms.clone(),
            cost_counters: settings.cost_counters,
            screen_fill: view_buffer.screen_fill(),
            early_depth: early_depth.0,
            albedo: factors,
            coverage: object_coverage(pack, of.id),
            transmissive,
            bindings: view_buffer.bindings,
        });
        commands
            .entity(entity)
            .remove::<MeshMaterial3d<StandardMaterial>>()
            .insert(MeshMaterial3d(m));
    }
}

/// Keeps every proxy material's uniform and bindings up to date with its camera.
///
/// A material is written only when its uniform (which changes with the camera's settings)
/// or its camera's bindings changed: a written asset's bind group is prepared again, and the
/// per-frame lookups are in the camera's view buffer, so a camera costs no material uploads
/// from one frame to the next.
pub(crate) fn update_materials(
    packs: Res<Assets<RadiancePack>>,
    cameras: Query<(&PlenopticCamera, &view::ViewBuffer)>,
    roots: Query<&PlenopticScene>,
    proxies: Query<(&ChildOf, &ProxyOf, &MeshMaterial3d<PlenopticMaterial>)>,
    mut materials: ResMut<Assets<PlenopticMaterial>>,
) {
    for (parent, of, handle) in &proxies {
        let Ok(scene) = roots.get(parent.parent()) else {
            continue;
        };
        let Ok((cam, view)) = cameras.get(scene.camera) else {
            continue;
        };
        if let Some(pack) = packs.get(cam.pack.id()) {
            frame::rebind(&mut materials, &handle.0, of.id, (cam, pack), view);
        }
    }
}

impl frame::BindsView for PlenopticMaterial {
    /// Coverage and material were looked up in the manifest once, when the material was
    /// attached.
    fn shading(&self, id: u32) -> frame::ObjectShading<'_> {
        frame::ObjectShading {
            id,
            coverage: self.coverage,
            factors: self.albedo.as_ref(),
            opaque_pass: self.alpha_mode() == AlphaMode::Opaque,
        }
    }

    fn bound(&self) -> (&ObjectParams, u64, &Handle<ShaderBuffer>) {
        (&self.params, self.bindings, &self.view)
    }

    fn bind(&mut self, params: ObjectParams, view: &view::ViewBuffer) {
        self.params = params;
        self.bindings = view.bindings;
        self.view = view.buffer.clone();
        self.counters = view.counters.clone();
        self.fill_entries = view.fill_entries.clone();
        self.hole_list = view.hole_list.clone();
        self.screen_fill = view.screen_fill();
        if let Some((geometry, terms)) = &view.blended {
            self.blended_geometry = geometry.clone();
            self.blended_terms = terms.clone();
        }
        if let Some((cubes, shading)) = &view.keys {
            self.cubes = cubes.clone();
            self.shading_cubes = shading.clone();
        }
    }
}
