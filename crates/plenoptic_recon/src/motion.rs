//! Object motion read from the pack: translation, rotation and scale tracks evaluated at any
//! time, giving the object-to-world transform the geometry mask and the motion-compensated
//! lookups need (p_τ = M(τ) M(t)⁻¹ p).
//!
//! The evaluation is the scene crate's (`plenoptic_scene::anim`, which the baker placed the
//! objects with), implemented here on the pack's own track type so that the runtime does not
//! depend on the scene importer:
//!
//! - before the first key a channel holds its first value, after the last key its last value;
//! - step holds the previous key; linear interpolates (slerp for rotations);
//! - cubic spline is the Hermite basis on glTF's (in-tangent, value, out-tangent) triples with
//!   tangents scaled by the key interval, rotations normalised afterwards;
//! - a missing channel keeps the identity (zero translation, no rotation, unit scale).

use glam::{Affine3A, Quat, Vec3, Vec4};
use plenoptic_pack::{Interpolation, ObjectTracks, Track};

/// Values a track interpolates.
trait Channel: Copy {
    fn lerp(a: Self, b: Self, s: f32) -> Self;
    fn hermite(terms: [(Self, f32); 4]) -> Self;
}

impl Channel for Vec3 {
    fn lerp(a: Self, b: Self, s: f32) -> Self {
        a.lerp(b, s)
    }
    fn hermite(terms: [(Self, f32); 4]) -> Self {
        terms.iter().fold(Vec3::ZERO, |acc, (v, w)| acc + *v * *w)
    }
}

impl Channel for Quat {
    fn lerp(a: Self, b: Self, s: f32) -> Self {
        a.slerp(b, s)
    }
    fn hermite(terms: [(Self, f32); 4]) -> Self {
        let v = terms
            .iter()
            .fold(Vec4::ZERO, |acc, (q, w)| acc + Vec4::from(*q) * *w);
        Quat::from_vec4(v).normalize()
    }
}

/// A track whose value count matches its key count (checked once, at construction).
#[derive(Clone, Debug, PartialEq)]
struct Checked<T>(Track<T>);

impl<T: Channel> Checked<T> {
    fn new(track: &Track<T>) -> Option<Self> {
        let n = track.times.len();
        (n > 0 && track.values.len() == n * track.interpolation.values_per_key())
            .then(|| Checked(track.clone()))
    }

    /// The value of key `i` (the middle of a cubic spline's triple).
    fn value(&self, i: usize) -> T {
        match self.0.interpolation {
            Interpolation::CubicSpline => self.0.values[3 * i + 1],
            _ => self.0.values[i],
        }
    }

    fn sample(&self, t: f32) -> T {
        let times = &self.0.times;
        let last = times.len() - 1;
        if t.is_nan() || t <= times[0] || last == 0 {
            return self.value(0);
        }
        if t >= times[last] {
            return self.value(last);
        }
        // The last key at or before t.
        let i = times.partition_point(|&k| k <= t).saturating_sub(1);
        let dt = times[i + 1] - times[i];
        if dt <= 0.0 {
            return self.value(i + 1);
        }
        let s = (t - times[i]) / dt;
        match self.0.interpolation {
            Interpolation::Step => self.value(i),
            Interpolation::Linear => T::lerp(self.value(i), self.value(i + 1), s),
            Interpolation::CubicSpline => {
                let v = &self.0.values;
                let (s2, s3) = (s * s, s * s * s);
                T::hermite([
                    (v[3 * i + 1], 2.0 * s3 - 3.0 * s2 + 1.0),
                    (v[3 * i + 2], (s3 - 2.0 * s2 + s) * dt),
                    (v[3 * i + 4], -2.0 * s3 + 3.0 * s2),
                    (v[3 * i + 3], (s3 - s2) * dt),
                ])
            }
        }
    }
}

/// The channels of an [`ObjectMotion`], borrowed ([`ObjectMotion::tracks`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MotionTracks<'a> {
    /// Translation, if the object has a usable one.
    pub translation: Option<&'a Track<Vec3>>,
    /// Rotation, if any.
    pub rotation: Option<&'a Track<Quat>>,
    /// Scale, if any.
    pub scale: Option<&'a Track<Vec3>>,
}

/// The motion of one object: its pack tracks, ready to be evaluated at any time.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ObjectMotion {
    translation: Option<Checked<Vec3>>,
    rotation: Option<Checked<Quat>>,
    scale: Option<Checked<Vec3>>,
}

impl ObjectMotion {
    /// The motion of `tracks`; a channel without keys, or with a value count that does not
    /// match its keys, is left out (it keeps the identity).
    pub fn new(tracks: &ObjectTracks) -> Self {
        ObjectMotion {
            translation: tracks.translation.as_ref().and_then(Checked::new),
            rotation: tracks.rotation.as_ref().and_then(Checked::new),
            scale: tracks.scale.as_ref().and_then(Checked::new),
        }
    }

