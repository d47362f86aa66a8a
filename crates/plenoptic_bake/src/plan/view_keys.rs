//! Range-image keys where a base view's indirect light is not linear between its keys (thesis
//! §6.6.1's indirect-illumination coherence, applied per base view; docs/architecture.md,
//! "Baking").
//!
//! The runtime blends a view's two keys around the frame's time linearly (thesis §8.2.3's time
//! weights). The light keys follow what the lights see and the ambient field's keys follow how
//! much its irradiance changes between an interval's ends; neither says whether the light a
//! view shows is linear in between. Under a sun study it often is not: on the tour the light a
//! camera in room B sees falls 17 % from the light key at 5.25 s to 6.5 s and 1 % more to the
//! next one at 7 s, so the blend of those keys is 4.8 % too bright at 6.5 s
//! (docs/fidelity.md, "Mean offsets between keys").
//!
//! So each view takes an ambient key time that lies between two of its keys as a key of its own
//! where the field there differs from the linear blend of the field at its bracketing keys by
//! more than [`LERP_RMS`] (relative RMS of the irradiance's luminance over the surfaces a
//! [`PROBE_FACE`]-pixel cube at the view sees). The worst such time is taken first and the test
//! repeated, so a view gets keys only where its own light bends. The fields are those the bake
//! renders with (linear between the ambient keys), so a time the test passes is one where the
//! range images would agree with the blend up to their noise.

use std::borrow::Cow;
use std::collections::HashMap;

use glam::Vec3;
use plenoptic_pack::cube::texel_direction;
use plenoptic_trace::image::luminance;
use plenoptic_trace::{AmbientField, Hit, PlacedScene, Ray, SceneAccel};
use rayon::prelude::*;

use super::ambient::field_at;

/// Largest relative RMS difference, over what a view sees, between the ambient field at a time
/// inside one of its key intervals and the linear blend of the field at the interval's ends.
pub const LERP_RMS: f32 = 0.05;

/// Face size of the cube of probe rays each view's test traces.
pub const PROBE_FACE: u32 = 16;

/// A view's keys (`keys`, ascending) with the ambient key times (`times`, ascending, `fields` at
/// them) added where its light bends (see the module doc); `position` is the view's.
pub fn refine(
    accel: &SceneAccel<'_>,
    position: Vec3,
    keys: &[f32],
    times: &[f32],
    fields: &[AmbientField],
) -> Vec<f32> {
    let mut keys = keys.to_vec();
    // Each candidate's probe is traced and read at its own time once; the luminance there from
    // the field at a key time is read once per (candidate, key).
    let mut probes: Vec<Probe<'_>> = times
        .iter()
        .zip(fields)
        .filter(|(t, _)| bracket(&keys, **t).is_some())
        .map(|(&t, field)| Probe::new(accel, position, t, field))
        .collect();
    let mut at_keys: HashMap<u32, Cow<'_, AmbientField>> = HashMap::new();
    loop {
        let mut worst: Option<(usize, f64)> = None;
        for (i, probe) in probes.iter_mut().enumerate() {
            let Some((t0, t1)) = bracket(&keys, probe.t) else {
                continue;
            };
            for t in [t0, t1] {
                at_keys
                    .entry(t.to_bits())
                    .or_insert_with(|| field_at(times, fields, t));
            }
            let e0 = probe.seen(t0, &at_keys[&t0.to_bits()]);
            let e1 = probe.seen(t1, &at_keys[&t1.to_bits()]);
            let err = probe.bend(&e0, &e1, (probe.t - t0) / (t1 - t0));
            probe.remember(t0, e0);
            probe.remember(t1, e1);
            if worst.is_none_or(|(_, w)| err > w) {
                worst = Some((i, err));
            }
        }
        match worst {
            Some((i, err)) if err > f64::from(LERP_RMS) => {
                let t = probes[i].t;
                keys.insert(keys.partition_point(|&k| k < t), t);
            }
            _ => return keys,
        }
    }
}

/// The keys around `t` strictly inside their interval; `None` at a key or outside them.
fn bracket(keys: &[f32], t: f32) -> Option<(f32, f32)> {
    let i = keys.partition_point(|&k| k <= t);
    if i == 0 || i >= keys.len() || keys[i - 1] == t {
        return None;
    }
    Some((keys[i - 1], keys[i]))
}

/// A candidate time's probe cube: its hits at that time, the field's luminance there, and the
/// luminance the fields at the view's keys give them.
struct Probe<'a> {
    t: f32,
    placed: PlacedScene<'a>,
    hits: Vec<(Hit, Vec3)>,
    own: Vec<f32>,
    at_keys: HashMap<u32, Vec<f32>>,
}

impl<'a> Probe<'a> {
    /// The probe cube at `position` traced at `t`, read in `field` (the field at `t`).
    fn new(accel: &'a SceneAccel<'a>, position: Vec3, t: f32, field: &AmbientField) -> Self {
        let placed = accel.at_time(t);
        let hits: Vec<(Hit, Vec3)> = (0..6 * PROBE_FACE * PROBE_FACE)
            .into_par_iter()
            .filter_map(|i| {
                let dir = texel_direction(PROBE_FACE, i as usize);
                Some((placed.intersect(&Ray::new(position, dir))?, dir))
            })
            .collect();
        let mut probe = Self {
            t,
            placed,
            hits,
            own: Vec::new(),
            at_keys: HashMap::new(),
        };
        probe.own = probe.read(field);
        probe
    }

    /// Luminance of `field`'s irradiance at each hit, as the renderer reads it.
    fn read(&self, field: &AmbientField) -> Vec<f32> {
        self.hits
            .par_iter()
            .map(|(hit, dir)| luminance(field.irradiance_seen(&self.placed, hit, -*dir)))
            .collect()
    }

    /// [`Self::read`] of `field`, the field at key time `key`, kept from an earlier call.
    fn seen(&mut self, key: f32, field: &AmbientField) -> Vec<f32> {
        self.at_keys
            .remove(&key.to_bits())
            .unwrap_or_else(|| self.read(field))
    }

    /// Keeps `values` as [`Self::seen`]'s answer for `key`.
    fn remember(&mut self, key: f32, values: Vec<f32>) {
        self.at_keys.insert(key.to_bits(), values);
    }

    /// Relative RMS difference between the field at the probe's time and the blend
    /// `(1 − s)·e0 + s·e1` of the fields at its bracketing keys (luminance is linear, so the
    /// blend of luminances is the luminance of the blend).
    fn bend(&self, e0: &[f32], e1: &[f32], s: f32) -> f64 {
        let (diff, total) =
            self.own
                .iter()
                .zip(e0.iter().zip(e1))
                .fold((0.0, 0.0), |(d, n), (&e, (&a, &b))| {
                    let blend = a + (b - a) * s;
                    (d + f64::from(e - blend).powi(2), n + f64::from(e).powi(2))
                });
        if total <= 0.0 {
            return 0.0;
        }
        (diff / total).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_bracket_is_the_interval_strictly_around_a_time() {
        let keys = [0.0, 1.0, 2.0];
        assert_eq!(bracket(&keys, 0.5), Some((0.0, 1.0)));
        assert_eq!(bracket(&keys, 1.5), Some((1.0, 2.0)));
        assert_eq!(bracket(&keys, 1.0), None);
        assert_eq!(bracket(&keys, 2.5), None);
        assert_eq!(bracket(&keys, -1.0), None);
    }
}
