//! Camera paths: the file format shared by `plenoptic render` (reconstruction) and
//! `plenoptic reference` (the reference path tracer), so both render the same frames.
//!
//! # Format (JSON)
//!
//! ```json
//! {
//!   "frame_rate": 24.0,
//!   "width": 640, "height": 360,
//!   "keyframes": [
//!     { "time": 0.0, "position": [0.0, 1.4, 2.0], "yaw_deg": 0.0, "pitch_deg": -10.0,
//!       "vfov_deg": 60.0, "scene_time": 0.0 },
//!     { "time": 2.0, "position": [1.0, 1.4, 2.0], "orientation": [0.0, 0.0, 0.0, 1.0],
//!       "vfov_deg": 60.0, "scene_time": 1.0 }
//!   ]
//! }
//! ```
//!
//! - `time`: seconds along the path (strictly increasing over the keyframes).
//! - `position`: camera position, world space (metres).
//! - orientation: either `orientation` (a unit quaternion `[x, y, z, w]` in the camera
//!   convention of [`crate::camera::Camera`]: looks along −Z, +Y up) or `yaw_deg` /
//!   `pitch_deg` (yaw about +Y, 0 looks along −Z, positive turns left towards −X; pitch
//!   positive looks up). If both are given the quaternion wins.
//! - `vfov_deg`: vertical field of view, degrees (default 60).
//! - `scene_time`: the animation time shown at this keyframe (default: `time`).
//! - `frame_rate`, `width`, `height`: frames per path second and resolution.
//!
//! Sampling: position by centripetal-free uniform Catmull-Rom through the keyframes
//! (end segments use the end points as their own neighbours), orientation by slerp between the
//! bracketing keyframes, field of view and scene time linearly. Frame `i` is at path time
//! `start + i / frame_rate`, for every such time ≤ the last keyframe's time.

use std::path::Path;

use glam::{Quat, Vec3};
use serde::{Deserialize, Serialize};

use crate::camera::Camera;
use crate::{Error, Result};

/// One keyframe of a [`CameraPath`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Keyframe {
    /// Path time, seconds.
    pub time: f32,
    /// Camera position, world space.
    pub position: [f32; 3],
    /// Orientation quaternion `[x, y, z, w]` (wins over yaw/pitch).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub orientation: Option<[f32; 4]>,
    /// Yaw about +Y in degrees (0 looks along −Z).
    #[serde(default)]
    pub yaw_deg: f32,
    /// Pitch in degrees (positive looks up).
    #[serde(default)]
    pub pitch_deg: f32,
    /// Vertical field of view, degrees.
    #[serde(default = "default_vfov")]
    pub vfov_deg: f32,
    /// Animation time shown at this keyframe (default: `time`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scene_time: Option<f32>,
}

fn default_vfov() -> f32 {
    60.0
}

impl Keyframe {
    /// A keyframe looking from `position` towards `target` (+Y up).
    pub fn looking_at(
        time: f32,
        position: Vec3,
        target: Vec3,
        vfov_deg: f32,
        scene_time: f32,
    ) -> Self {
        let f = (target - position).normalize_or(-Vec3::Z);
        let yaw = (-f.x).atan2(-f.z).to_degrees();
        let pitch = f.y.clamp(-1.0, 1.0).asin().to_degrees();
        Keyframe {
            time,
            position: position.to_array(),
            orientation: None,
            yaw_deg: yaw,
            pitch_deg: pitch,
            vfov_deg,
            scene_time: Some(scene_time),
        }
    }

    /// The keyframe's orientation quaternion.
    pub fn rotation(&self) -> Quat {
        match self.orientation {
            Some(q) => Quat::from_array(q).normalize(),
            None => {
                Quat::from_rotation_y(self.yaw_deg.to_radians())
                    * Quat::from_rotation_x(self.pitch_deg.to_radians())
            }
        }
    }

    fn scene_t(&self) -> f32 {
        self.scene_time.unwrap_or(self.time)
    }
}

