//! One render layer per [`PlenopticCamera`]: what the plugin draws for a camera (its proxy
//! geometry, its background, its runtime sun's shadow casters) is seen by that camera only.
//!
//! A pack's objects move with the camera's time, and two cameras at different times need
//! an object in two places. A Bevy mesh entity has one transform for every view, so each
//! camera draws its own set of proxy entities, placed at its own time and carrying its own
//! lookups, on a render layer of its own ([`ViewLayer`]). The camera's `RenderLayers` keep
//! whatever the app gave it (layer 0 when nothing) and gain that layer, so the app's own
//! meshes stay visible and keep compositing with the proxies by depth. Cameras of the app
//! that are not plenoptic cameras do not see any camera's proxies.

use std::collections::HashMap;

use bevy::camera::visibility::RenderLayers;
use bevy::prelude::*;

use super::PlenopticCamera;
use crate::settings::PlenopticSettings;

/// The render layer of a [`PlenopticCamera`]'s own proxies, background and sun (see the
/// module doc), from [`PlenopticSettings::first_render_layer`] up, the lowest free pair (the
/// layer above is the camera's shadow-only layer, [`ViewLayer::shadow_only`]).
#[derive(Component, Debug, Clone, Copy, PartialEq, Eq)]
pub struct ViewLayer(pub usize);

impl ViewLayer {
    /// The layer as `RenderLayers`, for the entities drawn for this camera.
    pub fn layers(self) -> RenderLayers {
        RenderLayers::layer(self.0)
    }

    /// The layer above it, which the camera does not see: proxies drawn only into the
    /// camera's sun's shadow map (those of objects the app's own lit meshes show,
    /// [`crate::lit::scene`]).
    pub fn shadow_only(self) -> RenderLayers {
        RenderLayers::layer(self.0 + 1)
    }

    /// The camera's sun's layers: its own and the shadow-only one.
    pub fn light_layers(self) -> RenderLayers {
        RenderLayers::from_layers(&[self.0, self.0 + 1])
    }
}

/// Which camera holds which layer.
#[derive(Resource, Debug, Default)]
pub struct ViewLayers(pub HashMap<Entity, usize>);

/// A plenoptic camera's layer, if it has one yet, and its `RenderLayers`.
type CameraLayers<'a> = (Entity, Option<&'a ViewLayer>, Option<&'a RenderLayers>);

/// Gives every plenoptic camera a [`ViewLayer`] and keeps it in the camera's
/// `RenderLayers`; frees the layers of cameras that are gone.
pub fn assign_view_layers(
    mut commands: Commands,
    settings: Res<PlenopticSettings>,
    mut assigned: ResMut<ViewLayers>,
    cameras: Query<CameraLayers, With<PlenopticCamera>>,
) {
    assigned.0.retain(|e, _| cameras.contains(*e));
    for (entity, layer, render_layers) in &cameras {
        let layer = match layer {
            Some(l) => *assigned.0.entry(entity).or_insert(l.0),
            None => {
                // Two layers each: the camera's and its shadow-only one above it.
                let mut l = settings.first_render_layer;
                while assigned
                    .0
                    .values()
                    .any(|&taken| taken == l || taken == l + 1 || taken + 1 == l)
                {
                    l += 2;
                }
                assigned.0.insert(entity, l);
                commands.entity(entity).insert(ViewLayer(l));
                l
            }
        };
        let own = RenderLayers::layer(layer);
        let current = render_layers.cloned().unwrap_or_default();
        if !current.intersects(&own) {
            commands.entity(entity).insert(current.with(layer));
        }
    }
}
