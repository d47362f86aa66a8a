//! Shadow rays against the pack's proxy geometry (pack 3's runtime sun, docs/architecture.md,
//! "The runtime sun"; thesis ch. 5: direct light computed apart from indirect light, at its
//! own accuracy).
//!
//! Objects that never move share one BVH over their world-space triangles, built once. Each
//! animated object has a BVH of its own in object space; a ray is moved into the object's
//! space at the frame's time, after a test against the object's bounds placed then. BVHs are
//! obvhs's compressed wide BVHs with its own ray–triangle test (both faces), as the tracer's
//! flat BVH uses them.
//!
//! Every proxy triangle blocks light, transmissive glass included, as in the tracer's shadow
//! rays, except the surfaces of see-through objects (glTF `alphaMode: BLEND`, the pack's
//! [`plenoptic_pack::ObjectEntry::coverage`] c): the tracer's shadow ray meets such a surface
//! with probability c and passes with 1 − c, so [`PlacedShadows::transmittance`] lets
//! `Π (1 − c)` through over the see-through surfaces a ray crosses before anything opaque (a
//! pane modelled as a thin box: two surfaces, 0.88² = 0.77 at c = 0.12). Alpha masks are not
//! applied (the tracer applies them; no tour object has one).

use std::time::Duration;

use glam::{Affine3A, Vec3, Vec3A};
use obvhs::{
    BvhBuildParams,
    cwbvh::{CwBvh, builder::build_cwbvh_from_tris},
    ray::{Ray, RayHit},
    triangle::Triangle,
};

use crate::proxy::ProxyGeometry;

/// (pack object id, triangle index in its mesh).
pub(crate) type TriangleTag = (u32, u32);

/// Each animated object's pack id and its triangles in object space, in mesh order.
pub(crate) type MovingTriangles = Vec<(u32, Vec<Triangle>)>;

/// A BVH and its triangles in BVH order.
struct TriangleBvh {
    bvh: CwBvh,
    triangles: Vec<Triangle>,
    /// (pack object id, triangle index in its mesh) of each triangle, in BVH order.
    tags: Vec<TriangleTag>,
    /// Bounds (min, max) of the triangles.
    bounds: (Vec3, Vec3),
}

impl TriangleBvh {
    fn new(tris: Vec<Triangle>, tags: Vec<TriangleTag>) -> Option<Self> {
        if tris.is_empty() {
            return None;
        }
        let bvh = build_cwbvh_from_tris(
            &tris,
            BvhBuildParams::medium_build(),
            &mut Duration::default(),
        );
        let (mut lo, mut hi) = (Vec3A::splat(f32::INFINITY), Vec3A::splat(f32::NEG_INFINITY));
        for t in &tris {
            lo = lo.min(t.v0).min(t.v1).min(t.v2);
            hi = hi.max(t.v0).max(t.v1).max(t.v2);
        }
        let triangles = bvh
            .primitive_indices
            .iter()
            .map(|&i| tris[i as usize])
            .collect();
        let tags = bvh
            .primitive_indices
            .iter()
            .map(|&i| tags[i as usize])
            .collect();
        Some(Self {
            bvh,
            triangles,
            tags,
            bounds: (lo.into(), hi.into()),
        })
    }

    fn occluded(&self, origin: Vec3A, dir: Vec3A, tmax: f32) -> bool {
        // −0.0 components would disagree with obvhs's sign tests; + 0.0 turns them into +0.0.
        let ray = Ray::new(origin, dir + Vec3A::ZERO, 0.0, tmax);
        !self
            .bvh
            .ray_traverse_miss(ray, |r, i| self.triangles[i].intersect(r))
    }

    /// The fraction of light the ray passes: 0 when an opaque triangle lies closer than
    /// `tmax`, else the product of `pass(object)` over the see-through triangles it crosses
    /// (`pass` is `None` for an opaque object). Stops at the first opaque triangle.
    fn transmittance(
        &self,
        origin: Vec3A,
        dir: Vec3A,
        tmax: f32,
        pass: &impl Fn(u32) -> Option<f32>,
    ) -> f32 {
        let ray = Ray::new(origin, dir + Vec3A::ZERO, 0.0, tmax);
        let mut through = 1.0;
        let open = self.bvh.ray_traverse_miss(ray, |r, i| {
            let t = self.triangles[i].intersect(r);
            if t < tmax
                && let Some(p) = pass(self.tags[i].0)
            {
                through *= p;
                return f32::INFINITY;
            }
            t
        });
        if open { through } else { 0.0 }
    }

