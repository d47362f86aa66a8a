//! The bottom level: one BVH per mesh, in object space, built once.

use glam::{Vec2, Vec3, Vec3A};
use obvhs::{
    BvhBuildParams,
    cwbvh::{CwBvh, builder::build_cwbvh_from_tris},
    ray::{Ray as BvhRay, RayHit},
    triangle::Triangle,
};
use plenoptic_scene::Mesh;
use std::time::Duration;

/// A CWBVH over `tris` (obvhs's medium-quality build) and its triangles in BVH order, each
/// made by `triangle(index in tris, triangle)`.
pub(crate) fn build_bvh<T>(
    tris: &[Triangle],
    triangle: impl Fn(u32, &Triangle) -> T,
) -> (CwBvh, Vec<T>) {
    let bvh = build_cwbvh_from_tris(
        tris,
        BvhBuildParams::medium_build(),
        &mut Duration::default(),
    );
    let triangles = bvh
        .primitive_indices
        .iter()
        .map(|&i| triangle(i, &tris[i as usize]))
        .collect();
    (bvh, triangles)
}

/// A triangle in BVH order with the index of the triangle it came from.
#[derive(Debug, Clone, Copy)]
pub(crate) struct BlasTriangle {
    pub v0: Vec3A,
    pub e1: Vec3A,
    pub e2: Vec3A,
    pub index: u32,
}

/// How far outside [0, 1] a barycentric may fall and still count: rounding makes a ray that
/// meets the edge shared by two triangles exactly (a camera looking straight down at the
/// diagonal of a square) miss both without it.
const EDGE_EPS: f32 = 1e-6;

/// Möller–Trumbore: returns (t, b1, b2) with the hit at v0 + b1·e1 + b2·e2, both faces; a
/// hit within [`EDGE_EPS`] of an edge counts, so neighbouring triangles leave no crack.
#[inline(always)]
pub(crate) fn intersect_triangle(
    v0: Vec3A,
    e1: Vec3A,
    e2: Vec3A,
    origin: Vec3A,
    dir: Vec3A,
    tmin: f32,
    tmax: f32,
) -> Option<(f32, f32, f32)> {
    let p = dir.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-20 {
        return None;
    }
    let inv = 1.0 / det;
    let s = origin - v0;
    let b1 = s.dot(p) * inv;
    if !(-EDGE_EPS..=1.0 + EDGE_EPS).contains(&b1) {
        return None;
    }
    let q = s.cross(e1);
    let b2 = dir.dot(q) * inv;
    if b2 < -EDGE_EPS || b1 + b2 > 1.0 + EDGE_EPS {
        return None;
    }
    let t = e2.dot(q) * inv;
    (t > tmin && t < tmax).then_some((t, b1, b2))
}

/// An object-space BVH over one mesh.
#[derive(Debug, Clone)]
pub struct Blas {
    pub(crate) bvh: CwBvh,
    pub(crate) triangles: Vec<BlasTriangle>,
    /// Object-space bounds (min, max).
    pub(crate) bounds: (Vec3, Vec3),
}

/// The closest triangle a ray meets in one BLAS.
#[derive(Debug, Clone, Copy)]
pub(crate) struct BlasHit {
    pub t: f32,
    pub triangle: u32,
    pub bary: Vec2,
}

impl Blas {
    /// Builds the BVH of `mesh`; `None` for a mesh without triangles.
    pub fn new(mesh: &Mesh) -> Option<Self> {
        if mesh.triangles.is_empty() {
            return None;
        }
        let tris: Vec<Triangle> = mesh
            .triangles
            .iter()
            .map(|t| Triangle {
                v0: mesh.positions[t[0] as usize].into(),
                v1: mesh.positions[t[1] as usize].into(),
                v2: mesh.positions[t[2] as usize].into(),
            })
            .collect();
        let (bvh, triangles) = build_bvh(&tris, |i, t| BlasTriangle {
            v0: t.v0,
            e1: t.v1 - t.v0,
            e2: t.v2 - t.v0,
            index: i,
        });
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for p in &mesh.positions {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
        Some(Self {
            bvh,
            triangles,
            bounds: (lo, hi),
        })
    }

    /// Closest hit of an object-space ray (direction not necessarily unit; t in its units)
    /// among the candidates `accept(triangle, barycentrics)` keeps: a rejected candidate is no
    /// hit and traversal goes on past it (an any-hit filter; each triangle is tested once).
    #[inline]
    pub(crate) fn closest(
        &self,
        origin: Vec3A,
        dir: Vec3A,
        tmax: f32,
        mut accept: impl FnMut(u32, Vec2) -> bool,
    ) -> Option<BlasHit> {
        let ray = BvhRay::new(origin, dir + Vec3A::ZERO, 0.0, tmax);
        let mut hit = RayHit::none();
        let mut best: Option<BlasHit> = None;
        self.bvh.ray_traverse(ray, &mut hit, |r, slot| {
            let tri = &self.triangles[slot];
            match intersect_triangle(tri.v0, tri.e1, tri.e2, r.origin, r.direction, 0.0, r.tmax) {
                Some((t, b1, b2)) if accept(tri.index, Vec2::new(b1, b2)) => {
                    best = Some(BlasHit {
                        t,
                        triangle: tri.index,
                        bary: Vec2::new(b1, b2),
                    });
                    t
                }
                _ => f32::INFINITY,
            }
        });
        best
    }

    /// Whether any triangle that `accept(triangle, barycentrics)` keeps lies along the ray
    /// before `tmax`.
    #[inline]
    pub(crate) fn occluded(
        &self,
        origin: Vec3A,
        dir: Vec3A,
        tmax: f32,
        mut accept: impl FnMut(u32, Vec2) -> bool,
    ) -> bool {
        let ray = BvhRay::new(origin, dir + Vec3A::ZERO, 0.0, tmax);
        !self.bvh.ray_traverse_miss(ray, |r, slot| {
            let tri = &self.triangles[slot];
            match intersect_triangle(tri.v0, tri.e1, tri.e2, r.origin, r.direction, 0.0, r.tmax) {
                Some((t, b1, b2)) if accept(tri.index, Vec2::new(b1, b2)) => t,
                _ => f32::INFINITY,
            }
        })
    }
}
