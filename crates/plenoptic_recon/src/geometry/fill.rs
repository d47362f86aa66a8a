//! The last fallbacks of a geometry-assisted pass ([`super`], step 4): pixels that no lookup
//! and no volume sample answered take the nearest answered pixel of the same object in screen
//! space, then the nearest texel of the object around each key's lookup
//! ([`crate::neighbour`]), then the heaviest view's cube in the point's direction.

use glam::Vec3;
use rayon::prelude::*;

use super::{DIRECT, HOLE, NONE, VOLUME, ViewKey};
use crate::frame::Frame;

/// The colour of the nearest texel at about the distance of point `p` (at the frame's time;
/// `slot` its motion's slot) within [`crate::NEIGHBOUR_TEXELS`] of each key's lookup texel on
/// the same face ([`crate::neighbour::nearest_texel`]), the keys blended with their weights,
/// with the second channel's colour at the same texels; `None` where no key has one.
fn neighbour_texel(
    keys: &[ViewKey],
    slot: Option<usize>,
    object: u32,
    p: Vec3,
) -> Option<(Vec3, Vec3)> {
    let (mut sum, mut sum2, mut ws) = (Vec3::ZERO, Vec3::ZERO, 0.0f32);
    for k in keys.iter().filter(|k| k.weight > 1e-4) {
        let q = slot
            .and_then(|s| k.motion.get(s))
            .map_or(p, |m| m.transform_point3(p));
        let best =
            crate::neighbour::nearest_texel(&k.cubes.ids, &k.cubes.distance, q - k.base, object);
        if let Some(idx) = best
            && let Some(c) = k.cubes.radiance.texels.get(idx)
        {
            sum += *c * k.weight;
            if let Some(c2) = k.second.as_ref().and_then(|s| s.texels.get(idx)) {
                sum2 += *c2 * k.weight;
            }
            ws += k.weight;
        }
    }
    (ws > 0.0).then(|| (sum / ws, sum2 / ws))
}

/// Fills HOLE pixels from the nearest DIRECT/VOLUME pixel of the same object (ring search),
/// then from the nearest texels of the object around the lookups ([`neighbour_texel`]); what
/// remains takes the heaviest view's cube in the point's direction. `plane2` (the second
/// channel, or empty) is filled from the same pixels and texels. Returns the counts (filled,
/// background).
pub(super) fn hole_fill(
    frame: &mut Frame,
    plane2: &mut [Vec3],
    class: &mut [u8],
    radius: i64,
    keys: &[ViewKey],
    point: &(dyn Fn(usize) -> Vec3 + Sync),
    slot: &(dyn Fn(u32) -> Option<usize> + Sync),
) -> (usize, usize) {
    let (w, h) = (frame.width as i64, frame.height as i64);
    let holes: Vec<usize> = (0..class.len()).filter(|&j| class[j] == HOLE).collect();
    if holes.is_empty() {
        return (0, 0);
    }
    let fills: Vec<(usize, Option<(Vec3, Vec3)>)> = holes
        .par_iter()
        .map(|&j| {
            let (x, y) = (j as i64 % w, j as i64 / w);
            let o = frame.object[j];
            for r in 1..=radius {
                let (mut sum, mut sum2, mut n) = (Vec3::ZERO, Vec3::ZERO, 0);
                for dy in -r..=r {
                    for dx in -r..=r {
                        if dx.abs() != r && dy.abs() != r {
                            continue;
                        }
                        let (nx, ny) = (x + dx, y + dy);
                        if nx < 0 || ny < 0 || nx >= w || ny >= h {
                            continue;
                        }
                        let k = (ny * w + nx) as usize;
                        if (class[k] == DIRECT || class[k] == VOLUME) && frame.object[k] == o {
                            sum += frame.radiance[k];
                            sum2 += plane2.get(k).copied().unwrap_or_default();
                            n += 1;
                        }
                    }
                }
                if n > 0 {
                    return (j, Some((sum / n as f32, sum2 / n as f32)));
                }
            }
            (j, neighbour_texel(keys, slot(o), o, point(j)))
        })
        .collect();
    let heaviest = keys.iter().max_by(|a, b| a.weight.total_cmp(&b.weight));
    let (mut filled, mut rest) = (0, 0);
    for (j, c) in fills {
        match c {
            Some((c, c2)) => {
                frame.radiance[j] = c;
                if let Some(x) = plane2.get_mut(j) {
                    *x = c2;
                }
                filled += 1;
            }
            None => {
                rest += 1;
                class[j] = NONE + 1;
                if let Some(k) = heaviest {
                    let d = point(j) - k.base;
                    frame.radiance[j] = k.cubes.radiance.lookup(d).copied().unwrap_or_default();
                    if let (Some(x), Some(cube)) = (plane2.get_mut(j), &k.second) {
                        *x = cube.lookup(d).copied().unwrap_or_default();
                    }
                }
            }
        }
    }
    (filled, rest)
}