    /// The nearest triangle within `tmax`.
    fn nearest(&self, origin: Vec3A, dir: Vec3A, tmax: f32) -> Option<ProxyHit> {
        let ray = Ray::new(origin, dir + Vec3A::ZERO, 0.0, tmax);
        let mut hit = RayHit::none();
        if !self
            .bvh
            .ray_traverse(ray, &mut hit, |r, i| self.triangles[i].intersect(r))
        {
            return None;
        }
        let (object, triangle) = *self.tags.get(hit.primitive_id as usize)?;
        Some(ProxyHit {
            t: hit.t,
            object,
            triangle,
        })
    }

    /// How many triangles the ray from `origin` along `dir` crosses closer than `tmax`.
    fn crossings(&self, origin: Vec3A, dir: Vec3A, tmax: f32) -> u32 {
        let ray = Ray::new(origin, dir + Vec3A::ZERO, 0.0, tmax);
        let mut n = 0;
        self.bvh.ray_traverse_anyhit(ray, |r, i| {
            if self.triangles[i].intersect(r) < tmax {
                n += 1;
            }
        });
        n
    }
}

/// Where a ray meets the proxies ([`PlacedShadows::nearest`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProxyHit {
    /// Distance along the ray.
    pub t: f32,
    /// Pack id of the object met.
    pub object: u32,
    /// The triangle met, an index into the object's mesh triangles.
    pub triangle: u32,
}

/// The proxies as shadow rays see them.
pub struct ShadowScene {
    fixed: Option<TriangleBvh>,
    /// (pack id, object-space BVH) of every object with motion.
    moving: Vec<(u32, TriangleBvh)>,
    /// (pack id, 1 − coverage) of every see-through object, sorted by id.
    see_through: Vec<(u32, f32)>,
}

impl std::fmt::Debug for ShadowScene {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ShadowScene")
            .field("fixed", &self.fixed.as_ref().map(|b| b.triangles.len()))
            .field("moving", &self.moving.len())
            .finish()
    }
}

/// A [`ShadowScene`] at one time: the moving objects placed.
pub struct PlacedShadows<'s> {
    scene: &'s ShadowScene,
    /// Per moving object: world → object transform and world bounds.
    moving: Vec<(Affine3A, Vec3, Vec3)>,
}

impl ShadowScene {
    /// The shadow geometry of `proxy`.
    pub fn new(proxy: &ProxyGeometry) -> Self {
        Self::of_objects(proxy, |_| true)
    }

    /// The geometry of the objects of `proxy` whose pack id `keep` accepts.
    pub fn of_objects(proxy: &ProxyGeometry, keep: impl Fn(u32) -> bool) -> Self {
        let (fixed, moving) = split_triangles(proxy, keep);
        let (fixed, tags) = fixed.into_iter().unzip();
        Self {
            fixed: TriangleBvh::new(fixed, tags),
            moving: moving
                .into_iter()
                .filter_map(|(id, tris)| {
                    let tags = (0..tris.len() as u32).map(|k| (id, k)).collect();
                    Some((id, TriangleBvh::new(tris, tags)?))
                })
                .collect(),
            see_through: Vec::new(),
        }
    }

    /// The scene with the objects of `coverage` (pack id, coverage c in [0, 1]) see-through:
    /// [`PlacedShadows::transmittance`] passes 1 − c of the light at each of their surfaces.
    pub fn with_see_through(mut self, coverage: impl IntoIterator<Item = (u32, f32)>) -> Self {
        self.see_through = coverage
            .into_iter()
            .map(|(id, c)| (id, 1.0 - c.clamp(0.0, 1.0)))
            .collect();
        self.see_through.sort_by_key(|&(id, _)| id);
        self
    }

    /// The fraction a surface of object `id` lets through, `None` for an opaque object.
    fn pass(&self, id: u32) -> Option<f32> {
        self.see_through
            .binary_search_by_key(&id, |&(i, _)| i)
            .ok()
            .map(|k| self.see_through[k].1)
    }

