//! The proxies' ray-cast geometry laid out for a GPU shader: the triangles the CPU's
//! reflections cast rays against ([`crate::shadow::ShadowScene`], the escape test of
//! [`crate::specular`]), in one array of `vec4<f32>` words that the Bevy plugin's
//! `rays.wgsl` traverses exactly as [`FlatRays::occluded`] does here
//! (docs/architecture.md, "The runtime plugin"; thesis §8.2.3's view-dependent part).
//!
//! Each BVH (one over the objects that never move, in world space; one per animated object, in
//! its own space) is obvhs's binary BVH flattened in depth-first order with a *miss link* per
//! node: the node to visit next when the ray misses this one's box, i.e. the node after its
//! subtree. Traversal is then a loop without a stack (Smits, "Efficiency issues for ray
//! tracing", JGT 1998), which a fragment shader runs without a depth limit.
//!
//! Words (`u32` fields stored as the `f32` with those bits):
//! - word 0: (first, end) node words of the fixed BVH (equal: none), the count of moving BVHs,
//!   and 1 (the pack has proxy geometry);
//! - one word per moving BVH: (first, end) node words, its pack object id, and the fraction
//!   of light each of its surfaces lets through: 0 for an opaque object, 1 − c for
//!   see-through glazing of coverage c ([`FlatRays::with_see_through`]; glazing gets a BVH of
//!   its own in object space, moving or not, so that the runtime sun can walk the glazing
//!   alone, [`FlatRays::see_through_pass`]);
//! - two words per node: (box min, miss link), (box max, first triangle word or
//!   [`NO_TRIANGLES`] for an inner node);
//! - three words per triangle: (v0, 1 for the last triangle of its leaf else 0), (v1, 0),
//!   (v2, 0).
//!
//! A moving BVH is placed at a time by [`FlatRays::placements`]: three words per moving object,
//! the rows of its world → object transform at that time (an affine map keeps the ray's
//! parameter, so `tmax` holds in object space).

use std::time::Duration;

use glam::{Affine3A, Vec3, Vec4};
use obvhs::{BvhBuildParams, bvh2::builder::build_bvh2_from_tris, triangle::Triangle};

use crate::proxy::ProxyGeometry;

/// The second node word's `w` of an inner node.
pub const NO_TRIANGLES: u32 = u32::MAX;

/// The proxies' ray-cast geometry as words for a GPU storage buffer (see the module doc).
#[derive(Debug, Clone, PartialEq)]
pub struct FlatRays {
    words: Vec<Vec4>,
    /// Pack id of each moving BVH, in order.
    moving: Vec<u32>,
}

/// One BVH flattened: nodes with links relative to its first node, triangles in leaf order.
struct Flat {
    /// (min, miss link, max, first triangle or [`NO_TRIANGLES`]), indices in nodes and
    /// triangles of this BVH.
    nodes: Vec<(Vec3, u32, Vec3, u32)>,
    /// Triangles and whether each is the last of its leaf.
    triangles: Vec<(Triangle, bool)>,
}

fn flatten(tris: &[Triangle]) -> Option<Flat> {
    if tris.is_empty() {
        return None;
    }
    let bvh = build_bvh2_from_tris(
        tris,
        BvhBuildParams::medium_build(),
        &mut Duration::default(),
    );
    enum Step {
        Enter(usize),
        Exit(usize),
    }
    let mut flat = Flat {
        nodes: Vec::with_capacity(bvh.nodes.len()),
        triangles: Vec::with_capacity(tris.len()),
    };
    let mut stack = vec![Step::Enter(0)];
    while let Some(step) = stack.pop() {
        match step {
            Step::Enter(n) => {
                let node = &bvh.nodes[n];
                let here = flat.nodes.len();
                let (lo, hi) = (node.aabb().min.into(), node.aabb().max.into());
                if node.is_leaf() {
                    let first = flat.triangles.len() as u32;
                    let range =
                        node.first_index as usize..(node.first_index + node.prim_count) as usize;
                    let count = range.len();
                    for (k, &p) in bvh.primitive_indices[range].iter().enumerate() {
                        flat.triangles.push((tris[p as usize], k + 1 == count));
                    }
                    flat.nodes.push((lo, here as u32 + 1, hi, first));
                } else {
                    flat.nodes.push((lo, 0, hi, NO_TRIANGLES));
                    let left = node.first_index as usize;
                    stack.push(Step::Exit(here));
                    stack.push(Step::Enter(left + 1));
                    stack.push(Step::Enter(left));
                }
            }
            Step::Exit(here) => flat.nodes[here].1 = flat.nodes.len() as u32,
        }
    }
    Some(flat)
}