    /// The channels kept (translation, rotation, scale), as the pack stores them.
    pub fn tracks(&self) -> MotionTracks<'_> {
        MotionTracks {
            translation: self.translation.as_ref().map(|c| &c.0),
            rotation: self.rotation.as_ref().map(|c| &c.0),
            scale: self.scale.as_ref().map(|c| &c.0),
        }
    }

    /// Translation, rotation and scale at time `t`.
    pub fn sample(&self, t: f32) -> (Vec3, Quat, Vec3) {
        (
            self.translation
                .as_ref()
                .map_or(Vec3::ZERO, |c| c.sample(t)),
            self.rotation
                .as_ref()
                .map_or(Quat::IDENTITY, |c| c.sample(t)),
            self.scale.as_ref().map_or(Vec3::ONE, |c| c.sample(t)),
        )
    }

    /// Whether the transform may change over time: some channel has two stored values that
    /// differ (conservative for cubic splines, whose tangents count as values).
    pub fn is_animated(&self) -> bool {
        fn moves<T: PartialEq>(t: &Track<T>) -> bool {
            t.values.windows(2).any(|w| w[0] != w[1])
        }
        let t = self.tracks();
        t.translation.is_some_and(moves)
            || t.rotation.is_some_and(moves)
            || t.scale.is_some_and(moves)
    }

    /// The object-to-world transform T·R·S at time `t`.
    pub fn transform(&self, t: f32) -> Affine3A {
        let (translation, rotation, scale) = self.sample(t);
        Affine3A::from_scale_rotation_translation(scale, rotation, translation)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn track<T>(interpolation: Interpolation, times: Vec<f32>, values: Vec<T>) -> Track<T> {
        Track {
            interpolation,
            times,
            values,
        }
    }

    #[test]
    fn linear_step_and_clamping() {
        let m = ObjectMotion::new(&ObjectTracks {
            object_id: 1,
            translation: Some(track(
                Interpolation::Linear,
                vec![0.0, 2.0],
                vec![Vec3::ZERO, Vec3::new(2.0, 0.0, 0.0)],
            )),
            rotation: None,
            scale: Some(track(
                Interpolation::Step,
                vec![0.0, 1.0],
                vec![Vec3::ONE, Vec3::splat(2.0)],
            )),
        });
        let (t, r, s) = m.sample(0.5);
        assert_eq!(
            (t, r, s),
            (Vec3::new(0.5, 0.0, 0.0), Quat::IDENTITY, Vec3::ONE)
        );
        assert_eq!(m.sample(1.5).2, Vec3::splat(2.0));
        assert_eq!(m.sample(-1.0).0, Vec3::ZERO);
        assert_eq!(m.sample(9.0).0, Vec3::new(2.0, 0.0, 0.0));
        assert_eq!(m.sample(f32::NAN).0, Vec3::ZERO);
        let p = m.transform(1.5).transform_point3(Vec3::ONE);
        assert!(p.abs_diff_eq(Vec3::new(3.5, 2.0, 2.0), 1e-6), "{p}");
    }

    #[test]
    fn cubic_spline_passes_its_keys_and_follows_tangents() {
        // x(t) = t³ on [0, 1]: x(0) = 0, x'(0) = 0, x(1) = 1, x'(1) = 3.
        let v = |x: f32| Vec3::new(x, 0.0, 0.0);
        let m = ObjectMotion::new(&ObjectTracks {
            object_id: 1,
            translation: Some(track(
                Interpolation::CubicSpline,
                vec![0.0, 1.0],
                vec![v(0.0), v(0.0), v(0.0), v(3.0), v(1.0), v(3.0)],
            )),
            rotation: Some(track(
                Interpolation::Linear,
                vec![0.0, 1.0],
                vec![Quat::IDENTITY, Quat::from_rotation_y(1.0)],
            )),
            scale: None,
        });
        for s in [0.0f32, 0.25, 0.5, 0.9, 1.0] {
            assert!((m.sample(s).0.x - s.powi(3)).abs() < 1e-5, "{s}");
        }
        assert!(
            m.sample(0.5)
                .1
                .abs_diff_eq(Quat::from_rotation_y(0.5), 1e-5)
        );
    }

    #[test]
    fn malformed_channels_keep_the_identity() {
        let m = ObjectMotion::new(&ObjectTracks {
            object_id: 1,
            translation: Some(track(Interpolation::CubicSpline, vec![0.0], vec![Vec3::X])),
            rotation: Some(track(Interpolation::Linear, vec![], vec![])),
            scale: None,
        });
        assert_eq!(m.transform(0.3), Affine3A::IDENTITY);
    }
}