/// A camera path: keyframes, frame rate, resolution. See the module doc for the file format.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CameraPath {
    /// Frames per path second (> 0).
    pub frame_rate: f32,
    /// Frame width, pixels.
    pub width: u32,
    /// Frame height, pixels.
    pub height: u32,
    /// Keyframes in increasing `time`.
    pub keyframes: Vec<Keyframe>,
}

/// One sample of a path: the camera and the animation time it shows.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathSample {
    /// Frame index (for [`CameraPath::frames`]; 0 for [`CameraPath::sample`]).
    pub index: usize,
    /// Path time, seconds.
    pub path_time: f32,
    /// The camera.
    pub camera: Camera,
    /// The scene (animation) time.
    pub scene_time: f32,
}

impl CameraPath {
    /// Parses and validates a path from JSON text.
    pub fn from_json(text: &str) -> Result<Self> {
        let p: CameraPath =
            serde_json::from_str(text).map_err(|e| Error::Path(format!("camera path: {e}")))?;
        p.validate()?;
        Ok(p)
    }

    /// Reads a path file (JSON).
    pub fn load(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path)
            .map_err(|e| Error::Path(format!("cannot read camera path {}: {e}", path.display())))?;
        Self::from_json(&text).map_err(|e| Error::Path(format!("{}: {e}", path.display())))
    }

    /// Writes the path as pretty JSON.
    pub fn save(&self, path: impl AsRef<Path>) -> Result<()> {
        let path = path.as_ref();
        let text = serde_json::to_string_pretty(self).map_err(|e| Error::Path(e.to_string()))?;
        std::fs::write(path, text).map_err(|e| Error::Io(format!("{}: {e}", path.display())))
    }

    /// Checks: at least one keyframe, increasing finite times, positive frame rate and
    /// resolution, fields of view in (0, 180).
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(Error::Path(m));
        if self.keyframes.is_empty() {
            return bad("camera path has no keyframes".into());
        }
        if !(self.frame_rate.is_finite() && self.frame_rate > 0.0) {
            return bad(format!("frame rate {} is not positive", self.frame_rate));
        }
        if self.width == 0 || self.height == 0 {
            return bad(format!(
                "resolution {}×{} is empty",
                self.width, self.height
            ));
        }
        for (i, k) in self.keyframes.iter().enumerate() {
            if !k.time.is_finite() || !Vec3::from_array(k.position).is_finite() {
                return bad(format!("keyframe {i} has a non-finite time or position"));
            }
            if !(k.vfov_deg > 0.0 && k.vfov_deg < 180.0) {
                return bad(format!(
                    "keyframe {i}: vfov_deg {} outside (0, 180)",
                    k.vfov_deg
                ));
            }
            if i > 0 && k.time <= self.keyframes[i - 1].time {
                return bad(format!("keyframe {i}: times must increase"));
            }
        }
        Ok(())
    }

    /// First and last keyframe times.
    pub fn time_range(&self) -> (f32, f32) {
        let f = self.keyframes.first().map_or(0.0, |k| k.time);
        let l = self.keyframes.last().map_or(0.0, |k| k.time);
        (f, l)
    }

    /// Number of frames [`CameraPath::frames`] yields.
    pub fn frame_count(&self) -> usize {
        let (a, b) = self.time_range();
        ((b - a) * self.frame_rate + 1e-4).floor().max(0.0) as usize + 1
    }

    /// The camera and scene time at path time `s` (clamped to the keyframes' range).
    pub fn sample(&self, s: f32) -> PathSample {
        let k = &self.keyframes;
        let (a, b) = self.time_range();
        let s = if s.is_finite() { s.clamp(a, b) } else { a };
        let i = k
            .partition_point(|kf| kf.time <= s)
            .saturating_sub(1)
            .min(k.len() - 1);
        let j = (i + 1).min(k.len() - 1);
        let u = if j == i {
            0.0
        } else {
            (s - k[i].time) / (k[j].time - k[i].time)
        };
        let pos = |n: usize| Vec3::from_array(k[n].position);
        let p0 = pos(i.saturating_sub(1));
        let (p1, p2) = (pos(i), pos(j));
        let p3 = pos((j + 1).min(k.len() - 1));
        let position = catmull_rom(p0, p1, p2, p3, u);
        let (r1, mut r2) = (k[i].rotation(), k[j].rotation());
        if r1.dot(r2) < 0.0 {
            r2 = -r2;
        }
        let orientation = r1.slerp(r2, u).normalize();
        let vfov = (k[i].vfov_deg + (k[j].vfov_deg - k[i].vfov_deg) * u).to_radians();
        let scene_time = k[i].scene_t() + (k[j].scene_t() - k[i].scene_t()) * u;
        PathSample {
            index: 0,
            path_time: s,
            camera: Camera {
                position,
                orientation,
                vfov,
                width: self.width,
                height: self.height,
            },
            scene_time,
        }
    }

    /// `n` samples spread evenly over the whole path, first and last keyframe included,
    /// numbered 0..n (one sample, the first keyframe's, for `n` ≤ 1).
    pub fn spread(&self, n: usize) -> Vec<PathSample> {
        let (start, end) = self.time_range();
        if n <= 1 {
            return vec![self.sample(start)];
        }
        (0..n)
            .map(|i| PathSample {
                index: i,
                ..self.sample(start + (end - start) * i as f32 / (n - 1) as f32)
            })
            .collect()
    }

    /// Every frame of the path, at `frame_rate`.
    pub fn frames(&self) -> impl Iterator<Item = PathSample> + '_ {
        let start = self.time_range().0;
        (0..self.frame_count()).map(move |i| PathSample {
            index: i,
            ..self.sample(start + i as f32 / self.frame_rate)
        })
    }
}