fn bits(u: u32) -> f32 {
    f32::from_bits(u)
}

fn word_u32(w: f32) -> u32 {
    w.to_bits()
}

impl FlatRays {
    /// The ray-cast geometry of every proxy of `proxy`, the same triangles as
    /// [`crate::shadow::ShadowScene::new`].
    pub fn new(proxy: &ProxyGeometry) -> Self {
        Self::with_see_through(proxy, [])
    }

    /// [`FlatRays::new`] with the objects of `coverage` (pack id, coverage c) see-through
    /// glazing: each in a BVH of its own whose surfaces pass 1 − c of the light
    /// ([`FlatRays::see_through_pass`]). [`FlatRays::occluded`] still stops at them.
    pub fn with_see_through(
        proxy: &ProxyGeometry,
        coverage: impl IntoIterator<Item = (u32, f32)>,
    ) -> Self {
        let glazing: Vec<(u32, f32)> = coverage
            .into_iter()
            .map(|(id, c)| (id, 1.0 - c.clamp(0.0, 1.0)))
            .collect();
        let pass_of = |id: u32| glazing.iter().find(|g| g.0 == id).map(|g| g.1);
        let (fixed, moving) = crate::shadow::split_triangles(proxy, |id| pass_of(id).is_none());
        let fixed: Vec<Triangle> = fixed.into_iter().map(|(t, _)| t).collect();
        let fixed = flatten(&fixed);
        let see_through = proxy
            .object_ids()
            .iter()
            .zip(proxy.meshes())
            .filter_map(|(&id, m)| {
                let pass = pass_of(id)?;
                Some((id, crate::shadow::object_triangles(m), pass))
            });
        let moving: Vec<(u32, Flat, f32)> = moving
            .into_iter()
            .map(|(id, tris)| (id, tris, 0.0))
            .chain(see_through)
            .filter_map(|(id, tris, pass)| Some((id, flatten(&tris)?, pass)))
            .collect();
        let node_words = |f: &Flat| 2 * f.nodes.len() as u32;
        // Node words start after the header and the moving table; triangles after all nodes.
        let mut node_at = 1 + moving.len() as u32;
        let mut tri_at = node_at
            + fixed.as_ref().map_or(0, node_words)
            + moving.iter().map(|(_, f, _)| node_words(f)).sum::<u32>();
        let mut words = vec![Vec4::ZERO; 1 + moving.len()];
        let mut nodes = Vec::new();
        let mut triangles = Vec::new();
        let mut place = |f: &Flat| -> (u32, u32) {
            let first = node_at;
            for &(lo, miss, hi, tri) in &f.nodes {
                let leaf = if tri == NO_TRIANGLES {
                    NO_TRIANGLES
                } else {
                    tri_at + 3 * tri
                };
                nodes.push(lo.extend(bits(first + 2 * miss)));
                nodes.push(hi.extend(bits(leaf)));
            }
            for &(t, last) in &f.triangles {
                triangles.push(Vec3::from(t.v0).extend(if last { 1.0 } else { 0.0 }));
                triangles.push(Vec3::from(t.v1).extend(0.0));
                triangles.push(Vec3::from(t.v2).extend(0.0));
            }
            node_at += node_words(f);
            tri_at += 3 * f.triangles.len() as u32;
            (first, node_at)
        };
        let (f0, f1) = fixed.as_ref().map_or((0, 0), &mut place);
        words[0] = Vec4::new(bits(f0), bits(f1), bits(moving.len() as u32), bits(1));
        for (k, (id, f, pass)) in moving.iter().enumerate() {
            let (first, end) = place(f);
            words[1 + k] = Vec4::new(bits(first), bits(end), bits(*id), *pass);
        }
        words.extend(nodes);
        words.extend(triangles);
        FlatRays {
            words,
            moving: moving.iter().map(|(id, _, _)| *id).collect(),
        }
    }

