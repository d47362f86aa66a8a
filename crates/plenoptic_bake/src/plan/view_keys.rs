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

use glam::Vec3;
use plenoptic_pack::cube::texel_direction;
use plenoptic_trace::image::luminance;
use plenoptic_trace::{AmbientField, Ray, SceneAccel};
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
    loop {
        let worst = times
            .iter()
            .enumerate()
            .filter_map(|(i, &t)| {
                let bracket = bracket(&keys, t)?;
                Some((
                    t,
                    bend(accel, position, t, &fields[i], bracket, times, fields),
                ))
            })
            .max_by(|a, b| a.1.total_cmp(&b.1));
        match worst {
            Some((t, err)) if err > f64::from(LERP_RMS) => {
                let at = keys.partition_point(|&k| k < t);
                keys.insert(at, t);
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

/// Relative RMS difference, over the probe cube's hits at `t`, between `field` (the field at
/// `t`) and the linear blend of the fields at the ends of `(t0, t1)`.
fn bend(
    accel: &SceneAccel<'_>,
    position: Vec3,
    t: f32,
    field: &AmbientField,
    (t0, t1): (f32, f32),
    times: &[f32],
    fields: &[AmbientField],
) -> f64 {
    let placed = accel.at_time(t);
    let (a, b) = (field_at(times, fields, t0), field_at(times, fields, t1));
    let s = (t - t0) / (t1 - t0);
    let texels = 6 * PROBE_FACE * PROBE_FACE;
    let (diff, total) = (0..texels)
        .into_par_iter()
        .filter_map(|i| {
            let dir = texel_direction(PROBE_FACE, i as usize);
            let hit = placed.intersect(&Ray::new(position, dir))?;
            let at = |f: &AmbientField| f.irradiance_seen(&placed, &hit, -dir);
            let e = at(field);
            let blend = at(&a).lerp(at(&b), s);
            Some((
                f64::from(luminance(e - blend)).powi(2),
                f64::from(luminance(e)).powi(2),
            ))
        })
        .reduce(|| (0.0, 0.0), |x, y| (x.0 + y.0, x.1 + y.1));
    if total <= 0.0 {
        return 0.0;
    }
    (diff / total).sqrt()
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
