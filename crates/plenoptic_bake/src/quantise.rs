//! The precision the bake stores (docs/pack-format.md, "Range-image chunks"): texels are
//! rounded to what their own noise can tell before they are encoded, so that zstd is not spent
//! on noise bits.
//!
//! A draft range-image texel is the mean of a few samples (4 in the draft preset): its
//! relative noise is several per cent, while RGB9E5 keeps 9 bits (0.2 %) and R32F 24 bits of
//! every value. The low bits are noise that zstd cannot compress. Here, before encoding:
//!
//! - radiance and lighting keep [`COLOUR_BITS`] significant bits of the texel's largest
//!   channel (each channel is rounded to a step of 2^(⌊log₂ max⌋ − COLOUR_BITS + 1)): at most
//!   half a step, under 0.8 % of the largest channel;
//! - the non-diffuse radiance is rounded to the same step as the texel's radiance, so where
//!   it is a faint glossy sheen on a diffuse wall (most texels) it becomes 0;
//! - distances keep [`DISTANCE_BITS`] bits of mantissa (relative error under 1e-4, far inside
//!   the lookups' 3 % depth tolerance).
//!
//! Temporal-volume samples ([`coarsen_sample`]) are rounded the same way: a sample is one
//! path, far noisier than a range-image texel, and its colours and distance are stored in
//! the same formats. Rounding them shrank the tour's volume blocks by 13 % (10.96 → 9.51 MiB).
//!
//! A light group's layers ([`coarsen_layer`]) are rounded as the total's are (its lighting to
//! [`COLOUR_BITS`] bits of its own value, its non-diffuse radiance to the step of the group's
//! radiance), but to no step finer than 1/[`LAYER_RANGE`] of the total's: a reader adds a layer scaled by
//! the difference of two weights, so at differences up to `LAYER_RANGE` its rounding stays
//! within the total's own. Where a group adds next to nothing (a lamp's light two rooms
//! away), its texels round to zero and cost nothing.
//!
//! Object ids and normals are stored as they are. The formats do not change: a reader sees
//! ordinary RGB9E5 and R32F texels.

use glam::Vec3;
use plenoptic_pack::{RangeImage, VolumeSample};

/// Significant bits kept of a colour texel's largest channel.
pub const COLOUR_BITS: i32 = 7;
/// Mantissa bits kept of a distance (of f32's 23).
pub const DISTANCE_BITS: u32 = 13;

/// The rounding step of a texel whose largest channel is `max` (0 for black).
fn step_of(max: f32) -> f32 {
    if max > 0.0 && max.is_finite() {
        2f32.powi(max.log2().floor() as i32 - COLOUR_BITS + 1)
    } else {
        0.0
    }
}

/// `c` rounded to multiples of `step` per channel (unchanged where `step` is 0).
fn round_to(c: Vec3, step: f32) -> Vec3 {
    if step > 0.0 {
        (c / step).round() * step
    } else {
        c
    }
}

/// `d` with its mantissa rounded to [`DISTANCE_BITS`] bits (infinity and NaN unchanged).
pub fn coarse_distance(d: f32) -> f32 {
    if !d.is_finite() {
        return d;
    }
    let drop = 23 - DISTANCE_BITS;
    let bits = d.to_bits();
    let half = 1u32 << (drop - 1);
    let rounded = (bits + half) & !((1u32 << drop) - 1);
    f32::from_bits(rounded)
}

/// How many times a light group may be scaled against the others before its layers'
/// rounding exceeds the total's ([`coarsen_layer`]).
pub const LAYER_RANGE: f32 = 16.0;

/// `part`, one light group's share of the total `whole`, rounded to the step that
/// [`COLOUR_BITS`] bits of `own` give (the part itself for lighting, the group's radiance for
/// its non-diffuse part, as [`coarsen_part`]), but to no step finer than 1/[`LAYER_RANGE`] of
/// `whole`'s.
pub fn coarsen_layer(part: Vec3, own: Vec3, whole: Vec3) -> Vec3 {
    let step = step_of(own.max_element()).max(step_of(whole.max_element()) / LAYER_RANGE);
    round_to(part, step)
}

/// A light group's image of a range image whose total is `total`: its lighting and
/// non-diffuse radiance rounded by [`coarsen_layer`] (the rest is not stored).
pub fn coarsen_group(group: &RangeImage, total: &RangeImage) -> RangeImage {
    let mut out = group.clone();
    for (i, c) in out.lighting.texels.iter_mut().enumerate() {
        *c = coarsen_layer(*c, *c, total.lighting.texels[i]);
    }
    for (i, c) in out.non_diffuse.texels.iter_mut().enumerate() {
        *c = coarsen_layer(*c, group.radiance.texels[i], total.radiance.texels[i]);
    }
    out
}

/// `c` rounded to [`COLOUR_BITS`] significant bits of its largest channel.
pub fn coarsen_colour(c: Vec3) -> Vec3 {
    round_to(c, step_of(c.max_element()))
}