    /// The words of a pack without proxy geometry: nothing to cast against, and word 0's `w`
    /// is 0 (the shader then marches every ray, as the CPU does without proxies).
    pub fn none() -> Self {
        FlatRays {
            words: vec![Vec4::ZERO],
            moving: Vec::new(),
        }
    }

    /// The words, for a storage buffer of `array<vec4<f32>>`.
    pub fn words(&self) -> &[Vec4] {
        &self.words
    }

    /// Pack ids of the moving objects, in the order of [`Self::placements`].
    pub fn moving(&self) -> &[u32] {
        &self.moving
    }

    /// The moving objects placed: three words per moving object, the rows of the inverse of
    /// `object_to_world(id)` (at least one word, so that a buffer of them is never empty).
    pub fn placements(&self, object_to_world: impl Fn(u32) -> Affine3A) -> Vec<Vec4> {
        let mut out = Vec::with_capacity(3 * self.moving.len().max(1));
        for &id in &self.moving {
            let m = object_to_world(id).inverse();
            let (c, t) = (m.matrix3, m.translation);
            out.push(Vec4::new(c.x_axis.x, c.y_axis.x, c.z_axis.x, t.x));
            out.push(Vec4::new(c.x_axis.y, c.y_axis.y, c.z_axis.y, t.y));
            out.push(Vec4::new(c.x_axis.z, c.y_axis.z, c.z_axis.z, t.z));
        }
        if out.is_empty() {
            out.push(Vec4::ZERO);
        }
        out
    }

    /// Whether any triangle lies along the ray from `origin` along `dir` closer than `tmax`,
    /// with the moving objects at `placements`: the traversal `rays.wgsl` runs, step for step.
    pub fn occluded(&self, placements: &[Vec4], origin: Vec3, dir: Vec3, tmax: f32) -> bool {
        let w = &self.words;
        let header = w[0];
        if word_u32(header.w) == 0 {
            return false;
        }
        let (first, end) = (word_u32(header.x), word_u32(header.y));
        if self.hits(first, end, origin, dir, tmax, false) > 0 {
            return true;
        }
        (0..word_u32(header.z) as usize).any(|k| {
            let (first, end) = (word_u32(w[1 + k].x), word_u32(w[1 + k].y));
            placements.get(3 * k..3 * k + 3).is_some_and(|rows| {
                let (o, d) = placed_ray(rows, origin, dir);
                self.hits(first, end, o, d, tmax, false) > 0
            })
        })
    }

    /// The fraction of light the see-through glazing lets through along the ray from
    /// `origin` along `dir` within `tmax`: `Π (1 − c)` over the glazing surfaces it crosses,
    /// the other proxies ignored (the runtime sun's shadow map has them); `rays.wgsl`'s
    /// `see_through_pass`, step for step.
    pub fn see_through_pass(&self, placements: &[Vec4], origin: Vec3, dir: Vec3, tmax: f32) -> f32 {
        let w = &self.words;
        let mut through = 1.0;
        for k in 0..word_u32(w[0].z) as usize {
            let entry = w[1 + k];
            let Some(rows) = placements.get(3 * k..3 * k + 3) else {
                continue;
            };
            if entry.w > 0.0 {
                let (o, d) = placed_ray(rows, origin, dir);
                let n = self.hits(word_u32(entry.x), word_u32(entry.y), o, d, tmax, true);
                through *= entry.w.powi(n as i32);
            }
        }
        through
    }

