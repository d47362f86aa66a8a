//! One flat BVH over every world-space triangle with obvhs's own triangle test: no instances,
//! no transforms, no alpha test. The benchmark measures the two-level structure against it.

use glam::{Vec3, Vec3A};
use obvhs::{
    cwbvh::CwBvh,
    ray::{Ray as BvhRay, RayHit},
    triangle::Triangle,
};

use super::blas::build_bvh;
use super::{PlacedScene, Ray};

/// A single obvhs CWBVH over the placed scene's triangles in world space.
#[derive(Debug, Clone)]
pub struct FlatBvh {
    bvh: CwBvh,
    triangles: Vec<Triangle>,
}

impl FlatBvh {
    /// Flattens `placed` into world-space triangles and builds one BVH over them.
    pub fn new(placed: &PlacedScene<'_>) -> Self {
        let scene = placed.scene();
        let mut tris = Vec::new();
        for (id, object) in scene.objects.iter().enumerate() {
            let m = placed.object_transform(id as u32);
            let mesh = &scene.meshes[object.mesh];
            for t in &mesh.triangles {
                let [v0, v1, v2] =
                    t.map(|i| m.transform_point3a(mesh.positions[i as usize].into()));
                tris.push(Triangle { v0, v1, v2 });
            }
        }
        let (bvh, triangles) = build_bvh(&tris, |_, t| *t);
        Self { bvh, triangles }
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// Distance to the closest triangle along `ray`.
    pub fn closest(&self, ray: &Ray) -> Option<f32> {
        let r = BvhRay::new(
            Vec3A::from(ray.origin),
            Vec3A::from(ray.direction) + Vec3A::ZERO,
            0.0,
            ray.tmax,
        );
        let mut hit = RayHit::none();
        self.bvh
            .ray_traverse(r, &mut hit, |r, i| self.triangles[i].intersect(r))
            .then_some(hit.t)
    }

    /// Whether anything lies along `ray` before `ray.tmax`.
    pub fn occluded(&self, ray: &Ray) -> bool {
        let r = BvhRay::new(
            Vec3A::from(ray.origin),
            Vec3A::from(ray.direction) + Vec3A::ZERO,
            0.0,
            ray.tmax,
        );
        !self
            .bvh
            .ray_traverse_miss(r, |r, i| self.triangles[i].intersect(r))
    }

    /// World bounds (min, max).
    pub fn bounds(&self) -> (Vec3, Vec3) {
        (
            self.bvh.total_aabb.min.into(),
            self.bvh.total_aabb.max.into(),
        )
    }
}
