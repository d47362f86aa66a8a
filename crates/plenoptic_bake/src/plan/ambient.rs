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

/// Key times and the fields gathered at them.
pub struct AmbientKeys {
    /// Key times, ascending.
    pub times: Vec<f32>,
    /// The field at each key time.
    pub fields: Vec<AmbientField>,
    /// Intervals tested.
    pub tested: u64,
}

/// Chooses the ambient key times over `[start, end]` (one key at `start` when `animated` is
/// false or the range is empty) and gathers the fields at them.
#[allow(clippy::too_many_arguments)]
pub fn key_times(
    scene: &Scene,
    accel: &SceneAccel<'_>,
    settings: &AmbientSettings,
    start: f32,
    end: f32,
    max_depth: u32,
    max_rms: f32,
    animated: bool,
) -> Result<AmbientKeys> {
    let layout = Arc::new(FieldLayout::new(scene, settings.quality)?);
    let gather = |t: f32| AmbientField::compute(&accel.at_time(t), layout.clone(), settings);
    if !animated || end <= start {
        return Ok(AmbientKeys {
            times: vec![start],
            fields: vec![gather(start)],
            tested: 0,
        });
    }
    let lattice = 1u32 << max_depth.min(16);
    let (keys, tested, mut values) = subdivide(
        &[0, lattice],
        |k| gather(key_time(start, end, lattice, k)),
        |a, b| a.relative_rms(b).max(b.relative_rms(a)) <= f64::from(max_rms),
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
    Ok(AmbientKeys {
        times,
        fields,
        tested,
    })
}

/// The fields of `scene` (one light group's: the same geometry as the scene whose
/// [`key_times`] chose `times`, other emitters) gathered at `times`.
pub fn fields_at(
    scene: &Scene,
    accel: &SceneAccel<'_>,
    settings: &AmbientSettings,
    times: &[f32],
) -> Result<Vec<AmbientField>> {
    let layout = Arc::new(FieldLayout::new(scene, settings.quality)?);
    Ok(times
        .iter()
        .map(|&t| AmbientField::compute(&accel.at_time(t), layout.clone(), settings))
        .collect())
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