fn catmull_rom(p0: Vec3, p1: Vec3, p2: Vec3, p3: Vec3, u: f32) -> Vec3 {
    let (u2, u3) = (u * u, u * u * u);
    0.5 * ((2.0 * p1)
        + (p2 - p0) * u
        + (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) * u2
        + (3.0 * p1 - p0 - 3.0 * p2 + p3) * u3)
}

#[cfg(test)]
mod tests {
    use super::*;

    const EXAMPLE: &str = r#"{
      "frame_rate": 4.0, "width": 64, "height": 36,
      "keyframes": [
        { "time": 0.0, "position": [0.0, 1.4, 2.0], "yaw_deg": 0.0, "pitch_deg": 0.0, "scene_time": 0.0 },
        { "time": 1.0, "position": [1.0, 1.4, 2.0], "orientation": [0.0, 0.0, 0.0, 1.0], "vfov_deg": 50.0, "scene_time": 2.0 }
      ]
    }"#;

    #[test]
    fn parses_samples_and_round_trips() {
        let p = CameraPath::from_json(EXAMPLE).unwrap();
        assert_eq!(p.frame_count(), 5);
        let frames: Vec<_> = p.frames().collect();
        assert_eq!(frames.len(), 5);
        assert!(
            frames[0]
                .camera
                .position
                .abs_diff_eq(Vec3::new(0.0, 1.4, 2.0), 1e-6)
        );
        assert!(
            frames[4]
                .camera
                .position
                .abs_diff_eq(Vec3::new(1.0, 1.4, 2.0), 1e-6)
        );
        assert!((frames[2].scene_time - 1.0).abs() < 1e-6);
        assert!((frames[4].camera.vfov - 50f32.to_radians()).abs() < 1e-6);
        let text = serde_json::to_string(&p).unwrap();
        assert_eq!(CameraPath::from_json(&text).unwrap(), p);
        assert!(
            CameraPath::from_json(r#"{"frame_rate":1,"width":1,"height":1,"keyframes":[]}"#)
                .is_err()
        );
    }

    #[test]
    fn yaw_pitch_convention() {
        let k = Keyframe::looking_at(0.0, Vec3::ZERO, Vec3::new(-1.0, 0.0, 0.0), 60.0, 0.0);
        assert!((k.rotation() * -Vec3::Z).abs_diff_eq(-Vec3::X, 1e-5));
        let k = Keyframe::looking_at(0.0, Vec3::ZERO, Vec3::new(0.0, 1.0, -1.0), 60.0, 0.0);
        let f = k.rotation() * -Vec3::Z;
        assert!(f.abs_diff_eq(Vec3::new(0.0, 1.0, -1.0).normalize(), 1e-5));
    }
}
