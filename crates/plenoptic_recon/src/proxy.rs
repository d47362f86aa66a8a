//! Proxy geometry and the geometry mask (thesis §8.2.3: "geometry masks").
//!
//! The pack's proxy meshes (object space) and animation tracks become a
//! [`plenoptic_scene::Scene`] with one root node per object; the tracer's [`SceneAccel`]
//! builds one BVH per object once, and every frame only the top level is rebuilt
//! ([`SceneAccel::at_time`]). The *geometry mask* gives per pixel the object id (the pack's
//! id; 0 where no proxy is hit), the hit point and its distance, either by a primary ray per
//! pixel through that BVH ([`ProxyGeometry::mask`], the reference) or by rasterizing the same
//! placed triangles ([`ProxyGeometry::mask_raster`], the default of
//! [`crate::ReconSettings::mask`]: about 5× cheaper at 640×360 and what the GPU mask pass
//! does; the tests check that both agree).
//!
//! Conventions: an object whose tracks are absent is placed by the identity (its proxy mesh
//! is then in world space); a track that lacks a channel uses the identity for it.
//!
//! The [`SceneAccel`] borrows its scene, and a [`crate::Reconstructor`] owns both, so the
//! converted proxy scene is allocated once per reconstructor and intentionally never freed
//! (it is small: proxy meshes only). Create one reconstructor per pack, not one per frame.

use std::collections::HashMap;

use glam::{Affine3A, Vec3};
use plenoptic_pack::{
    AnimationTracks, Interpolation as PackInterp, PackReader, Track as PackTrack,
};
use plenoptic_scene::{Interpolation, Key, Mesh, Node, Object, Scene, Track, Trs, TrsTrack};
use plenoptic_trace::{PlacedScene, Ray, SceneAccel};
use rayon::prelude::*;

use crate::camera::Camera;

/// Converts one pack track into the scene's track type.
pub fn convert_track<T: Copy>(track: &PackTrack<T>) -> Option<Track<T>> {
    let n = track.times.len();
    if n == 0 || track.values.len() != n * track.interpolation.values_per_key() {
        return None;
    }
    let interpolation = match track.interpolation {
        PackInterp::Step => Interpolation::Step,
        PackInterp::Linear => Interpolation::Linear,
        PackInterp::CubicSpline => Interpolation::CubicSpline,
    };
    let keys = (0..n)
        .map(|i| {
            if track.interpolation == PackInterp::CubicSpline {
                Key {
                    time: track.times[i],
                    in_tangent: track.values[3 * i],
                    value: track.values[3 * i + 1],
                    out_tangent: track.values[3 * i + 2],
                }
            } else {
                let v = track.values[i];
                Key {
                    time: track.times[i],
                    value: v,
                    in_tangent: v,
                    out_tangent: v,
                }
            }
        })
        .collect();
    Some(Track {
        interpolation,
        keys,
    })
}

/// The pack's proxy geometry placed as a traceable scene.
pub struct ProxyGeometry {
    scene: &'static Scene,
    accel: SceneAccel<'static>,
    /// Pack object id of each scene object (scene object index → pack id).
    pack_ids: Vec<u32>,
    /// Pack object id → scene object index.
    index_of: HashMap<u32, usize>,
}

impl std::fmt::Debug for ProxyGeometry {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ProxyGeometry")
            .field("objects", &self.pack_ids)
            .finish()
    }
}

/// One object's proxy geometry as a pack stores it: the object-space mesh and the object's
/// motion, converted to the scene crate's tracks so it can be evaluated at any time.
#[derive(Debug, Clone)]
pub struct PackProxy {
    /// The object's id in the pack (0 is reserved for "no object").
    pub id: u32,
    /// The object's name from the manifest.
    pub name: String,
    /// The object's glTF node path from the manifest.
    pub node_path: String,
    /// The object-space proxy mesh.
    pub mesh: plenoptic_pack::ProxyMesh,
    /// The object's animation; `None` for an object without tracks (placed by the identity).
    pub track: Option<TrsTrack>,
}

