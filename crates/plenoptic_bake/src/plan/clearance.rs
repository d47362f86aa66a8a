//! Base views clear of objects (docs/architecture.md, Baking step 4; thesis §6.5 places base
//! views at the corners of the view space's cells, wherever they fall).
//!
//! A lattice corner may fall inside a solid (a pillar, a wall, a table top) or wedged between
//! the parts of one (the slabs of the tour's atrium sculpture, 6 cm above and below the
//! atrium's centre view). Its cube then sees the solid's inside or a few centimetres of it:
//! every lookup of a surface farther away is refused by the id and distance tests, and the
//! view only costs its bake. Here each base view is tested and, if crowded, moved to the
//! nearest clear point around it in the view space.
//!
//! - **Crowded:** more than [`CROWDED`] of [`DIRECTIONS`] directions (a spherical Fibonacci
//!   set) first meet a back face (the point is inside a closed mesh or under an open one) or
//!   any surface nearer than [`MIN_CLEARANCE`], at any of [`TIMES`] times spread over the
//!   bake's range (objects move). A view beside a wall is not crowded: at 0.2 m from it, 10 %
//!   of the directions meet the wall within 0.25 m.
//! - **Moved:** candidates lie on rings around the lattice point, [`RING_STEP`] apart, in the
//!   view space's plane (rectangle), along its line (segment) or in all directions (box), up
//!   to 0.45 of the distance to the nearest other base view (so that views keep their order
//!   and cells), inside the view space. The first ring with a clear candidate gives the
//!   least crowded of them (the first in ring order on ties). No clear candidate: the view
//!   stays and is counted.
//!
//! Pure function of the scene and the recipe, as the whole plan is.

use glam::Vec3;
use plenoptic_scene::recipe::ViewSpace;
use plenoptic_trace::{PlacedScene, Ray};
use rayon::prelude::*;

/// Directions tested around a point.
pub const DIRECTIONS: usize = 256;
/// Nearer than this (metres) a surface crowds a view.
pub const MIN_CLEARANCE: f32 = 0.25;
/// Largest fraction of crowded directions a clear view may have.
pub const CROWDED: f32 = 0.2;
/// Times tested, spread evenly over the bake's range (ends included).
pub const TIMES: usize = 5;
/// Metres between rings of candidates.
pub const RING_STEP: f32 = 0.1;
/// Candidates per ring (rectangle and box).
const RING_POINTS: usize = 16;

/// Direction `k` of `n` on the unit sphere (spherical Fibonacci set).
fn direction(k: usize, n: usize) -> Vec3 {
    let z = 1.0 - (2 * k + 1) as f32 / n as f32;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = k as f32 * 2.399_963_2;
    Vec3::new(r * phi.cos(), z, r * phi.sin())
}

/// The fraction of directions from `p` that meet a back face or a surface nearer than
/// [`MIN_CLEARANCE`], the largest over the scene placed at each time of `scenes`.
pub fn crowding(scenes: &[PlacedScene<'_>], p: Vec3) -> f32 {
    let mut worst = 0.0f32;
    for placed in scenes {
        let crowded = (0..DIRECTIONS)
            .filter(|&k| {
                placed
                    .intersect(&Ray::new(p, direction(k, DIRECTIONS)))
                    .is_some_and(|h| !h.front_face || h.distance < MIN_CLEARANCE)
            })
            .count();
        worst = worst.max(crowded as f32 / DIRECTIONS as f32);
    }
    worst
}

/// `n` times spread evenly over `start..=end` (one when the range is empty): where
/// [`crowding`] places the scene.
pub fn times(start: f32, end: f32, n: usize) -> Vec<f32> {
    if end <= start || n < 2 {
        return vec![start];
    }
    (0..n)
        .map(|i| start + (end - start) * i as f32 / (n - 1) as f32)
        .collect()
}

/// Unit directions in the view space's extent in which a view may move.
fn ring_directions(view: &ViewSpace) -> Vec<Vec3> {
    match *view {
        ViewSpace::Segment { a, b } => {
            let d = (b - a).normalize_or_zero();
            vec![d, -d]
        }
        ViewSpace::Rectangle { .. } => (0..RING_POINTS)
            .map(|i| {
                let a = std::f32::consts::TAU * i as f32 / RING_POINTS as f32;
                Vec3::new(a.cos(), 0.0, a.sin())
            })
            .collect(),
        ViewSpace::Box { .. } => (0..RING_POINTS)
            .map(|k| direction(k, RING_POINTS))
            .collect(),
    }
}

/// Whether `p` lies in the view space (a small margin for rounding).
fn inside(view: &ViewSpace, p: Vec3) -> bool {
    let eps = 1e-4;
    match *view {
        ViewSpace::Segment { a, b } => {
            let d = b - a;
            let s = (p - a).dot(d) / d.length_squared().max(1e-12);
            (-eps..=1.0 + eps).contains(&s)
        }
        ViewSpace::Rectangle { min, max, .. } => {
            (min.x - eps..=max.x + eps).contains(&p.x) && (min.y - eps..=max.y + eps).contains(&p.z)
        }
        ViewSpace::Box { min, max } => p.cmpge(min - eps).all() && p.cmple(max + eps).all(),
    }
}

/// How far a base view at `p` may move: 0.45 of the distance to the nearest of `others`
/// (so that views keep their order and their cells), or of the view space's diagonal when
/// there is no other.
pub fn reach(view: &ViewSpace, others: impl Iterator<Item = Vec3>, p: Vec3) -> f32 {
    let nearest = others
        .map(|q| q.distance(p))
        .filter(|&d| d > 0.0)
        .fold(f32::INFINITY, f32::min);
    let extent = match *view {
        ViewSpace::Segment { a, b } => (b - a).length(),
        ViewSpace::Rectangle { min, max, .. } => (max - min).length(),
        ViewSpace::Box { min, max } => (max - min).length(),
    };
    0.45 * if nearest.is_finite() { nearest } else { extent }
}

/// Where a base view at `p` should be: `p` itself when it is clear, else the clear point the
/// module doc describes within `reach` ([`reach`]); `None` when it is crowded and no
/// candidate is clear.
pub fn clear_position(
    scenes: &[PlacedScene<'_>],
    view: &ViewSpace,
    reach: f32,
    p: Vec3,
) -> Option<Vec3> {
    if crowding(scenes, p) <= CROWDED {
        return Some(p);
    }
    let rings = (reach / RING_STEP).floor() as usize;
    let dirs = ring_directions(view);
    for ring in 1..=rings {
        let r = ring as f32 * RING_STEP;
        let tested: Vec<(f32, Vec3)> = dirs
            .par_iter()
            .map(|&d| p + d * r)
            .filter(|&q| inside(view, q))
            .map(|q| (crowding(scenes, q), q))
            .collect();
        // The least crowded clear candidate, the first on ties.
        let best = tested
            .into_iter()
            .filter(|&(c, _)| c <= CROWDED)
            .min_by(|a, b| a.0.total_cmp(&b.0));
        if let Some((_, q)) = best {
            return Some(q);
        }
    }
    None
}
