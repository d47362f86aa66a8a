//! Decomposing space (thesis §6.5, "motion independence"; docs/architecture.md, Baking step 4).
//!
//! The view space (segment, rectangle or box) is a cell in a dyadic lattice with
//! `2^max_space_depth` steps per axis. A cube id-image is rendered at each corner of a cell;
//! the cell's fitness f is the fraction of pixels whose object id is the same in all its
//! corner images. While f < q (and the cell can still be halved), the cell is bisected
//! (segment), split in four (rectangle) or in eight (box), and each child is tested in turn.
//! The corners of all cells tested are the base views. They are ordered by lattice coordinate
//! (x, then y, then z), so the order does not depend on the order of the tests.
//!
//! The test uses the scene placed at the start of the time range: the decomposition of space
//! does not follow motion (time keys do).

use std::collections::BTreeMap;

use glam::Vec3;
use plenoptic_scene::ObjectId;
use plenoptic_scene::recipe::ViewSpace;
use plenoptic_trace::PlacedScene;

use super::ids::{cube_ids, fitness};

/// Number of axes the view space extends along: 1, 2 or 3.
pub fn dimensions(view: &ViewSpace) -> usize {
    match view {
        ViewSpace::Segment { .. } => 1,
        ViewSpace::Rectangle { .. } => 2,
        ViewSpace::Box { .. } => 3,
    }
}

/// The world position of lattice point `p` (coordinates in `0..=lattice`).
pub fn lattice_position(view: &ViewSpace, lattice: u32, p: [u32; 3]) -> Vec3 {
    let f = |i: usize| p[i] as f32 / lattice.max(1) as f32;
    match *view {
        ViewSpace::Segment { a, b } => a + (b - a) * f(0),
        ViewSpace::Rectangle { min, max, y } => Vec3::new(
            min.x + (max.x - min.x) * f(0),
            y,
            min.y + (max.y - min.y) * f(1),
        ),
        ViewSpace::Box { min, max } => min + (max - min) * Vec3::new(f(0), f(1), f(2)),
    }
}

/// What the decomposition of space found.
#[derive(Debug, Clone)]
pub struct SpaceDecomposition {
    /// Lattice steps per axis (`2^max_space_depth`).
    pub lattice: u32,
    /// Base views: lattice coordinates (unused axes 0) and positions, in lattice order.
    pub views: Vec<([u32; 3], Vec3)>,
    /// Cells tested.
    pub cells_tested: u64,
    /// Cells split.
    pub cells_split: u64,
}

/// Decomposes `view` by id-image coherence at quality `q`: see the module doc.
pub fn decompose(
    placed: &PlacedScene<'_>,
    view: &ViewSpace,
    q: f32,
    id_size: u32,
    max_depth: u32,
) -> SpaceDecomposition {
    let max_depth = max_depth.min(16);
    let lattice = 1u32 << max_depth;
    let dims = dimensions(view);
    let mut cache: BTreeMap<[u32; 3], Vec<ObjectId>> = BTreeMap::new();
    let mut stack = vec![([0u32; 3], lattice)];
    let (mut tested, mut split) = (0u64, 0u64);
    while let Some((origin, size)) = stack.pop() {
        let corners: Vec<[u32; 3]> = (0..1usize << dims)
            .map(|c| {
                let mut p = origin;
                for (axis, v) in p.iter_mut().enumerate().take(dims) {
                    if c >> axis & 1 == 1 {
                        *v += size;
                    }
                }
                p
            })
            .collect();
        for c in &corners {
            if !cache.contains_key(c) {
                let ids = cube_ids(placed, lattice_position(view, lattice, *c), id_size);
                cache.insert(*c, ids);
            }
        }
        tested += 1;
        if size <= 1 {
            continue;
        }
        let images: Vec<&[ObjectId]> = corners.iter().map(|c| cache[c].as_slice()).collect();
        if fitness(&images) >= f64::from(q) {
            continue;
        }
        split += 1;
        let half = size / 2;
        // Children pushed in reverse so that they are tested in order (child 0 first).
        for c in (0..1usize << dims).rev() {
            let mut p = origin;
            for (axis, v) in p.iter_mut().enumerate().take(dims) {
                if c >> axis & 1 == 1 {
                    *v += half;
                }
            }
            stack.push((p, half));
        }
    }
    // Lattice order by (x, y, z): sort on reversed coordinates would give z-major; keep the
    // BTreeMap's lexicographic (x, y, z) order.
    let views = cache
        .keys()
        .map(|&p| (p, lattice_position(view, lattice, p)))
        .collect();
    SpaceDecomposition {
        lattice,
        views,
        cells_tested: tested,
        cells_split: split,
    }
}
