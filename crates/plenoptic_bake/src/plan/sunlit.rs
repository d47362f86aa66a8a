//! Sun patches in the time decomposition of a sun study (docs/architecture.md, "Daylight"; an
//! extension of thesis §6.6.3, view-dependent temporal refinement).
//!
//! The thesis's id-image fitness counts the pixels whose object id changed. A sun patch
//! crossing a floor changes no id, and even a patch that moves away entirely is a few per
//! cent of a base view's cube, far below the 1 − q that fails an interval. So when the sun
//! moves, each base view also compares *where the sun falls* in what it sees: per cube texel,
//! whether its surface point faces the sun and sees it. Two times agree when their sunlit
//! texels overlap, |A ∩ B| / |A ∪ B| ≥ q (Jaccard), a measure relative to the patches' own
//! size: patches that race across the floor at a low sun split intervals, patches that creep
//! at midday do not.
//!
//! Sun visibility is traced in a copy of the scene whose glazing (BLEND coverage below one
//! half) is clear and whose other BLEND surfaces are opaque: coverage is sampled per ray, and
//! a shadow ray whose direction follows the sun would count that noise as motion.

use glam::Vec3;
use plenoptic_scene::{AlphaMode, Scene};
use plenoptic_trace::{PlacedScene, Ray, SceneAccel};
use rayon::prelude::*;

/// `scene` with see-through surfaces decided once: BLEND materials of alpha below one half
/// become clear, the others opaque (see the module doc).
pub fn visibility_scene(scene: &Scene) -> Scene {
    let mut clear = scene.clone();
    for m in &mut clear.materials {
        if m.alpha_mode == AlphaMode::Blend {
            if m.base_color.w < 0.5 {
                m.base_color.w = 0.0;
            } else {
                m.alpha_mode = AlphaMode::Opaque;
            }
        }
    }
    clear
}

/// The sun's visibility tests of a plan.
pub struct SunPatches<'s> {
    scene: &'s Scene,
    clear: SceneAccel<'s>,
}

impl<'s> SunPatches<'s> {
    /// The tests for `scene`, with `clear` its [`visibility_scene`]; `None` when its sun does
    /// not move or the copy cannot be traced.
    pub fn new(scene: &'s Scene, clear: &'s Scene) -> Option<Self> {
        if !scene.sun_is_animated() {
            return None;
        }
        let clear = SceneAccel::new(clear).ok()?;
        Some(Self { scene, clear })
    }

    /// Per texel of a `size`² cube at `position` (the order of `plenoptic_pack::cube`),
    /// whether the surface it sees is in sunlight at time `t`; `placed` is the scene at `t`.
    pub fn sunlit(&self, placed: &PlacedScene<'_>, position: Vec3, size: u32) -> Vec<bool> {
        let t = placed.time();
        let n = 6 * (size as usize) * (size as usize);
        let Some((sun, _)) = self.scene.sun_at(t).filter(|s| s.0.y > 0.0) else {
            return vec![false; n];
        };
        let clear = self.clear.at_time(t);
        (0..n)
            .into_par_iter()
            .map(|i| {
                let dir = plenoptic_pack::cube::texel_direction(size, i);
                let Some(hit) = placed.intersect(&Ray::new(position, dir)) else {
                    return false;
                };
                let mut normal = hit.geometric_normal.normalize_or_zero();
                if normal.dot(dir) > 0.0 {
                    normal = -normal;
                }
                normal.dot(sun) > 0.0 && !clear.occluded(&Ray::new(hit.offset_origin(sun), sun))
            })
            .collect()
    }
}

/// How much two sunlit masks agree: |A ∩ B| / |A ∪ B|, 1 when neither has sunlight.
pub fn overlap(a: &[bool], b: &[bool]) -> f64 {
    let (mut both, mut either) = (0usize, 0usize);
    for (&x, &y) in a.iter().zip(b) {
        both += usize::from(x && y);
        either += usize::from(x || y);
    }
    if either == 0 {
        1.0
    } else {
        both as f64 / either as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn overlap_is_relative_to_the_patches() {
        let mut a = vec![false; 1000];
        let mut b = vec![false; 1000];
        assert_eq!(overlap(&a, &b), 1.0);
        // A patch of 20 texels that moves by 10: a third of its union is shared.
        a[100..120].fill(true);
        b[110..130].fill(true);
        assert!((overlap(&a, &b) - 10.0 / 30.0).abs() < 1e-12);
        assert_eq!(overlap(&a, &a), 1.0);
    }
}
