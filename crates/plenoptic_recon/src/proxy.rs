//! Proxy geometry and the geometry mask (thesis §8.2.3: "geometry masks").
//!
//! The pack's proxy meshes (object space) and animation tracks are kept per object with
//! their [`ObjectMotion`]; every frame places them at t. The *geometry mask* gives per pixel
//! the object id (the pack's id; 0 where no proxy is hit), the hit point and its distance,
//! by rasterizing the placed triangles ([`ProxyGeometry::mask_raster`], what the GPU mask
//! pass does). The offline crate `plenoptic_eval` casts one ray per pixel through the
//! tracer's BVH over the same triangles instead (its `mask` module, the reference the
//! raster mask is tested against) and hands that mask to
//! [`crate::Reconstructor::render_with_mask`].
//!
//! Conventions: an object whose tracks are absent is placed by the identity (its proxy mesh
//! is then in world space); a track that lacks a channel uses the identity for it.

use std::collections::HashMap;

use glam::{Affine3A, Vec3};
use plenoptic_pack::{AnimationTracks, PackReader};

use crate::camera::Camera;
use crate::motion::ObjectMotion;

/// A triangle mesh in object space, as the geometry mask places it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriangleMesh {
    /// Vertex positions, object space.
    pub positions: Vec<Vec3>,
    /// Triangles as vertex indices (checked against `positions` on construction).
    pub triangles: Vec<[u32; 3]>,
    /// Vertex normals, object space (empty when the pack has none for the mesh, or a count
    /// that disagrees with the positions).
    pub normals: Vec<Vec3>,
}

impl TriangleMesh {
    /// The triangles of a pack proxy mesh; triangles with an index outside the positions
    /// are dropped (a pack is untrusted input).
    pub fn from_pack(mesh: &plenoptic_pack::ProxyMesh) -> Self {
        let n = mesh.positions.len();
        TriangleMesh {
            positions: mesh.positions.clone(),
            triangles: mesh
                .indices
                .chunks_exact(3)
                .map(|c| [c[0], c[1], c[2]])
                .filter(|t| t.iter().all(|&i| (i as usize) < n))
                .collect(),
            normals: mesh
                .normals
                .as_ref()
                .filter(|v| v.len() == n)
                .cloned()
                .unwrap_or_default(),
        }
    }
}

/// One object's proxy geometry as a pack stores it: the object-space mesh and the object's
/// motion, ready to be evaluated at any time.
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
    pub track: Option<ObjectMotion>,
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
            .map(ObjectMotion::new);
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

/// The pack's proxy geometry: one mesh and motion per object.
pub struct ProxyGeometry {
    /// Pack object id of each object (object index → pack id).
    pack_ids: Vec<u32>,
    meshes: Vec<TriangleMesh>,
    motions: Vec<Option<ObjectMotion>>,
    /// Pack object id → object index.
    index_of: HashMap<u32, usize>,
}

impl std::fmt::Debug for ProxyGeometry {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ProxyGeometry")
            .field("objects", &self.pack_ids)
            .finish()
    }
}

impl ProxyGeometry {
    /// Reads every proxy mesh and the tracks of `pack`. Returns the geometry (None if no
    /// proxy mesh could be read) and a description of every chunk that could not be read.
    pub fn from_pack(pack: &PackReader) -> (Option<Self>, Vec<String>) {
        let (proxies, failed) = read_proxies(pack);
        let missing: Vec<String> = failed
            .into_iter()
            .map(|(chunk, error)| format!("{chunk}: {error}"))
            .collect();
        (Self::from_proxies(&proxies), missing)
    }

    /// The geometry of `proxies` (None if there are none).
    pub fn from_proxies(proxies: &[PackProxy]) -> Option<Self> {
        if proxies.is_empty() {
            return None;
        }
        let pack_ids: Vec<u32> = proxies.iter().map(|p| p.id).collect();
        Some(ProxyGeometry {
            index_of: pack_ids
                .iter()
                .enumerate()
                .map(|(i, &id)| (id, i))
                .collect(),
            pack_ids,
            meshes: proxies
                .iter()
                .map(|p| TriangleMesh::from_pack(&p.mesh))
                .collect(),
            motions: proxies.iter().map(|p| p.track.clone()).collect(),
        })
    }

    /// Pack ids of the objects with geometry.
    pub fn object_ids(&self) -> &[u32] {
        &self.pack_ids
    }

    /// The object-space mesh of every object, in the order of [`Self::object_ids`].
    pub fn meshes(&self) -> &[TriangleMesh] {
        &self.meshes
    }

    /// The motion of every object (None: placed by the identity), in the order of
    /// [`Self::object_ids`].
    pub fn motions(&self) -> &[Option<ObjectMotion>] {
        &self.motions
    }

    /// Object-to-world transform of pack object `id` at time `t` (identity if unknown).
    pub fn transform(&self, id: u32, t: f32) -> Affine3A {
        match self.index_of.get(&id) {
            Some(&i) => self.transform_of(i, t),
            None => Affine3A::IDENTITY,
        }
    }

    fn transform_of(&self, index: usize, t: f32) -> Affine3A {
        self.motions[index]
            .as_ref()
            .map_or(Affine3A::IDENTITY, |m| m.transform(t))
    }

    /// The geometry mask of `camera` at time `t` by rasterizing the placed proxy triangles
    /// (what the GPU mask pass does). See the `raster` module.
    pub fn mask_raster(&self, camera: &Camera, t: f32) -> GeometryMask {
        crate::raster::rasterize(camera, &self.placed_meshes(t))
    }

    /// The proxy triangles placed at `t` and projected for `camera`, for band-wise
    /// rasterization fused with the per-pixel work.
    pub(crate) fn project(&self, camera: &Camera, t: f32) -> crate::raster::Projected {
        crate::raster::project(camera, &self.placed_meshes(t))
    }

    /// [`Self::project`] of the objects whose pack id `keep` accepts.
    pub(crate) fn project_only(
        &self,
        camera: &Camera,
        t: f32,
        keep: impl Fn(u32) -> bool,
    ) -> crate::raster::Projected {
        let mut placed = self.placed_meshes(t);
        placed.retain(|o| keep(o.0));
        crate::raster::project(camera, &placed)
    }

    /// (pack id, object-to-world transform at `t`, mesh) of every object.
    pub fn placed_meshes(&self, t: f32) -> Vec<(u32, Affine3A, &TriangleMesh)> {
        (0..self.pack_ids.len())
            .map(|i| (self.pack_ids[i], self.transform_of(i, t), &self.meshes[i]))
            .collect()
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
    /// The surface's geometric normal per pixel (world, unit, either side; zero where none or
    /// unknown, which leaves the lookups' face test out there).
    pub normal: Vec<Vec3>,
}

impl GeometryMask {
    /// A `width` × `height` mask in which no pixel sees proxy geometry.
    pub fn empty(width: u32, height: u32) -> Self {
        let n = width as usize * height as usize;
        Self {
            width,
            height,
            object: vec![0; n],
            position: vec![Vec3::ZERO; n],
            depth: vec![f32::INFINITY; n],
            normal: vec![Vec3::ZERO; n],
        }
    }
}