    /// The stackless walk of the node words `first..end`: how many triangles the ray meets,
    /// stopping at the first unless `all`.
    fn hits(&self, first: u32, end: u32, origin: Vec3, dir: Vec3, tmax: f32, all: bool) -> u32 {
        let w = &self.words;
        let inv = safe_recip(dir);
        let mut count = 0;
        let mut i = first;
        while i < end {
            let (a, b) = (w[i as usize], w[i as usize + 1]);
            if !meets_box(origin, inv, tmax, a.truncate(), b.truncate()) {
                i = word_u32(a.w);
                continue;
            }
            let leaf = word_u32(b.w);
            if leaf == NO_TRIANGLES {
                i += 2;
                continue;
            }
            let mut j = leaf as usize;
            loop {
                let (v0, v1, v2) = (w[j], w[j + 1], w[j + 2]);
                let [a0, a1, a2] = [v0, v1, v2].map(Vec4::truncate);
                if hits_triangle(origin, dir, tmax, a0, a1, a2) {
                    count += 1;
                    if !all {
                        return count;
                    }
                }
                if v0.w != 0.0 {
                    break;
                }
                j += 3;
            }
            i = word_u32(a.w);
        }
        count
    }
}

/// The ray (`origin`, `dir`) moved by the three rows of a world → object placement.
fn placed_ray(rows: &[Vec4], origin: Vec3, dir: Vec3) -> (Vec3, Vec3) {
    let apply = |p: Vec3, one: f32| {
        Vec3::new(
            rows[0].dot(p.extend(one)),
            rows[1].dot(p.extend(one)),
            rows[2].dot(p.extend(one)),
        )
    };
    (apply(origin, 1.0), apply(dir, 0.0))
}

/// `1/d` per component, a zero component replaced by ±1e-12 first (no NaN in the slab test).
fn safe_recip(d: Vec3) -> Vec3 {
    let s = |x: f32| {
        if x.abs() < 1e-12 {
            1e-12f32.copysign(x)
        } else {
            x
        }
    };
    Vec3::new(s(d.x), s(d.y), s(d.z)).recip()
}

/// Slab test of the ray against the box `lo..hi` over `0..=tmax`.
fn meets_box(origin: Vec3, inv: Vec3, tmax: f32, lo: Vec3, hi: Vec3) -> bool {
    let a = (lo - origin) * inv;
    let b = (hi - origin) * inv;
    let near = a.min(b).max_element().max(0.0);
    let far = a.max(b).min_element().min(tmax);
    near <= far
}

/// Möller–Trumbore, both faces, a hit at `0 ≤ t ≤ tmax`: obvhs's `Triangle::intersect`, but
/// with `u, v, w ≥ 0` compared as numbers, as WGSL compares them. obvhs tests their sign
/// bits, which rejects −0.0: a ray through the diagonal of a quad then misses both of its
/// triangles (the hand-picked ray into the moving cube in the tests does). This twin of
/// `rays.wgsl` keeps the shader's rule.
fn hits_triangle(origin: Vec3, dir: Vec3, tmax: f32, v0: Vec3, v1: Vec3, v2: Vec3) -> bool {
    let e1 = v0 - v1;
    let e2 = v2 - v0;
    let n = e1.cross(e2);
    let c = v0 - origin;
    let r = dir.cross(c);
    let det = n.dot(dir);
    if det == 0.0 {
        return false;
    }
    let inv_det = 1.0 / det;
    let u = r.dot(e2) * inv_det;
    let v = r.dot(e1) * inv_det;
    let w = 1.0 - u - v;
    if u < 0.0 || v < 0.0 || w < 0.0 {
        return false;
    }
    let t = n.dot(c) * inv_det;
    (0.0..=tmax).contains(&t)
}

#[cfg(test)]
#[path = "flat_rays_tests.rs"]
mod tests;