/// Reads the proxy mesh and the tracks of every object of `pack` that has a proxy mesh.
/// Returns them with `(chunk, error)` for every chunk that could not be read; missing tracks
/// count only when some object is animated. Shared by the CPU reconstruction and the Bevy
/// plugin's asset loader.
pub fn read_proxies(pack: &PackReader) -> (Vec<PackProxy>, Vec<(String, String)>) {
    let mut failed = Vec::new();
    let tracks = match pack.tracks() {
        Ok(t) => t,
        Err(e) => {
            if pack
                .manifest()
                .objects
                .iter()
                .any(|o| o.motion == plenoptic_pack::Motion::Animated)
            {
                failed.push(("animation tracks".to_string(), e.to_string()));
            }
            AnimationTracks::default()
        }
    };
    let mut proxies = Vec::new();
    for entry in &pack.manifest().objects {
        let Some(key) = entry.proxy_mesh else {
            continue;
        };
        let mesh = match pack.proxy_mesh(key) {
            Ok(m) => m,
            Err(e) => {
                failed.push((
                    format!("proxy mesh of object {} ({})", entry.id, entry.name),
                    e.to_string(),
                ));
                continue;
            }
        };
        let track = tracks
            .objects
            .iter()
            .find(|o| o.object_id == entry.id)
            .map(|o| TrsTrack {
                translation: o.translation.as_ref().and_then(convert_track),
                rotation: o.rotation.as_ref().and_then(convert_track),
                scale: o.scale.as_ref().and_then(convert_track),
            });
        proxies.push(PackProxy {
            id: entry.id,
            name: entry.name.clone(),
            node_path: entry.node_path.clone(),
            mesh,
            track,
        });
    }
    (proxies, failed)
}

impl ProxyGeometry {
    /// Reads every proxy mesh and the tracks of `pack`. Returns the geometry (None if no
    /// proxy mesh could be read) and a description of every chunk that could not be read.
    pub fn from_pack(pack: &PackReader) -> (Option<Self>, Vec<String>) {
        let (proxies, failed) = read_proxies(pack);
        let mut missing: Vec<String> = failed
            .into_iter()
            .map(|(chunk, error)| format!("{chunk}: {error}"))
            .collect();
        let mut scene = Scene::default();
        scene
            .materials
            .push(plenoptic_trace::shapes::diffuse(Vec3::splat(0.5)));
        let mut pack_ids = Vec::new();
        for PackProxy {
            id,
            name,
            node_path,
            mesh,
            track,
        } in proxies
        {
            let normals = mesh.normals.unwrap_or_default();
            scene.meshes.push(Mesh {
                positions: mesh.positions,
                normals,
                uvs: Vec::new(),
                tangents: Vec::new(),
                colors: Vec::new(),
                triangles: mesh
                    .indices
                    .chunks_exact(3)
                    .map(|c| [c[0], c[1], c[2]])
                    .collect(),
            });
            scene.nodes.push(Node {
                name: name.clone(),
                parent: None,
                rest: Trs::default(),
                track,
            });
            scene.objects.push(Object {
                name,
                node_path,
                node: scene.nodes.len() - 1,
                mesh: scene.meshes.len() - 1,
                material: 0,
            });
            pack_ids.push(id);
        }
        if scene.objects.is_empty() {
            return (None, missing);
        }
        let scene: &'static Scene = Box::leak(Box::new(scene));
        match SceneAccel::new(scene) {
            Ok(accel) => {
                let index_of = pack_ids
                    .iter()
                    .enumerate()
                    .map(|(i, &id)| (id, i))
                    .collect();
                (
                    Some(ProxyGeometry {
                        scene,
                        accel,
                        pack_ids,
                        index_of,
                    }),
                    missing,
                )
            }
            Err(e) => {
                missing.push(format!("proxy geometry: {e}"));
                (None, missing)
            }
        }
    }

