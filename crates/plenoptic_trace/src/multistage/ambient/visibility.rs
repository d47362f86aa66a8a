//! Interpolation that does not leak through walls.
//!
//! The field's grid is coarser than a wall is thick: where a floor or a ceiling runs under a
//! wall between two rooms, one sub-triangle can have a corner in each room, and barycentric
//! interpolation then carries the bright room's light into the dark one (the classic light
//! leak of lightmaps and irradiance grids). Two steps keep it out:
//!
//! 1. When a field is gathered, every grid edge is tested with one ray between its two points
//!    (each lifted off the surface along its normal). A point with a blocked edge is
//!    **guarded**: something stands between it and a neighbour.
//! 2. A lookup whose interpolation touches a guarded point tests the segment from the
//!    looked-up point to each of its three field points, drops the ones it cannot see, and
//!    renormalises the weights. Lookups elsewhere cost nothing extra; where no point is
//!    visible the plain weights are kept.

use std::collections::HashSet;

use glam::Vec3;

use super::layout::FieldLayout;
use crate::accel::{Hit, PlacedScene, Ray};

/// World position of a flat point index, lifted off its surface, and its world normal.
fn lifted(placed: &PlacedScene<'_>, layout: &FieldLayout, object: usize, local: usize) -> Vec3 {
    let Some(inst) = placed.instance(object as u32) else {
        return Vec3::splat(f32::NAN);
    };
    let gp = layout.objects[object].points[local];
    let p = inst.to_world.transform_point3(gp.position);
    let n = (inst.normal_matrix * gp.normal).normalize_or(Vec3::Y);
    p + n * lift(p)
}

fn lift(p: Vec3) -> f32 {
    1e-3 * (1.0 + p.abs().max_element())
}

/// Whether the segment from `a` to `b` is free.
fn clear(placed: &PlacedScene<'_>, a: Vec3, b: Vec3) -> bool {
    let d = b - a;
    let len = d.length();
    if !(len.is_finite()) || len <= 1e-6 {
        return true;
    }
    let mut ray = Ray::new(a, d / len);
    ray.tmax = len * (1.0 - 1e-4);
    !placed.occluded(&ray)
}

/// The grid edges that are blocked (step 1 of the module doc), as flat point indices.
pub(super) struct Blocked {
    /// Per flat point: one of its grid edges is blocked.
    pub(super) guarded: Vec<bool>,
    /// Blocked edges (smaller index first).
    edges: HashSet<(u32, u32)>,
}

impl Blocked {
    /// Whether the grid edge between flat points `a` and `b` is free.
    pub(super) fn edge_clear(&self, a: u32, b: u32) -> bool {
        !self.edges.contains(&(a.min(b), a.max(b)))
    }
}

/// Tests every grid edge of `layout` with one ray.
pub(super) fn blocked_edges(placed: &PlacedScene<'_>, layout: &FieldLayout) -> Blocked {
    use rayon::prelude::*;
    let jobs = layout.flat_points();
    let blocked: Vec<Vec<u32>> = jobs
        .par_iter()
        .map(|&(o, i)| {
            let a = lifted(placed, layout, o, i);
            let base = layout.offsets[o] as u32;
            layout.objects[o]
                .neighbours(i)
                .iter()
                .filter(|&&j| j as usize > i)
                .filter(|&&j| !clear(placed, a, lifted(placed, layout, o, j as usize)))
                .map(|&j| base + j)
                .collect()
        })
        .collect();
    let mut guarded = vec![false; jobs.len()];
    let mut edges = HashSet::new();
    for (flat, others) in blocked.iter().enumerate() {
        if !others.is_empty() {
            guarded[flat] = true;
        }
        for &j in others {
            guarded[j as usize] = true;
            edges.insert((flat as u32, j));
        }
    }
    Blocked { guarded, edges }
}

/// The field's interpolation weights at `hit` (flat point indices), with the points the hit
/// cannot see dropped where a guarded point is involved (step 2 of the module doc). `from`
/// is the direction the hit is seen from (unit, pointing away from the surface).
pub(super) fn visible_weights(
    placed: &PlacedScene<'_>,
    layout: &FieldLayout,
    guarded: &[bool],
    hit: &Hit,
    from: Vec3,
) -> Option<[(usize, f32); 3]> {
    let w = layout.weights(hit.object, hit.triangle, hit.barycentrics)?;
    let o = hit.object as usize;
    let base = layout.offsets[o];
    let mut flat = w.map(|(j, wt)| (base + j as usize, wt));
    if !flat.iter().any(|&(j, wt)| wt > 0.0 && guarded[j]) {
        return Some(flat);
    }
    let q = hit.offset_origin(from);
    let q = q + (q - hit.position).normalize_or_zero() * lift(hit.position);
    let mut kept = flat;
    let mut total = 0.0;
    for ((j, wt), k) in flat.iter().zip(kept.iter_mut()) {
        if *wt > 0.0 && !clear(placed, q, lifted(placed, layout, o, j - base)) {
            k.1 = 0.0;
        }
        total += k.1;
    }
    if total > 0.0 {
        for k in &mut kept {
            k.1 /= total;
        }
        flat = kept;
    }
    Some(flat)
}
