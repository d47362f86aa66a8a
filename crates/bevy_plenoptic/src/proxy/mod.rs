//! The geometry mask (thesis §8.2.3): the pack's proxy meshes as ordinary Bevy mesh
//! entities, placed from the pack's animation tracks at the camera's time.
//!
//! Rasterising them gives every pixel its object and the point on it and writes real depth
//! into Bevy's depth buffer, so ordinary Bevy meshes occlude the baked scene and are occluded
//! by it without any special compositing.
//!
//! Each [`PlenopticCamera`] has its own set, on its own render layer
//! ([`crate::camera::layers`]): two cameras at different times see the objects where each
//! camera's time puts them.

use std::collections::HashMap;

use bevy::light::NotShadowCaster;
use bevy::prelude::*;

use crate::asset::RadiancePack;
use crate::camera::PlenopticCamera;
use crate::camera::layers::ViewLayer;
use crate::settings::{PlenopticEvent, PlenopticSystems};

/// Spawns and animates the proxy geometry of every [`PlenopticCamera`].
#[derive(Debug, Default)]
pub struct PlenopticProxyPlugin;

impl Plugin for PlenopticProxyPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<ProxyScenes>().add_systems(
            Update,
            (spawn_proxy_scenes, place_proxies)
                .chain()
                .in_set(PlenopticSystems::Playback)
                .after(crate::camera::advance_playback),
        );
    }
}

/// The root entity of each plenoptic camera's proxy geometry.
#[derive(Resource, Debug, Default)]
pub struct ProxyScenes(pub HashMap<Entity, Entity>);

/// Marks the root of a camera's proxy geometry.
#[derive(Component, Debug, Clone)]
pub struct PlenopticScene {
    /// The pack.
    pub pack: Handle<RadiancePack>,
    /// The camera it is drawn for (and placed at the time of).
    pub camera: Entity,
}

/// One proxy object: its pack object id.
#[derive(Component, Debug, Clone, Copy, PartialEq, Eq)]
pub struct ProxyOf {
    /// Pack object id.
    pub id: u32,
}

/// The material proxy meshes are drawn with.
#[derive(Resource, Debug, Clone)]
pub struct ProxyMaterial(pub Handle<StandardMaterial>);

/// Spawns each camera's proxy geometry once its pack has loaded (again when the camera
/// changes pack) and despawns that of cameras that are gone.
#[expect(clippy::too_many_arguments, reason = "a Bevy system's parameters")]
fn spawn_proxy_scenes(
    mut commands: Commands,
    mut scenes: ResMut<ProxyScenes>,
    packs: Res<Assets<RadiancePack>>,
    cameras: Query<(Entity, &PlenopticCamera, &ViewLayer)>,
    roots: Query<&PlenopticScene>,
    material: Option<Res<ProxyMaterial>>,
    mut materials: ResMut<Assets<StandardMaterial>>,
    mut events: MessageWriter<PlenopticEvent>,
) {
    scenes.0.retain(|camera, root| {
        let keep = cameras
            .get(*camera)
            .is_ok_and(|(_, cam, _)| roots.get(*root).is_ok_and(|s| s.pack == cam.pack));
        if !keep && let Ok(mut e) = commands.get_entity(*root) {
            e.despawn();
        }
        keep
    });
    for (camera, cam, layer) in &cameras {
        let id = cam.pack.id();
        if scenes.0.contains_key(&camera) {
            continue;
        }
        let Some(pack) = packs.get(id) else {
            continue;
        };
        let material = match &material {
            Some(m) => m.0.clone(),
            None => {
                let m = materials.add(StandardMaterial {
                    base_color: Color::linear_rgb(0.5, 0.5, 0.5),
                    unlit: true,
                    // Proxy meshes are seen from both sides (walls from inside a room).
                    cull_mode: None,
                    double_sided: true,
                    ..default()
                });
                commands.insert_resource(ProxyMaterial(m.clone()));
                m
            }
        };
        // Once per pack, not per camera.
        if !scenes.0.keys().any(|c| {
            cameras
                .get(*c)
                .is_ok_and(|(_, other, _)| other.pack.id() == id)
        }) {
            for (chunk, reason) in &pack.failed {
                events.write(PlenopticEvent::ChunkFailed {
                    chunk: chunk.clone(),
                    reason: reason.clone(),
                });
            }
        }
        let root = commands
            .spawn((
                Name::new("plenoptic proxy geometry"),
                PlenopticScene {
                    pack: cam.pack.clone(),
                    camera,
                },
                Transform::IDENTITY,
                Visibility::default(),
            ))
            .with_children(|parent| {
                for p in &pack.proxies {
                    let mut proxy = parent.spawn((
                        Name::new(p.name.clone()),
                        ProxyOf { id: p.id },
                        Mesh3d(p.mesh.clone()),
                        MeshMaterial3d(material.clone()),
                        p.transform_at(cam.time),
                        layer.layers(),
                    ));
                    // Glazing dims the runtime sun by its coverage instead of blocking it
                    // (the shaders' `see_through_pass`), so it stays out of the shadow map.
                    if pack.coverage(p.id).is_some() {
                        proxy.insert(NotShadowCaster);
                    }
                }
            })
            .id();
        scenes.0.insert(camera, root);
    }
}

/// Places every proxy object at its camera's time.
fn place_proxies(
    packs: Res<Assets<RadiancePack>>,
    cameras: Query<&PlenopticCamera>,
    roots: Query<(&PlenopticScene, &Children)>,
    mut proxies: Query<(&ProxyOf, &mut Transform)>,
) {
    for (scene, children) in &roots {
        let Some(pack) = packs.get(&scene.pack) else {
            continue;
        };
        let Ok(cam) = cameras.get(scene.camera) else {
            continue;
        };
        for child in children.iter() {
            let Ok((of, mut transform)) = proxies.get_mut(child) else {
                continue;
            };
            if let Some(p) = pack.proxy(of.id)
                && p.track.is_some()
            {
                let t = p.transform_at(cam.time);
                if *transform != t {
                    *transform = t;
                }
            }
        }
    }
}
