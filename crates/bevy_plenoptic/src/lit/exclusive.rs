//! A lit scene drawn by its own camera only (`docs/architecture.md`, "The runtime plugin"):
//! for an app with several plenoptic cameras (split-screen, picture-in-picture, a stereo
//! pair) that spawns the scene once per camera, each copy lit for its camera's pack, time and
//! place ([`PlenopticLit::only_for`]).
//!
//! A Bevy mesh entity has one material for every view, and a lit mesh's material binds its
//! camera's view buffer; so a mesh seen by two cameras is lit for one of them. With one copy
//! of the scene per camera, each copy's meshes are put on its camera's own render layer
//! ([`ViewLayer`]), as the camera's proxies are: no other camera draws them. A mesh keeps the
//! render layers it had in [`OnCameraLayer`] and gets them back when its scene is no longer
//! lit for one camera only or the camera is gone.
//!
//! A scene lit with [`PlenopticLit::new`] while another plenoptic camera sees layer 0 (where
//! the scene's meshes are unless the app moved them) gets a warning, once: that camera draws
//! the meshes lit for the first: with both copies drawn by both cameras, each camera's frame
//! differs from its proxies' by 2.4 and 10.5 times their mean luminance on lavapipe (printed by
//! `cargo test --test plugin_gpu own_copy -- --nocapture`).

use std::collections::HashSet;

use bevy::camera::visibility::RenderLayers;
use bevy::prelude::*;

use super::scene::PlenopticLit;
use crate::camera::PlenopticCamera;
use crate::camera::layers::ViewLayer;
use crate::settings::PlenopticSystems;

/// Adds the systems (part of [`super::PlenopticLitPlugin`]).
pub(super) fn build(app: &mut App) {
    app.add_systems(
        Update,
        (release_camera_layers, camera_layers, warn_shared_scenes)
            .chain()
            .after(PlenopticSystems::Streaming),
    );
}

impl PlenopticLit {
    /// The scene lit by `camera`'s pack at its time, drawn by every camera that sees it.
    pub fn new(camera: Entity) -> Self {
        PlenopticLit {
            camera,
            only_this_camera: false,
        }
    }

    /// The scene lit by `camera`'s pack at its time and drawn by `camera` only (one copy of
    /// the scene per camera).
    pub fn only_for(camera: Entity) -> Self {
        PlenopticLit {
            camera,
            only_this_camera: true,
        }
    }
}

/// A mesh of a scene lit for one camera only, on that camera's layer.
#[derive(Component, Debug, Clone, PartialEq, Eq)]
pub struct OnCameraLayer {
    /// The camera.
    pub camera: Entity,
    /// The mesh's render layers before (`None`: it had none, layer 0).
    pub original: Option<RenderLayers>,
}

/// A mesh under a [`PlenopticLit`] root: its render layers and whether it is on a camera's.
type SceneMesh<'a> = (Option<&'a RenderLayers>, Option<&'a OnCameraLayer>);

/// Puts the meshes of every scene lit for one camera only on that camera's layer.
fn camera_layers(
    mut commands: Commands,
    roots: Query<(Entity, &PlenopticLit)>,
    children: Query<&Children>,
    meshes: Query<SceneMesh, With<Mesh3d>>,
    cameras: Query<&ViewLayer>,
) {
    for (root, lit) in &roots {
        if !lit.only_this_camera {
            continue;
        }
        let Ok(layer) = cameras.get(lit.camera) else {
            continue;
        };
        let wanted = layer.layers();
        for entity in children.iter_descendants(root) {
            let Ok((layers, placed)) = meshes.get(entity) else {
                continue;
            };
            if layers == Some(&wanted) && placed.is_some_and(|p| p.camera == lit.camera) {
                continue;
            }
            let original = match placed {
                Some(p) => p.original.clone(),
                None => layers.cloned(),
            };
            commands.entity(entity).insert((
                wanted.clone(),
                OnCameraLayer {
                    camera: lit.camera,
                    original,
                },
            ));
        }
    }
}

/// Gives a mesh its own render layers back once its scene is no longer lit for its camera
/// only, or the camera is gone.
fn release_camera_layers(
    mut commands: Commands,
    roots: Query<&PlenopticLit>,
    parents: Query<&ChildOf>,
    cameras: Query<(), With<ViewLayer>>,
    placed: Query<(Entity, &OnCameraLayer)>,
) {
    for (entity, on) in &placed {
        let lit = parents
            .iter_ancestors(entity)
            .find_map(|a| roots.get(a).ok());
        if lit.is_some_and(|l| l.only_this_camera && l.camera == on.camera)
            && cameras.contains(on.camera)
        {
            continue;
        }
        let mut e = commands.entity(entity);
        e.remove::<OnCameraLayer>();
        match &on.original {
            Some(layers) => e.insert(layers.clone()),
            None => e.remove::<RenderLayers>(),
        };
    }
}

/// Warns once per scene lit for one camera with [`PlenopticLit::new`] that another plenoptic
/// camera seeing layer 0 draws (see the module doc).
fn warn_shared_scenes(
    roots: Query<(Entity, &PlenopticLit)>,
    cameras: Query<(Entity, Option<&RenderLayers>), With<PlenopticCamera>>,
    mut warned: Local<HashSet<Entity>>,
) {
    for (root, lit) in &roots {
        if lit.only_this_camera || warned.contains(&root) {
            continue;
        }
        let others = cameras
            .iter()
            .filter(|(c, layers)| {
                *c != lit.camera && layers.is_none_or(|l| l.intersects(&RenderLayers::default()))
            })
            .count();
        if others > 0 {
            warn!(
                "plenoptic: the scene {root} is lit for camera {} (PlenopticLit::new), and \
                 {others} other plenoptic camera(s) draw its meshes lit for that camera; spawn \
                 the scene once per camera with PlenopticLit::only_for",
                lit.camera
            );
            warned.insert(root);
        }
    }
}
