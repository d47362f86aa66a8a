//! The thin-object fallback of the geometry-assisted mode (after the same-object hole fill;
//! `docs/architecture.md`, "Reconstruction"): a point whose object no texel centre met (a
//! window's mullion seen from across a room) takes, in each key, the nearest texel of its own
//! object around the lookup's texel, else the nearest texel of any surface at about its
//! distance (the wall around the window), instead of the cube in its direction, which shows
//! what lies behind it (the sky).
//!
//! The search is a square of [`NEIGHBOUR_TEXELS`] texels on either side of the lookup's texel
//! on its face. `bevy_plenoptic`'s `geometry.wgsl` searches alike, with these constants.

use glam::Vec3;
use plenoptic_pack::CubeImage;

/// Texels on either side of a lookup's texel (along each axis of its face) searched for the
/// object itself, else any surface at the point's distance, when nothing else answered. On
/// the tour (64-px cubes), a search of 2 texels leaves Room A's mullions at 3.8× the path
/// tracer's luminance and 3 at 2.7×. 4 brings them to 1.03× on average, but a base view 7 m
/// from a window sees its opening 9 texels wide, so that a mullion no texel centre met lies 5
/// texels from the wall: at 4, ten of its pixels in frame 6 of 8 (320 × 180) show the sky, 86 %
/// of that frame's squared error (corrected relative LRMS 0.421; 0.087 at 5 and above). 8 leaves a
/// margin for wider openings; the search only runs for pixels nothing else answered.
pub const NEIGHBOUR_TEXELS: i64 = 8;

/// How far (relative) a neighbouring texel's distance may be from the point's: a thin
/// object's neighbouring texel sees another part of it.
pub const NEIGHBOUR_TOLERANCE: f32 = 0.25;

/// Ranks another object's texel behind every texel of the object itself (above the largest
/// squared offset in the search window).
const OTHER_OBJECT: i64 = 2 * NEIGHBOUR_TEXELS * NEIGHBOUR_TEXELS + 1;

/// The index of the texel that stands in for a point of `object` at offset `d` from the base
/// view: the nearest texel of `object` within [`NEIGHBOUR_TEXELS`] of the texel `d` falls in,
/// on the same face, at a distance within [`NEIGHBOUR_TOLERANCE`] of `|d|`; failing that, the
/// nearest texel of any surface at that distance. The nearest is the smallest offset, the
/// first found in row order on ties. `None` when there is none, or `d` is zero.
pub(crate) fn nearest_texel(
    ids: &CubeImage<u32>,
    distance: &CubeImage<f32>,
    d: Vec3,
    object: u32,
) -> Option<usize> {
    let dist = d.length();
    if dist <= 1e-6 || !dist.is_finite() {
        return None;
    }
    let n = i64::from(ids.face_size.max(1));
    let t = plenoptic_pack::cube::direction_to_texel(ids.face_size, d) as i64;
    let (face, i, j) = (t / (n * n), t % n, (t / n) % n);
    let mut best: Option<(i64, usize)> = None;
    for dj in -NEIGHBOUR_TEXELS..=NEIGHBOUR_TEXELS {
        for di in -NEIGHBOUR_TEXELS..=NEIGHBOUR_TEXELS {
            let (x, y) = (i + di, j + dj);
            if x < 0 || y < 0 || x >= n || y >= n {
                continue;
            }
            let idx = (face * n * n + y * n + x) as usize;
            let Some(&id) = ids.texels.get(idx) else {
                continue;
            };
            // The object's own texels first, then any surface at the point's distance.
            let score = di * di + dj * dj + if id == object { 0 } else { OTHER_OBJECT };
            if id != 0
                && distance
                    .texels
                    .get(idx)
                    .is_some_and(|&l| (l - dist).abs() <= NEIGHBOUR_TOLERANCE * dist)
                && best.is_none_or(|(b, _)| score < b)
            {
                best = Some((score, idx));
            }
        }
    }
    best.map(|(_, idx)| idx)
}

#[cfg(test)]
mod tests {
    use super::*;

    const N: u32 = 32;
    const WALL: u32 = 5;
    const MULLION: u32 = 7;

    /// A cube whose +z face (layer 4) shows a wall at distance 3 with a square opening of
    /// `half` texels on either side of its centre texel (16, 16), open to the sky (id 0).
    fn window(half: i64) -> (CubeImage<u32>, CubeImage<f32>) {
        let ids = CubeImage::from_fn(N, |idx, _| {
            let n = N as usize;
            let (face, x, y) = (idx / (n * n), (idx % n) as i64, ((idx / n) % n) as i64);
            let inside = (x - 16).abs() <= half && (y - 16).abs() <= half;
            if face == 4 && inside { 0 } else { WALL }
        });
        let distance = CubeImage::from_fn(N, |idx, _| {
            if ids.texels[idx] == 0 {
                f32::INFINITY
            } else {
                3.0
            }
        });
        (ids, distance)
    }

    /// The direction to texel (x, y) of face 4.
    fn towards(x: u32, y: u32) -> Vec3 {
        plenoptic_pack::cube::texel_direction(N, (4 * N * N + y * N + x) as usize)
    }

    #[test]
    fn a_point_in_the_middle_of_a_wide_opening_finds_the_wall() {
        // The tour's case: the opening's edge 5 texels from the lookup (a 4-texel search
        // finds nothing there, and the mullion shows the sky).
        let (ids, distance) = window(4);
        let d = towards(16, 16) * 3.0;
        assert_eq!(
            ids.texels[nearest_texel(&ids, &distance, d, MULLION).unwrap()],
            WALL
        );
        // An opening wider than the search: nothing.
        let (ids, distance) = window(NEIGHBOUR_TEXELS);
        assert_eq!(nearest_texel(&ids, &distance, d, MULLION), None);
    }

    #[test]
    fn the_objects_own_texels_come_before_a_nearer_wall() {
        let (mut ids, distance) = window(4);
        // A texel of the mullion at the search's far corner (squared offset 2 · 8² = 128),
        // farther than the wall's edge (5² = 25): an own texel anywhere in the window ranks
        // first (with a fixed rank of 100 for other objects, the wall would win here).
        let k = NEIGHBOUR_TEXELS as u32;
        let far = (4 * N * N + (16 + k) * N + 16 + k) as usize;
        ids.texels[far] = MULLION;
        let mut distance = distance;
        distance.texels[far] = 3.05;
        let d = towards(16, 16) * 3.0;
        assert_eq!(nearest_texel(&ids, &distance, d, MULLION), Some(far));
        // Another object's texel loses to the nearest wall.
        assert_eq!(
            ids.texels[nearest_texel(&ids, &distance, d, 99).unwrap()],
            WALL
        );
    }

    #[test]
    fn texels_at_another_distance_are_not_taken() {
        let (ids, distance) = window(4);
        // The point 2× as far as the wall (beyond the tolerance): nothing qualifies.
        let d = towards(16, 16) * 6.0;
        assert_eq!(nearest_texel(&ids, &distance, d, MULLION), None);
        assert_eq!(nearest_texel(&ids, &distance, Vec3::ZERO, MULLION), None);
    }
}
