//! The runtime sun on the GPU (pack 3; docs/architecture.md, "The runtime sun"): a pack whose
//! lighting leaves the sun's direct light out ([`plenoptic_pack::DirectSun`]) gets it back
//! per fragment, as `plenoptic_recon::sun` adds it on the CPU: the surface's BSDF for the
//! sun's direction (`sun.wgsl`, the same formulas) × the track's illuminance at the
//! camera's time × the cosine × the visibility.
//!
//! The visibility comes from Bevy's own cascaded shadow map of a [`DirectionalLight`] the
//! plugin spawns per camera on such a pack ([`PlenopticSun`]), aimed along the sun's track at
//! the camera's time, shadows on: the camera's proxies cast shadows as any mesh does. The
//! light is on the camera's own render layer and its shadow-only one
//! ([`crate::camera::layers`]; the proxies of objects the app's own lit meshes show are
//! there, [`crate::lit::scene`]): Bevy gives a view
//! only the directional lights that share a layer with it, and a light's shadow casters are
//! the meshes on its layers, so each camera is lit and shadowed by its own sun at its own
//! time. That light also lights the app's own `StandardMaterial` meshes in that camera like
//! the pack's sun, but they cast no shadow from it (they are not on the camera's layer). The
//! CPU casts shadow rays against the proxies instead, so the two agree away from shadow edges
//! and differ at them by the shadow map's resolution and filter. Glazing (objects with a pack
//! coverage c) casts no shadow map: `sun.wgsl` dims the light by `Π (1 − c)` over the glazing
//! surfaces between the fragment and the sun, walking the glazing's own BVHs in the flat ray
//! layout (`rays.wgsl`'s `see_through_pass`), as the CPU's shadow rays pass glazing. The app's
//! own meshes lit by that light get the sun through glazing undimmed.

use bevy::light::CascadeShadowConfigBuilder;
use bevy::prelude::*;

use super::view::ViewParams;
use crate::asset::RadiancePack;
use crate::camera::PlenopticCamera;
use crate::camera::layers::ViewLayer;

/// The directional light the plugin keeps for the runtime sun of a camera's pack.
#[derive(Component, Debug, Clone)]
pub struct PlenopticSun {
    /// The camera it lights.
    pub camera: Entity,
}

/// The sun of `pack` at time `t`, when its lighting leaves the sun to the runtime: unit
/// direction towards it and its illuminance.
pub fn sun_at(pack: &RadiancePack, t: f32) -> Option<(Vec3, Vec3)> {
    let (track, _) = pack.reader.direct_sun()?;
    let (towards, illuminance) = track.at(t);
    Some((towards.normalize_or(Vec3::Y), illuminance))
}

/// The view buffer's sun fields for a camera at time `t` on `pack`.
pub(super) fn fill(params: &mut ViewParams, pack: &RadiancePack, t: f32, weight: Vec3) {
    if let Some((towards, illuminance)) = sun_at(pack, t) {
        params.sun = towards.extend(0.0);
        params.flags |= super::view::ViewFlags::SUN;
        params.sun_illuminance = (illuminance * weight).extend(0.0);
    }
}

/// Spawns, aims and removes the [`PlenopticSun`] lights: one per camera whose pack has a
/// runtime sun, at the camera's time.
pub(super) fn update_suns(
    mut commands: Commands,
    packs: Res<Assets<RadiancePack>>,
    cameras: Query<(Entity, &PlenopticCamera, &ViewLayer)>,
    mut suns: Query<(Entity, &PlenopticSun, &mut Transform, &mut DirectionalLight)>,
) {
    let mut wanted: Vec<(Entity, ViewLayer, Vec3, Vec3, f32)> = Vec::new();
    for (camera, cam, layer) in &cameras {
        let Some(pack) = packs.get(cam.pack.id()) else {
            continue;
        };
        if let Some((towards, e)) = sun_at(pack, cam.time) {
            let b = &pack.reader.manifest().scene_bounds;
            wanted.push((camera, *layer, towards, e, (b.max - b.min).length()));
        }
    }
    let lux = |e: Vec3| 0.2126 * e.x + 0.7152 * e.y + 0.0722 * e.z;
    // The illuminance's colour at unit luminance (the light's `illuminance` carries the lux).
    let colour = |e: Vec3| {
        let c = e / lux(e).max(1e-6);
        Color::linear_rgb(c.x, c.y, c.z)
    };
    let aim = |towards: Vec3| {
        let up = if towards.y.abs() > 0.99 {
            Vec3::Z
        } else {
            Vec3::Y
        };
        Transform::default().looking_to(-towards, up)
    };
    for (entity, sun, mut transform, mut light) in &mut suns {
        match wanted.iter().position(|w| w.0 == sun.camera) {
            Some(i) => {
                let (_, _, towards, e, _) = wanted.swap_remove(i);
                *transform = aim(towards);
                light.illuminance = lux(e);
                light.color = colour(e);
            }
            None => commands.entity(entity).despawn(),
        }
    }
    for (camera, layer, towards, e, diagonal) in wanted {
        commands.spawn((
            Name::new("plenoptic sun"),
            PlenopticSun { camera },
            layer.light_layers(),
            DirectionalLight {
                illuminance: lux(e),
                color: colour(e),
                shadow_maps_enabled: true,
                ..default()
            },
            aim(towards),
            // The cascades cover the scene from any camera inside it (Bevy's defaults for a
            // pack without bounds).
            if diagonal > 0.0 {
                CascadeShadowConfigBuilder {
                    maximum_distance: diagonal,
                    first_cascade_far_bound: diagonal / 8.0,
                    ..default()
                }
                .build()
            } else {
                CascadeShadowConfigBuilder::default().build()
            },
        ));
    }
}
