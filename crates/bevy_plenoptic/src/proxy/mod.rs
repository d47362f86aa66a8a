//! The geometry mask (thesis §8.2.3): the pack's proxy meshes as ordinary Bevy mesh
//! entities, placed from the pack's animation tracks at the camera's time.
//!
//! Rasterising them gives every pixel its object and the point on it and writes real depth
//! into Bevy's depth buffer, so ordinary Bevy meshes occlude the baked scene and are occluded
//! by it without any special compositing.

use std::collections::HashMap;

use bevy::prelude::*;

use crate::asset::RadiancePack;
use crate::camera::PlenopticCamera;
use crate::{PlenopticEvent, PlenopticSystems};

/// Spawns and animates the proxy geometry of every pack a [`PlenopticCamera`] shows.
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

/// The root entity of the proxy geometry of each pack on screen.
#[derive(Resource, Debug, Default)]
pub struct ProxyScenes(pub HashMap<AssetId<RadiancePack>, Entity>);

/// Marks the root of a pack's proxy geometry.
#[derive(Component, Debug, Clone)]
pub struct PlenopticScene {
    /// The pack.
    pub pack: Handle<RadiancePack>,
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

fn spawn_proxy_scenes(
    mut commands: Commands,
    mut scenes: ResMut<ProxyScenes>,
    packs: Res<Assets<RadiancePack>>,
    cameras: Query<&PlenopticCamera>,
    material: Option<Res<ProxyMaterial>>,
    mut materials: ResMut<Assets<StandardMaterial>>,
    mut events: MessageWriter<PlenopticEvent>,
) {
    for cam in &cameras {
        let id = cam.pack.id();
        if scenes.0.contains_key(&id) {
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
        for (chunk, reason) in &pack.failed {
            events.write(PlenopticEvent::ChunkFailed {
                chunk: chunk.clone(),
                reason: reason.clone(),
            });
        }
        let root = commands
            .spawn((
                Name::new("plenoptic proxy geometry"),
                PlenopticScene {
                    pack: cam.pack.clone(),
                },
                Transform::IDENTITY,
                Visibility::default(),
            ))
            .with_children(|parent| {
                for p in &pack.proxies {
                    parent.spawn((
                        Name::new(p.name.clone()),
                        ProxyOf { id: p.id },
                        Mesh3d(p.mesh.clone()),
                        MeshMaterial3d(material.clone()),
                        p.transform_at(cam.time),
                    ));
                }
            })
            .id();
        scenes.0.insert(id, root);
    }
}

/// Places every proxy object at the time of the first camera showing its pack.
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
        let Some(cam) = cameras.iter().find(|c| c.pack.id() == scene.pack.id()) else {
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
