//! Acceleration structures: a BVH per mesh in object space ([`SceneAccel`], built once) and a
//! top level over the objects placed at time t ([`PlacedScene`], rebuilt per time).
//!
//! Rigid animation therefore costs only a top-level rebuild over the instance bounds (docs/architecture.md,
//! Baking step 2). Rays are carried into object space by each instance's inverse transform
//! without renormalising the direction, so hit distances stay world distances.

mod blas;
mod flat;

pub use blas::Blas;
pub use flat::FlatBvh;

use glam::{Affine3A, Mat3, Vec2, Vec3, Vec3A};
use obvhs::{
    BvhBuildParams,
    aabb::Aabb,
    cwbvh::{CwBvh, builder::build_cwbvh},
    ray::{Ray as BvhRay, RayHit},
};
use plenoptic_scene::{NO_OBJECT, ObjectId, Scene};
use std::time::Duration;

use crate::alpha::{AlphaTest, accepts};
use crate::camera::Camera;
use crate::environment::EnvTableCache;
use crate::image::Image;
use crate::light::LightSet;
use crate::texture::sample_ref;
use crate::{Result, TraceError};

/// A world-space ray: origin, unit direction and the largest distance of interest.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ray {
    /// Start point.
    pub origin: Vec3,
    /// Unit direction.
    pub direction: Vec3,
    /// Hits at or beyond this distance are ignored.
    pub tmax: f32,
}

impl Ray {
    /// An unbounded ray.
    pub fn new(origin: Vec3, direction: Vec3) -> Self {
        Self {
            origin,
            direction,
            tmax: f32::INFINITY,
        }
    }
}

/// The closest surface a ray meets.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    /// Distance along the ray.
    pub distance: f32,
    /// The object hit.
    pub object: ObjectId,
    /// Index of the triangle in the object's mesh.
    pub triangle: u32,
    /// Barycentric weights (b1, b2) of the triangle's second and third vertex.
    pub barycentrics: Vec2,
    /// World position.
    pub position: Vec3,
    /// Unit world geometric normal, oriented by the triangle's winding (counter-clockwise front).
    pub geometric_normal: Vec3,
    /// Unit world shading normal: interpolated vertex normal, normal-mapped, in the same
    /// hemisphere as `geometric_normal`.
    pub shading_normal: Vec3,
    /// Texture coordinates (zero when the mesh has none).
    pub uv: Vec2,
    /// Whether the ray arrived on the front side (against `geometric_normal`).
    pub front_face: bool,
}

impl Hit {
    /// A point just off the surface on the side `direction` leaves to, for spawning rays.
    pub fn offset_origin(&self, direction: Vec3) -> Vec3 {
        let n = self.geometric_normal;
        let eps = 1e-4 * (1.0 + self.position.abs().max_element());
        if direction.dot(n) >= 0.0 {
            self.position + n * eps
        } else {
            self.position - n * eps
        }
    }
}

/// BLASes of every mesh of a scene; build once, place at any time with [`SceneAccel::at_time`].
#[derive(Debug, Clone)]
pub struct SceneAccel<'s> {
    scene: &'s Scene,
    blas: Vec<Option<Blas>>,
    /// Per object id, how its hits are alpha-tested.
    alpha: Vec<AlphaTest>,
    /// The environment's sampling tables, shared by placements at nearby times.
    env_tables: EnvTableCache,
}

/// One object placed in the world.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Instance {
    pub object: ObjectId,
    pub mesh: usize,
    pub to_world: Affine3A,
    pub to_object: Affine3A,
    pub normal_matrix: Mat3,
}

/// The scene placed at one time: instance transforms, a top-level BVH and the lights.
#[derive(Debug)]
pub struct PlacedScene<'a> {
    accel: &'a SceneAccel<'a>,
    time: f32,
    tlas: CwBvh,
    /// Instances in TLAS primitive order.
    instances: Vec<Instance>,
    /// Per object id, the index into `instances` (usize::MAX for objects without triangles).
    instance_of: Vec<usize>,
    lights: LightSet,
    bounds: (Vec3, Vec3),
}

