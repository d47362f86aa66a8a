//! The geometry mask by ray casting: one primary ray per pixel centre through the tracer's
//! two-level BVH over the pack's proxy geometry. It is the reference the runtime's
//! rasterized mask ([`plenoptic_recon::ProxyGeometry::mask_raster`]) is tested against, and
//! [`plenoptic_recon::Reconstructor::render_with_mask`] reconstructs from it.
//!
//! The proxies become a [`Scene`] ([`proxy_scene`]) with one root node per object whose
//! track is the object's pack track converted to the scene crate's type; the tracer builds
//! one BVH per object once ([`RayCastMask::new`]) and rebuilds only the top level per frame.
//! The scene is borrowed, so the caller keeps it alive:
//!
//! ```text
//! let scene = proxy_scene(proxy);
//! let caster = RayCastMask::new(&scene, proxy)?;
//! let mask = caster.mask(&camera, t);
//! ```

use glam::Vec3;
use plenoptic_pack::{Interpolation as PackInterp, Track as PackTrack};
use plenoptic_recon::{Camera, GeometryMask, ObjectMotion, ProxyGeometry};
use plenoptic_scene::{Interpolation, Key, Mesh, Node, Object, Scene, Track, Trs, TrsTrack};
use plenoptic_trace::{PlacedScene, Ray, SceneAccel};
use rayon::prelude::*;

use crate::Result;

/// Converts one pack track into the scene crate's track type (None for an empty or
/// malformed track).
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

/// An object's motion as the scene crate's node track.
pub fn trs_track(motion: &ObjectMotion) -> TrsTrack {
    let tracks = motion.tracks();
    TrsTrack {
        translation: tracks.translation.and_then(convert_track),
        rotation: tracks.rotation.and_then(convert_track),
        scale: tracks.scale.and_then(convert_track),
    }
}

/// The proxy geometry as a traceable scene: one root node and object per proxy, in the order
/// of [`ProxyGeometry::object_ids`], with one grey diffuse material.
pub fn proxy_scene(proxy: &ProxyGeometry) -> Scene {
    let mut scene = Scene::default();
    scene
        .materials
        .push(plenoptic_trace::shapes::diffuse(Vec3::splat(0.5)));
    for ((&id, mesh), motion) in proxy
        .object_ids()
        .iter()
        .zip(proxy.meshes())
        .zip(proxy.motions())
    {
        scene.meshes.push(Mesh {
            positions: mesh.positions.clone(),
            normals: Vec::new(),
            uvs: Vec::new(),
            tangents: Vec::new(),
            colors: Vec::new(),
            triangles: mesh.triangles.clone(),
        });
        let name = format!("proxy{id}");
        scene.nodes.push(Node {
            name: name.clone(),
            parent: None,
            rest: Trs::default(),
            track: motion.as_ref().map(trs_track),
        });
        scene.objects.push(Object {
            node_path: format!("/{name}"),
            name,
            node: scene.nodes.len() - 1,
            mesh: scene.meshes.len() - 1,
            material: 0,
        });
    }
    scene
}

/// Ray-cast geometry masks of one pack's proxies.
pub struct RayCastMask<'s> {
    accel: SceneAccel<'s>,
    /// Pack object id per scene object.
    pack_ids: Vec<u32>,
}

impl std::fmt::Debug for RayCastMask<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RayCastMask")
            .field("objects", &self.pack_ids)
            .finish()
    }
}

impl<'s> RayCastMask<'s> {
    /// Builds the BVH of every object of `scene`, which must be [`proxy_scene`]`(proxy)`.
    /// Fails when the proxies have no triangle.
    pub fn new(scene: &'s Scene, proxy: &ProxyGeometry) -> Result<Self> {
        Ok(RayCastMask {
            accel: SceneAccel::new(scene)?,
            pack_ids: proxy.object_ids().to_vec(),
        })
    }

    /// The proxies placed at time `t`.
    pub fn at_time(&'s self, t: f32) -> PlacedScene<'s> {
        self.accel.at_time(t)
    }

    /// The geometry mask of `camera` at time `t`.
    pub fn mask(&'s self, camera: &Camera, t: f32) -> GeometryMask {
        self.mask_placed(&self.at_time(t), camera)
    }

    /// The geometry mask of `camera` over already placed proxies.
    pub fn mask_placed(&self, placed: &PlacedScene<'_>, camera: &Camera) -> GeometryMask {
        let b = camera.basis();
        let w = camera.width as usize;
        let mut mask = GeometryMask::empty(camera.width, camera.height);
        mask.object
            .par_chunks_mut(w)
            .zip(mask.position.par_chunks_mut(w))
            .zip(mask.depth.par_chunks_mut(w))
            .zip(mask.normal.par_chunks_mut(w))
            .enumerate()
            .for_each(|(y, (((o, p), d), n))| {
                for x in 0..w {
                    let dir = b.direction(x as f32 + 0.5, y as f32 + 0.5);
                    if let Some(hit) = placed.intersect(&Ray::new(b.position, dir)) {
                        o[x] = self.pack_ids.get(hit.object as usize).copied().unwrap_or(0);
                        p[x] = hit.position;
                        d[x] = hit.distance;
                        n[x] = hit.geometric_normal;
                    }
                }
            });
        mask
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Quat;
    use plenoptic_pack::ObjectTracks;

    /// The runtime's own track evaluation and the scene crate's (which the baker placed the
    /// objects with) give the same transforms for every interpolation.
    #[test]
    fn runtime_motion_matches_the_scene_crate() {
        let v = |x: f32, y: f32| Vec3::new(x, y, 0.5 * x);
        let tracks = ObjectTracks {
            object_id: 3,
            translation: Some(PackTrack {
                interpolation: PackInterp::CubicSpline,
                times: vec![0.0, 0.7, 2.0],
                values: vec![
                    v(0.0, 1.0),
                    v(0.0, 0.0),
                    v(1.0, 0.0),
                    v(-1.0, 2.0),
                    v(1.0, 1.0),
                    v(0.5, 0.5),
                    v(0.0, 0.0),
                    v(3.0, -1.0),
                    v(2.0, 1.0),
                ],
            }),
            rotation: Some(PackTrack {
                interpolation: PackInterp::Linear,
                times: vec![0.0, 1.0, 2.0],
                values: vec![
                    Quat::IDENTITY,
                    Quat::from_rotation_y(1.2),
                    Quat::from_rotation_x(-0.7),
                ],
            }),
            scale: Some(PackTrack {
                interpolation: PackInterp::Step,
                times: vec![0.0, 1.5],
                values: vec![Vec3::ONE, Vec3::new(2.0, 1.0, 0.5)],
            }),
        };
        let motion = ObjectMotion::new(&tracks);
        let scene_track = trs_track(&motion);
        for i in 0..=50 {
            let t = -0.2 + 2.4 * i as f32 / 50.0;
            let ours = motion.transform(t);
            let theirs = scene_track.sample(t, Trs::default()).to_affine();
            assert!(
                ours.to_cols_array()
                    .iter()
                    .zip(theirs.to_cols_array())
                    .all(|(a, b)| (a - b).abs() < 1e-5),
                "t = {t}: {ours:?} vs {theirs:?}"
            );
        }
    }
}