    /// The scene with its moving objects placed at time `t`.
    pub fn at<'s>(&'s self, proxy: &ProxyGeometry, t: f32) -> PlacedShadows<'s> {
        let moving = self
            .moving
            .iter()
            .map(|(id, b)| {
                let xf = proxy.transform(*id, t);
                let (lo, hi) = placed_bounds(xf, b.bounds);
                (xf.inverse(), lo, hi)
            })
            .collect();
        PlacedShadows {
            scene: self,
            moving,
        }
    }
}

/// How far off a surface point `p` (geometric normal `ng`, either side) a shadow ray towards
/// `wi` starts: 10⁻⁴ · (1 + |p|∞) along the normal, on `wi`'s side, as the path tracer's
/// `Hit::offset_origin` offsets it (the runtime sun's and the lamps' rays).
pub fn shadow_lift(p: Vec3, ng: Vec3, wi: Vec3) -> Vec3 {
    let eps = 1e-4 * (1.0 + p.abs().max_element());
    if wi.dot(ng) >= 0.0 {
        ng * eps
    } else {
        -ng * eps
    }
}

impl PlacedShadows<'_> {
    /// Whether anything lies along the ray from `origin` along unit `dir` closer than
    /// `tmax`.
    pub fn occluded(&self, origin: Vec3, dir: Vec3, tmax: f32) -> bool {
        let (o, d) = (Vec3A::from(origin), Vec3A::from(dir));
        if let Some(b) = &self.scene.fixed
            && b.occluded(o, d, tmax)
        {
            return true;
        }
        self.scene
            .moving
            .iter()
            .zip(&self.moving)
            .any(|((_, b), (to_object, lo, hi))| {
                ray_meets_box(origin, dir, tmax, *lo, *hi)
                    // An affine map keeps the ray parameter: t is the same in object space.
                    && b.occluded(
                        to_object.transform_point3a(o),
                        to_object.transform_vector3a(d),
                        tmax,
                    )
            })
    }

    /// The fraction of light that reaches `origin` along unit `dir` from `tmax` away: 0 when
    /// an opaque triangle lies between, else `Π (1 − c)` over the see-through surfaces crossed
    /// ([`ShadowScene::with_see_through`]; 1 when there are none). Without see-through
    /// objects it is [`PlacedShadows::occluded`] as 0 or 1, at the same cost.
    pub fn transmittance(&self, origin: Vec3, dir: Vec3, tmax: f32) -> f32 {
        if self.scene.see_through.is_empty() {
            return if self.occluded(origin, dir, tmax) {
                0.0
            } else {
                1.0
            };
        }
        let (o, d) = (Vec3A::from(origin), Vec3A::from(dir));
        let pass = |id| self.scene.pass(id);
        let mut through = self
            .scene
            .fixed
            .as_ref()
            .map_or(1.0, |b| b.transmittance(o, d, tmax, &pass));
        for ((_, b), (to_object, lo, hi)) in self.scene.moving.iter().zip(&self.moving) {
            if through == 0.0 {
                break;
            }
            if ray_meets_box(origin, dir, tmax, *lo, *hi) {
                // An affine map keeps the ray parameter: t is the same in object space.
                through *= b.transmittance(
                    to_object.transform_point3a(o),
                    to_object.transform_vector3a(d),
                    tmax,
                    &pass,
                );
            }
        }
        through
    }

    /// The nearest triangle along the ray from `origin` along unit `dir` within `tmax`
    /// (both faces count).
    pub fn nearest(&self, origin: Vec3, dir: Vec3, tmax: f32) -> Option<ProxyHit> {
        let (o, d) = (Vec3A::from(origin), Vec3A::from(dir));
        let mut best = self
            .scene
            .fixed
            .as_ref()
            .and_then(|b| b.nearest(o, d, tmax));
        for ((_, b), (to_object, lo, hi)) in self.scene.moving.iter().zip(&self.moving) {
            let reach = best.map_or(tmax, |h| h.t);
            if !ray_meets_box(origin, dir, reach, *lo, *hi) {
                continue;
            }
            // An affine map keeps the ray parameter: t is the same in object space.
            let hit = b.nearest(
                to_object.transform_point3a(o),
                to_object.transform_vector3a(d),
                reach,
            );
            best = hit.or(best);
        }
        best
    }

    /// How many triangles the ray from `origin` along unit `dir` crosses closer than `tmax`
    /// (both faces count).
    pub fn crossings(&self, origin: Vec3, dir: Vec3, tmax: f32) -> u32 {
        let (o, d) = (Vec3A::from(origin), Vec3A::from(dir));
        let fixed = self
            .scene
            .fixed
            .as_ref()
            .map_or(0, |b| b.crossings(o, d, tmax));
        let moving: u32 = self
            .scene
            .moving
            .iter()
            .zip(&self.moving)
            .filter(|(_, (_, lo, hi))| ray_meets_box(origin, dir, tmax, *lo, *hi))
            .map(|((_, b), (to_object, _, _))| {
                b.crossings(
                    to_object.transform_point3a(o),
                    to_object.transform_vector3a(d),
                    tmax,
                )
            })
            .sum();
        fixed + moving
    }
}