impl<'s> SceneAccel<'s> {
    /// Builds the bottom-level BVH of every mesh. Fails on a scene without any triangle.
    pub fn new(scene: &'s Scene) -> Result<Self> {
        let blas: Vec<Option<Blas>> = {
            use rayon::prelude::*;
            scene.meshes.par_iter().map(Blas::new).collect()
        };
        let drawable = scene
            .objects
            .iter()
            .any(|o| blas.get(o.mesh).is_some_and(Option::is_some));
        if !drawable {
            return Err(TraceError::EmptyScene);
        }
        let alpha = AlphaTest::per_object(scene);
        Ok(Self {
            scene,
            blas,
            alpha,
            env_tables: EnvTableCache::default(),
        })
    }

    /// The scene.
    pub fn scene(&self) -> &'s Scene {
        self.scene
    }

    /// Places the objects at time `t`: computes transforms, builds the top level and the light
    /// set; the bottom levels are reused.
    pub fn at_time(&'s self, t: f32) -> PlacedScene<'s> {
        let scene = self.scene;
        let mut instances = Vec::new();
        let mut aabbs = Vec::new();
        for (id, object) in scene.objects.iter().enumerate() {
            let Some(Some(blas)) = self.blas.get(object.mesh) else {
                continue;
            };
            let to_world = scene.object_transform(id as ObjectId, t);
            let (lo, hi) = blas.bounds;
            let mut aabb = Aabb::empty();
            for c in 0..8 {
                let corner = Vec3::new(
                    if c & 1 == 0 { lo.x } else { hi.x },
                    if c & 2 == 0 { lo.y } else { hi.y },
                    if c & 4 == 0 { lo.z } else { hi.z },
                );
                aabb.extend(to_world.transform_point3a(corner.into()));
            }
            aabbs.push(aabb);
            instances.push(Instance {
                object: id as ObjectId,
                mesh: object.mesh,
                to_world,
                to_object: to_world.inverse(),
                normal_matrix: Mat3::from(to_world.matrix3).inverse().transpose(),
            });
        }
        debug_assert!(!instances.is_empty(), "SceneAccel::new checks for geometry");
        let tlas = build_cwbvh(
            &aabbs,
            BvhBuildParams::fast_build(),
            &mut Duration::default(),
        );
        let instances: Vec<Instance> = tlas
            .primitive_indices
            .iter()
            .map(|&i| instances[i as usize])
            .collect();
        let mut instance_of = vec![usize::MAX; scene.objects.len()];
        for (i, inst) in instances.iter().enumerate() {
            instance_of[inst.object as usize] = i;
        }
        let bounds = aabbs.iter().fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(lo, hi), a| (lo.min(a.min.into()), hi.max(a.max.into())),
        );
        let lights = LightSet::new(scene, t, &instances, self.env_tables.light(scene, t));
        PlacedScene {
            accel: self,
            time: t,
            tlas,
            instances,
            instance_of,
            lights,
            bounds,
        }
    }
}