    /// Pack ids of the objects with geometry.
    pub fn object_ids(&self) -> &[u32] {
        &self.pack_ids
    }

    /// Object-to-world transform of pack object `id` at time `t` (identity if unknown).
    pub fn transform(&self, id: u32, t: f32) -> Affine3A {
        match self.index_of.get(&id) {
            Some(&i) => self.scene.object_transform(i as u32, t),
            None => Affine3A::IDENTITY,
        }
    }

    /// The geometry placed at time `t`.
    pub fn at_time(&self, t: f32) -> PlacedScene<'_> {
        self.accel.at_time(t)
    }

    /// The geometry mask of `camera` at time `t` by ray casting through the tracer's
    /// two-level BVH (the reference; about one ray per pixel).
    pub fn mask(&self, camera: &Camera, t: f32) -> GeometryMask {
        let placed = self.at_time(t);
        self.mask_placed(&placed, camera)
    }

    /// The geometry mask of `camera` at time `t` by rasterizing the placed proxy triangles
    /// (what the GPU mask pass does): the same object ids and hit points as [`Self::mask`]
    /// up to pixel-centre edge rules, at a fraction of the cost. See the `raster` module.
    pub fn mask_raster(&self, camera: &Camera, t: f32) -> GeometryMask {
        crate::raster::rasterize(camera, &self.placed_meshes(t))
    }

    /// The proxy triangles placed at `t` and projected for `camera`, for band-wise
    /// rasterization fused with the per-pixel work.
    pub(crate) fn project(&self, camera: &Camera, t: f32) -> crate::raster::Projected {
        crate::raster::project(camera, &self.placed_meshes(t))
    }

    /// (pack id, object-to-world transform at `t`, mesh) of every object.
    fn placed_meshes(&self, t: f32) -> Vec<(u32, Affine3A, &Mesh)> {
        self.scene
            .objects
            .iter()
            .enumerate()
            .map(|(i, o)| {
                (
                    self.pack_ids[i],
                    self.scene.object_transform(i as u32, t),
                    &self.scene.meshes[o.mesh],
                )
            })
            .collect()
    }

    /// The geometry mask of `camera` over already placed geometry.
    pub fn mask_placed(&self, placed: &PlacedScene<'_>, camera: &Camera) -> GeometryMask {
        let b = camera.basis();
        let (w, h) = (camera.width as usize, camera.height as usize);
        let mut object = vec![0u32; w * h];
        let mut position = vec![Vec3::ZERO; w * h];
        let mut depth = vec![f32::INFINITY; w * h];
        object
            .par_chunks_mut(w)
            .zip(position.par_chunks_mut(w))
            .zip(depth.par_chunks_mut(w))
            .enumerate()
            .for_each(|(y, ((o, p), d))| {
                for x in 0..w {
                    let dir = b.direction(x as f32 + 0.5, y as f32 + 0.5);
                    if let Some(hit) = placed.intersect(&Ray::new(b.position, dir)) {
                        o[x] = self.pack_ids.get(hit.object as usize).copied().unwrap_or(0);
                        p[x] = hit.position;
                        d[x] = hit.distance;
                    }
                }
            });
        GeometryMask {
            width: camera.width,
            height: camera.height,
            object,
            position,
            depth,
        }
    }
}

/// What the proxy geometry shows through every pixel's centre.
#[derive(Clone, Debug, PartialEq)]
pub struct GeometryMask {
    /// Width, pixels.
    pub width: u32,
    /// Height, pixels.
    pub height: u32,
    /// Pack object id per pixel (0: no proxy geometry).
    pub object: Vec<u32>,
    /// World hit point per pixel (zero where none).
    pub position: Vec<Vec3>,
    /// Distance from the eye along the ray (∞ where none).
    pub depth: Vec<f32>,
}