/// `part` (a share of `whole`, such as its non-diffuse radiance) rounded to the step that
/// [`coarsen_colour`] gives `whole`.
pub fn coarsen_part(part: Vec3, whole: Vec3) -> Vec3 {
    round_to(part, step_of(whole.max_element()))
}

/// `image` with every texel rounded as the module doc says.
pub fn coarsen(image: &RangeImage) -> RangeImage {
    let mut out = image.clone();
    for (i, c) in out.radiance.texels.iter_mut().enumerate() {
        let nd = &mut out.non_diffuse.texels[i];
        *nd = coarsen_part(*nd, *c);
        *c = coarsen_colour(*c);
    }
    for c in &mut out.lighting.texels {
        *c = coarsen_colour(*c);
    }
    for d in &mut out.distance.texels {
        *d = coarse_distance(*d);
    }
    out
}

/// A temporal-volume sample with its colours and distance rounded as a range image's texels
/// are.
pub fn coarsen_sample(s: &VolumeSample) -> VolumeSample {
    VolumeSample {
        radiance: coarsen_colour(s.radiance),
        non_diffuse: coarsen_part(s.non_diffuse, s.radiance),
        lighting: coarsen_colour(s.lighting),
        distance: coarse_distance(s.distance),
        ..*s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colours_keep_their_largest_channel_within_a_percent() {
        for &v in &[1e-4f32, 0.013, 0.5, 1.0, 3.7, 1234.5] {
            let c = Vec3::new(v, 0.37 * v, 0.011 * v);
            let r = round_to(c, step_of(c.max_element()));
            assert!((r - c).abs().max_element() <= 0.008 * v, "{c} -> {r}");
        }
        assert_eq!(round_to(Vec3::ZERO, step_of(0.0)), Vec3::ZERO);
    }

    #[test]
    fn a_layer_keeps_its_own_bits_down_to_a_sixteenth_of_the_totals_step() {
        let whole = Vec3::splat(1.0);
        // A group that is most of the total keeps 7 bits of its own.
        let big = Vec3::new(0.8123, 0.4, 0.1);
        assert_eq!(coarsen_layer(big, big, whole), coarsen_colour(big));
        // One far under the total's step rounds to it: the total's step is 2⁻⁶, a layer's
        // no finer than 2⁻¹⁰, so 3·10⁻⁴ becomes 0 and 0.0101 stays within 2⁻¹¹.
        let tiny = Vec3::splat(3e-4);
        assert_eq!(coarsen_layer(tiny, tiny, whole), Vec3::ZERO);
        let small = Vec3::splat(0.0101);
        let rounded = coarsen_layer(small, small, whole);
        assert!((rounded - small).abs().max_element() <= 2f32.powi(-11));
        // Scaled by up to LAYER_RANGE, the layer's error stays within the total's.
        let err = (rounded - small).abs().max_element() * LAYER_RANGE;
        assert!(err <= step_of(1.0) / 2.0 + 1e-6);
    }

    #[test]
    fn faint_sheen_under_the_radiance_step_becomes_zero() {
        let mut image = RangeImage::new(1);
        image.radiance.texels.fill(Vec3::splat(1.0));
        image.non_diffuse.texels.fill(Vec3::splat(0.003));
        let out = coarsen(&image);
        assert!(out.non_diffuse.texels.iter().all(|&c| c == Vec3::ZERO));
        assert!(out.radiance.texels.iter().all(|&c| c == Vec3::ONE));
    }

    #[test]
    fn volume_samples_are_rounded_like_texels() {
        let s = VolumeSample {
            direction: Vec3::Z,
            t: 0.25,
            radiance: Vec3::new(1.003, 0.5, 0.25),
            lighting: Vec3::new(0.2, 0.7011, 0.1),
            non_diffuse: Vec3::splat(0.003),
            distance: 3.3333,
            normal: Vec3::Y,
            object_id: 7,
            radius: 0.01,
        };
        let r = coarsen_sample(&s);
        assert_eq!(r.radiance, coarsen_colour(s.radiance));
        assert!((r.radiance - s.radiance).abs().max_element() <= 0.008 * 1.003);
        assert!((r.lighting - s.lighting).abs().max_element() <= 0.008 * 0.7011);
        assert_ne!(r.lighting, s.lighting);
        assert_eq!(r.non_diffuse, Vec3::ZERO);
        assert!(((r.distance - s.distance) / s.distance).abs() < 1e-4);
        assert_eq!(
            (r.direction, r.t, r.normal, r.object_id, r.radius),
            (s.direction, s.t, s.normal, s.object_id, s.radius)
        );
    }

    #[test]
    fn distances_keep_four_significant_digits() {
        for &d in &[0.01f32, 0.7, 1.0, 3.3333, 17.25, 250.0] {
            let r = coarse_distance(d);
            assert!(((r - d) / d).abs() < 1e-4, "{d} -> {r}");
        }
        assert_eq!(coarse_distance(f32::INFINITY), f32::INFINITY);
    }
}
