//! Ambient-field key times (thesis §6.6.1, "indirect illumination coherence";
//! docs/architecture.md, Baking step 5, last sentence).
//!
//! The ambient field (indirect irradiance on the simplified scene, `plenoptic_trace`) is
//! gathered at both ends of the time range; an interval is bisected on the time lattice while
//! the relative RMS of irradiance between its ends exceeds `quality.ambient_rms` (both ways
//! round: the larger of the two relative differences). Between key times the renderer
//! interpolates the field linearly ([`field_at`]).

use std::borrow::Cow;
use std::sync::Arc;

use plenoptic_scene::Scene;
use plenoptic_scene::recipe::Quality;
use plenoptic_trace::multistage::FieldLayout;
use plenoptic_trace::{AmbientField, AmbientSettings, SceneAccel};

use super::time::{key_time, subdivide};
use crate::error::Result;

/// Ambient settings for a recipe's quality: gather rays = `ambient_samples`, simplification
/// by q (at least 0.05), bounces iterated until the rest of the series is under 0.5 % (at
/// most 64), gather rays following up to 8 delta bounces through glass and mirrors.
pub fn settings(quality: &Quality, seed: u64) -> AmbientSettings {
    AmbientSettings {
        quality: quality.q.clamp(0.05, 1.0),
        rays_per_point: quality.ambient_samples.max(1),
        seed,
        ..AmbientSettings::low()
    }
}

/// The settings a bake with seed `bake_seed` gathers its ambient fields with.
pub fn field_settings(quality: &Quality, bake_seed: u64) -> AmbientSettings {
    settings(quality, bake_seed ^ 0xa3b1)
}

/// Key times and what was gathered at them.
pub struct AmbientKeys<V = AmbientField> {
    /// Key times, ascending.
    pub times: Vec<f32>,
    /// The field (or one field per light layer) at each key time.
    pub fields: Vec<V>,
    /// Intervals tested.
    pub tested: u64,
}

/// The time range and its subdivision limits, as the plan gives them.
#[derive(Debug, Clone, Copy)]
pub struct KeyRange {
    /// First time.
    pub start: f32,
    /// Last time.
    pub end: f32,
    /// Deepest bisection of the range.
    pub max_depth: u32,
    /// Largest relative RMS change between an interval's ends.
    pub max_rms: f32,
    /// Whether anything changes (else one key at `start`).
    pub animated: bool,
}

/// Bisects `range` on the time lattice while `field` of what `gather` returns at an
/// interval's ends differs by more than `range.max_rms` (both ways round).
fn choose<V>(
    range: KeyRange,
    gather: impl Fn(f32) -> V,
    field: impl Fn(&V) -> &AmbientField,
) -> AmbientKeys<V> {
    let KeyRange {
        start,
        end,
        max_depth,
        max_rms,
        animated,
    } = range;
    if !animated || end <= start {
        return AmbientKeys {
            times: vec![start],
            fields: vec![gather(start)],
            tested: 0,
        };
    }
    let lattice = 1u32 << max_depth.min(16);
    let (keys, tested, mut values) = subdivide(
        &[0, lattice],
        |k| gather(key_time(start, end, lattice, k)),
        |a, b| {
            let (a, b) = (field(a), field(b));
            a.relative_rms(b).max(b.relative_rms(a)) <= f64::from(max_rms)
        },
    );
    let times: Vec<f32> = keys
        .iter()
        .map(|&k| key_time(start, end, lattice, k))
        .collect();
    let fields = keys
        .iter()
        .map(|k| {
            values
                .remove(k)
                .unwrap_or_else(|| gather(key_time(start, end, lattice, *k)))
        })
        .collect();
    AmbientKeys {
        times,
        fields,
        tested,
    }
}

/// Chooses the ambient key times over the range (one key at its start when nothing is
/// animated or the range is empty) and gathers the fields at them.
pub fn key_times(
    scene: &Scene,
    accel: &SceneAccel<'_>,
    settings: &AmbientSettings,
    range: KeyRange,
) -> Result<AmbientKeys> {
    let layout = Arc::new(FieldLayout::new(scene, settings.quality)?);
    let gather = |t: f32| AmbientField::compute(&accel.at_time(t), layout.clone(), settings);
    Ok(choose(range, gather, |f| f))
}

/// [`key_times`] for a scene baked as light layers ([`crate::groups`]): each layer's field is
/// gathered at every time tested, and the key times are chosen on their sum (the whole
/// scene's field, by linearity), so no field of the whole scene is gathered. Returns each
/// key time's fields, one per layer in `layers`' order. The layers share one geometry and so
/// one field layout.
pub fn layered_key_times(
    layers: &[(&Scene, &SceneAccel<'_>)],
    settings: &AmbientSettings,
    range: KeyRange,
) -> Result<AmbientKeys<Vec<AmbientField>>> {
    let Some((scene, _)) = layers.first() else {
        return Ok(AmbientKeys {
            times: Vec::new(),
            fields: Vec::new(),
            tested: 0,
        });
    };
    let layout = Arc::new(FieldLayout::new(scene, settings.quality)?);
    let gather = |t: f32| {
        let fields: Vec<AmbientField> = layers
            .iter()
            .map(|(_, a)| AmbientField::compute(&a.at_time(t), layout.clone(), settings))
            .collect();
        // One layout for all: the sum cannot fail.
        let sum = AmbientField::sum(&fields).and_then(|s| s.ok());
        (fields, sum)
    };
    let keys = choose(range, gather, |(fields, sum)| {
        sum.as_ref().unwrap_or(&fields[0])
    });
    Ok(AmbientKeys {
        times: keys.times,
        fields: keys.fields.into_iter().map(|(f, _)| f).collect(),
        tested: keys.tested,
    })
}

/// The field at time `t`: the key field itself at a key time, else the linear interpolation
/// of the two key fields around `t` (clamped at the ends).
pub fn field_at<'f>(times: &[f32], fields: &'f [AmbientField], t: f32) -> Cow<'f, AmbientField> {
    debug_assert_eq!(times.len(), fields.len());
    let i = times.partition_point(|&k| k <= t);
    if i == 0 {
        return Cow::Borrowed(&fields[0]);
    }
    if i >= times.len() || times[i - 1] == t {
        return Cow::Borrowed(&fields[i - 1]);
    }
    let (a, b) = (times[i - 1], times[i]);
    let s = ((t - a) / (b - a)).clamp(0.0, 1.0);
    match AmbientField::lerp(&fields[i - 1], &fields[i], s) {
        Ok(f) => Cow::Owned(f),
        Err(_) => Cow::Borrowed(&fields[i - 1]),
    }
}
