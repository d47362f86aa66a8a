//! Node animation: translation, rotation and scale tracks with glTF's three interpolation
//! modes, evaluated at any time.
//!
//! Before the first key a track holds its first value and after the last key its last value.
//! Cubic-spline tracks store, like glTF, an (in-tangent, value, out-tangent) triple per key and
//! use the Hermite basis with tangents scaled by the key interval; rotations are normalised
//! after cubic interpolation and spherically interpolated in linear mode.

use glam::{Quat, Vec3, Vec4};

use crate::model::Trs;

/// How a track interpolates between keys.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Interpolation {
    /// The value of the previous key holds until the next key.
    Step,
    /// Linear (spherical linear for rotations).
    Linear,
    /// Cubic Hermite spline with per-key in- and out-tangents.
    CubicSpline,
}

/// The value of one key: for cubic splines the tangents travel with it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Key<T> {
    /// Key time in seconds.
    pub time: f32,
    /// The value at the key.
    pub value: T,
    /// Incoming tangent (cubic spline only; zero otherwise).
    pub in_tangent: T,
    /// Outgoing tangent (cubic spline only; zero otherwise).
    pub out_tangent: T,
}

/// A keyframed track of one property.
#[derive(Debug, Clone, PartialEq)]
pub struct Track<T> {
    /// Interpolation mode.
    pub interpolation: Interpolation,
    /// Keys in increasing time order (checked on import).
    pub keys: Vec<Key<T>>,
}

/// Values a track can interpolate.
pub trait Animatable: Copy {
    /// Linear interpolation from `a` to `b` at `s` in [0, 1].
    fn lerp(a: Self, b: Self, s: f32) -> Self;
    /// `a·wa + b·wb + c·wc + d·wd`, for the Hermite basis.
    fn combine(terms: [(Self, f32); 4]) -> Self;
    /// Brings a cubic result back to the value's domain (normalises quaternions).
    fn finish(self) -> Self {
        self
    }
}

impl Animatable for Vec3 {
    fn lerp(a: Self, b: Self, s: f32) -> Self {
        a.lerp(b, s)
    }
    fn combine(terms: [(Self, f32); 4]) -> Self {
        terms.iter().fold(Vec3::ZERO, |acc, (v, w)| acc + *v * *w)
    }
}

impl Animatable for Quat {
    fn lerp(a: Self, b: Self, s: f32) -> Self {
        a.slerp(b, s)
    }
    fn combine(terms: [(Self, f32); 4]) -> Self {
        let v = terms
            .iter()
            .fold(Vec4::ZERO, |acc, (q, w)| acc + Vec4::from(*q) * *w);
        Quat::from_vec4(v)
    }
    fn finish(self) -> Self {
        self.normalize()
    }
}

impl<T: Animatable> Track<T> {
    /// The track's value at time `t`, or `None` for a track without keys.
    pub fn sample(&self, t: f32) -> Option<T> {
        let keys = &self.keys;
        let first = keys.first()?;
        let last = keys.last()?;
        if t.is_nan() || t <= first.time || keys.len() == 1 {
            return Some(first.value);
        }
        if t >= last.time {
            return Some(last.value);
        }
        // The last key at or before t.
        let i = keys.partition_point(|k| k.time <= t).saturating_sub(1);
        let (k0, k1) = (&keys[i], &keys[i + 1]);
        let dt = k1.time - k0.time;
        if dt <= 0.0 {
            return Some(k1.value);
        }
        let s = (t - k0.time) / dt;
        Some(match self.interpolation {
            Interpolation::Step => k0.value,
            Interpolation::Linear => T::lerp(k0.value, k1.value, s),
            Interpolation::CubicSpline => {
                let (s2, s3) = (s * s, s * s * s);
                T::combine([
                    (k0.value, 2.0 * s3 - 3.0 * s2 + 1.0),
                    (k0.out_tangent, (s3 - 2.0 * s2 + s) * dt),
                    (k1.value, -2.0 * s3 + 3.0 * s2),
                    (k1.in_tangent, (s3 - s2) * dt),
                ])
                .finish()
            }
        })
    }

    /// First and last key times.
    pub fn time_range(&self) -> Option<(f32, f32)> {
        Some((self.keys.first()?.time, self.keys.last()?.time))
    }
}

/// The animation of one node: any of translation, rotation and scale.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct TrsTrack {
    /// Translation track.
    pub translation: Option<Track<Vec3>>,
    /// Rotation track.
    pub rotation: Option<Track<Quat>>,
    /// Scale track.
    pub scale: Option<Track<Vec3>>,
}

impl TrsTrack {
    /// The local transform at `t`; properties without a track keep their `rest` value.
    pub fn sample(&self, t: f32, rest: Trs) -> Trs {
        Trs {
            translation: self
                .translation
                .as_ref()
                .and_then(|k| k.sample(t))
                .unwrap_or(rest.translation),
            rotation: self
                .rotation
                .as_ref()
                .and_then(|k| k.sample(t))
                .unwrap_or(rest.rotation),
            scale: self
                .scale
                .as_ref()
                .and_then(|k| k.sample(t))
                .unwrap_or(rest.scale),
        }
    }

    /// The span of all keys of the three tracks.
    pub fn time_range(&self) -> Option<(f32, f32)> {
        [
            self.translation.as_ref().and_then(Track::time_range),
            self.rotation.as_ref().and_then(Track::time_range),
            self.scale.as_ref().and_then(Track::time_range),
        ]
        .into_iter()
        .flatten()
        .reduce(|(a0, b0), (a1, b1)| (a0.min(a1), b0.max(b1)))
    }
}

impl<T: Animatable> Track<T> {
    /// A step track from `(time, value)` keys.
    pub fn step(keys: impl IntoIterator<Item = (f32, T)>) -> Self {
        Self::simple(Interpolation::Step, keys)
    }

    /// A linear track (spherical linear for rotations) from `(time, value)` keys.
    pub fn linear(keys: impl IntoIterator<Item = (f32, T)>) -> Self {
        Self::simple(Interpolation::Linear, keys)
    }

    /// A cubic-spline track from `(time, in_tangent, value, out_tangent)` keys, the order glTF
    /// stores them in.
    pub fn cubic_spline(keys: impl IntoIterator<Item = (f32, T, T, T)>) -> Self {
        Self {
            interpolation: Interpolation::CubicSpline,
            keys: keys
                .into_iter()
                .map(|(time, in_tangent, value, out_tangent)| Key {
                    time,
                    value,
                    in_tangent,
                    out_tangent,
                })
                .collect(),
        }
    }

    fn simple(interpolation: Interpolation, keys: impl IntoIterator<Item = (f32, T)>) -> Self {
        Self {
            interpolation,
            keys: keys
                .into_iter()
                .map(|(time, value)| {
                    // The zero of T: any value with weight zero.
                    let zero = T::combine([(value, 0.0); 4]);
                    Key {
                        time,
                        value,
                        in_tangent: zero,
                        out_tangent: zero,
                    }
                })
                .collect(),
        }
    }
}