impl<'a> PlacedScene<'a> {
    /// The scene.
    pub fn scene(&self) -> &'a Scene {
        self.accel.scene
    }

    /// The time the scene is placed at.
    pub fn time(&self) -> f32 {
        self.time
    }

    /// World bounds (min, max) of the placed geometry.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        self.bounds
    }

    /// The lights at this time.
    pub fn lights(&self) -> &LightSet {
        &self.lights
    }

    /// Object-to-world transform of `object` at this time (identity for objects without
    /// geometry).
    pub fn object_transform(&self, object: ObjectId) -> Affine3A {
        match self.instance_of.get(object as usize) {
            Some(&i) if i != usize::MAX => self.instances[i].to_world,
            _ => Affine3A::IDENTITY,
        }
    }

    /// The closest hit along `ray`, if any. Hits that the material's alpha removes (glTF MASK
    /// below the cutoff, BLEND by coverage; see [`crate::alpha`]) are passed through.
    pub fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let origin = Vec3A::from(ray.origin);
        // −0.0 components would disagree with obvhs's sign tests (its safe inverse keeps the sign
        // of zero, its octant test does not); adding +0.0 turns them into +0.0.
        let dir = Vec3A::from(ray.direction) + Vec3A::ZERO;
        let tlas_ray = BvhRay::new(origin, dir, 0.0, ray.tmax);
        let mut rh = RayHit::none();
        let mut best: Option<(usize, blas::BlasHit)> = None;
        self.tlas.ray_traverse(tlas_ray, &mut rh, |r, slot| {
            let inst = &self.instances[slot];
            let Some(blas) = &self.accel.blas[inst.mesh] else {
                return f32::INFINITY;
            };
            let o = inst.to_object.transform_point3a(r.origin);
            let d = inst.to_object.transform_vector3a(r.direction);
            let hit = match self.accel.alpha[inst.object as usize] {
                AlphaTest::Opaque => blas.closest(o, d, r.tmax, |_, _| true),
                test => blas.closest(o, d, r.tmax, |tri, bary| {
                    self.accepts(test, inst, tri, bary, ray)
                }),
            };
            match hit {
                Some(h) => {
                    best = Some((slot, h));
                    h.t
                }
                None => f32::INFINITY,
            }
        });
        let (slot, h) = best?;
        Some(self.make_hit(ray, &self.instances[slot], h))
    }

    /// Whether anything lies along `ray` before `ray.tmax`, with the same alpha test as
    /// [`PlacedScene::intersect`].
    pub fn occluded(&self, ray: &Ray) -> bool {
        let origin = Vec3A::from(ray.origin);
        // −0.0 components would disagree with obvhs's sign tests (its safe inverse keeps the sign
        // of zero, its octant test does not); adding +0.0 turns them into +0.0.
        let dir = Vec3A::from(ray.direction) + Vec3A::ZERO;
        let tlas_ray = BvhRay::new(origin, dir, 0.0, ray.tmax);
        !self.tlas.ray_traverse_miss(tlas_ray, |r, slot| {
            let inst = &self.instances[slot];
            let Some(blas) = &self.accel.blas[inst.mesh] else {
                return f32::INFINITY;
            };
            let o = inst.to_object.transform_point3a(r.origin);
            let d = inst.to_object.transform_vector3a(r.direction);
            let blocked = match self.accel.alpha[inst.object as usize] {
                AlphaTest::Opaque => blas.occluded(o, d, r.tmax, |_, _| true),
                test => blas.occluded(o, d, r.tmax, |tri, bary| {
                    self.accepts(test, inst, tri, bary, ray)
                }),
            };
            if blocked { 0.0 } else { f32::INFINITY }
        })
    }

    /// Whether a candidate hit of world ray `ray` on `inst` survives the alpha test.
    #[inline]
    fn accepts(
        &self,
        test: AlphaTest,
        inst: &Instance,
        triangle: u32,
        bary: Vec2,
        ray: &Ray,
    ) -> bool {
        let scene = self.accel.scene;
        accepts(
            test,
            scene,
            inst.object,
            &scene.meshes[inst.mesh],
            triangle,
            bary,
            ray.origin,
            ray.direction,
        )
    }

    /// Whether the segment from `a` to `b` is blocked (both ends excluded by a small margin).
    pub fn segment_occluded(&self, a: Vec3, b: Vec3) -> bool {
        let d = b - a;
        let len = d.length();
        if len <= 0.0 {
            return false;
        }
        let eps = 1e-4 * (1.0 + b.abs().max_element());
        self.occluded(&Ray {
            origin: a,
            direction: d / len,
            tmax: (len - eps).max(0.0),
        })
    }

    fn make_hit(&self, ray: &Ray, inst: &Instance, h: blas::BlasHit) -> Hit {
        let scene = self.accel.scene;
        let mesh = &scene.meshes[inst.mesh];
        let tri = mesh.triangles[h.triangle as usize];
        let [i0, i1, i2] = tri.map(|i| i as usize);
        let (b1, b2) = (h.bary.x, h.bary.y);
        let b0 = 1.0 - b1 - b2;
        let p0 = mesh.positions[i0];
        let local_ng = (mesh.positions[i1] - p0).cross(mesh.positions[i2] - p0);
        let ng = (inst.normal_matrix * local_ng).normalize_or(Vec3::Z);
        let interp = |a: Vec3, b: Vec3, c: Vec3| a * b0 + b * b1 + c * b2;
        let mut ns = if mesh.normals.len() == mesh.positions.len() {
            let n = interp(mesh.normals[i0], mesh.normals[i1], mesh.normals[i2]);
            (inst.normal_matrix * n).normalize_or(ng)
        } else {
            ng
        };
        let uv = if mesh.uvs.len() == mesh.positions.len() {
            mesh.uvs[i0] * b0 + mesh.uvs[i1] * b1 + mesh.uvs[i2] * b2
        } else {
            Vec2::ZERO
        };
        let material = &scene.materials[scene.objects[inst.object as usize].material];
        if let (Some(tex), true) = (
            material.normal_texture,
            mesh.tangents.len() == mesh.positions.len(),
        ) {
            let t4 = mesh.tangents[i0] * b0 + mesh.tangents[i1] * b1 + mesh.tangents[i2] * b2;
            let t = inst.to_world.transform_vector3(t4.truncate());
            let t = (t - ns * ns.dot(t)).normalize_or_zero();
            if t != Vec3::ZERO {
                // The bitangent's handedness, flipped by a mirroring placement: the cross
                // product of mirrored vectors is the mirror of theirs, negated (glTF's
                // MikkTSpace tangents; Bevy's `mesh_tangent_local_to_world` does the same).
                let mut sign = if mesh.tangents[i0].w < 0.0 { -1.0 } else { 1.0 };
                if inst.to_world.matrix3.determinant() < 0.0 {
                    sign = -sign;
                }
                let b = ns.cross(t) * sign;
                let m = sample_ref(scene, &tex, uv);
                let s = material.normal_scale;
                let local = Vec3::new(
                    (m.x * 2.0 - 1.0) * s,
                    (m.y * 2.0 - 1.0) * s,
                    m.z * 2.0 - 1.0,
                );
                ns = (t * local.x + b * local.y + ns * local.z).normalize_or(ns);
            }
        }
        if ns.dot(ng) < 0.0 {
            ns = -ns;
        }
        Hit {
            distance: h.t,
            object: inst.object,
            triangle: h.triangle,
            barycentrics: h.bary,
            position: ray.origin + ray.direction * h.t,
            geometric_normal: ng,
            shading_normal: ns,
            uv,
            front_face: ray.direction.dot(ng) < 0.0,
        }
    }

    /// The object id seen through the centre of every pixel ([`NO_OBJECT`] for misses).
    pub fn id_image(&self, camera: &(impl Camera + ?Sized)) -> Image<ObjectId> {
        let (w, h) = camera.resolution();
        Image::render(w, h, |x, y| {
            camera
                .ray(x, y, Vec2::splat(0.5))
                .and_then(|r| self.intersect(&r))
                .map_or(NO_OBJECT, |hit| hit.object)
        })
    }

    /// The placed instance of `object`, if it has geometry.
    pub(crate) fn instance(&self, object: ObjectId) -> Option<&Instance> {
        match self.instance_of.get(object as usize) {
            Some(&i) if i != usize::MAX => Some(&self.instances[i]),
            _ => None,
        }
    }
}