/// The triangles of the objects of `proxy` whose pack id `keep` accepts: those that never move
/// together in world space (each with its pack id and index in its mesh), and each animated
/// object's own in object space, in mesh order (with its pack id). Shared by the CPU's BVHs
/// and the GPU's flat layout ([`crate::flat_rays`]).
pub(crate) fn split_triangles(
    proxy: &ProxyGeometry,
    keep: impl Fn(u32) -> bool,
) -> (Vec<(Triangle, TriangleTag)>, MovingTriangles) {
    let placed = |m: &crate::proxy::TriangleMesh, xf: Affine3A| {
        object_triangles(m).into_iter().map(move |t| Triangle {
            v0: xf.transform_point3a(t.v0),
            v1: xf.transform_point3a(t.v1),
            v2: xf.transform_point3a(t.v2),
        })
    };
    let mut fixed = Vec::new();
    let mut moving = Vec::new();
    for (i, &id) in proxy.object_ids().iter().enumerate() {
        if !keep(id) {
            continue;
        }
        let mesh = &proxy.meshes()[i];
        match &proxy.motions()[i] {
            Some(m) if m.is_animated() => moving.push((id, object_triangles(mesh))),
            _ => fixed.extend(placed(mesh, proxy.transform(id, 0.0)).zip((0..).map(|k| (id, k)))),
        }
    }
    (fixed, moving)
}

/// The triangles of `mesh` in its object's space, in mesh order.
pub(crate) fn object_triangles(mesh: &crate::proxy::TriangleMesh) -> Vec<Triangle> {
    mesh.triangles
        .iter()
        .map(|t| {
            let [v0, v1, v2] = t.map(|i| mesh.positions[i as usize].into());
            Triangle { v0, v1, v2 }
        })
        .collect()
}

/// The world bounds of object-space bounds `b` moved by `xf` (its eight corners').
fn placed_bounds(xf: Affine3A, b: (Vec3, Vec3)) -> (Vec3, Vec3) {
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for k in 0..8 {
        let c = Vec3::new(
            if k & 1 == 0 { b.0.x } else { b.1.x },
            if k & 2 == 0 { b.0.y } else { b.1.y },
            if k & 4 == 0 { b.0.z } else { b.1.z },
        );
        let p = xf.transform_point3(c);
        lo = lo.min(p);
        hi = hi.max(p);
    }
    (lo, hi)
}

/// Slab test of a ray against a box.
fn ray_meets_box(origin: Vec3, dir: Vec3, tmax: f32, lo: Vec3, hi: Vec3) -> bool {
    let inv = dir.recip();
    let a = (lo - origin) * inv;
    let b = (hi - origin) * inv;
    let near = a.min(b).max_element().max(0.0);
    let far = a.max(b).min_element().min(tmax);
    // NaN (a zero direction component on the slab's plane) counts as a hit: the BVH decides.
    near <= far || near.is_nan() || far.is_nan()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_test_hits_and_misses() {
        let (lo, hi) = (Vec3::ZERO, Vec3::ONE);
        let o = Vec3::new(0.5, 0.5, -1.0);
        assert!(ray_meets_box(o, Vec3::Z, 10.0, lo, hi));
        assert!(!ray_meets_box(o, Vec3::Z, 0.5, lo, hi));
        assert!(!ray_meets_box(o, -Vec3::Z, 10.0, lo, hi));
        assert!(!ray_meets_box(
            Vec3::new(2.0, 0.5, -1.0),
            Vec3::Z,
            10.0,
            lo,
            hi
        ));
    }
}
