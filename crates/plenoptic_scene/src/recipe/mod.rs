//! The bake recipe: what to bake (scene files with placements), where the viewer may go (the
//! view space), when (the time range) and how well (quality), as TOML.
//!
//! The TOML deserialises into [`Recipe`], which mirrors the file (unknown keys are rejected),
//! and [`Recipe::validate`] checks it into a [`BakeRecipe`] with paths resolved against the
//! recipe's directory. Every validation error names the key:
//! `recipe.toml: view_space.max: must be greater than view_space.min on every axis`.
//!
//! ```toml
//! output = "out/house.pack"
//!
//! [[scene]]
//! file = "house.glb"
//! translation = [0.0, 0.0, 0.0]
//! rotation_deg = [0.0, 90.0, 0.0]   # or rotation = [x, y, z, w]
//! scale = [1.0, 1.0, 1.0]
//!
//! [view_space]
//! kind = "rectangle"                # "segment": a, b; "rectangle": min, max (x, z), y; "box": min, max
//! min = [-2.0, -3.0]
//! max = [2.0, 3.0]
//! y = 1.6
//!
//! [time]
//! start = 0.0
//! end = 10.0
//! frame_rate = 30.0
//!
//! [quality]
//! preset = "preview"                # draft, preview, production (default), final
//! q = 0.93                          # any Quality field overrides the preset
//! ```

pub mod daylight;
mod groups;
mod quality;

use std::path::{Path, PathBuf};

use glam::{EulerRot, Quat, Vec2, Vec3};
use serde::{Deserialize, Serialize};

pub use self::groups::{EmitterRef, LightGroupSpec, LightGroupToml, MAX_GROUPS};
pub use self::quality::{Preset, Quality};
use crate::error::RecipeError;
use crate::model::Trs;

/// A recipe as written in TOML, before validation.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Recipe {
    /// Where the pack is written, relative to the recipe.
    pub output: String,
    /// Scene files, merged in order.
    #[serde(default)]
    pub scene: Vec<SceneEntry>,
    /// Where the viewer may go.
    pub view_space: ViewSpaceToml,
    /// The time range.
    pub time: TimeToml,
    /// Quality preset and overrides.
    #[serde(default)]
    pub quality: QualityToml,
    /// A sun study (see [`daylight`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sun: Option<daylight::SunToml>,
    /// The environment (see [`daylight`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sky: Option<daylight::SkyToml>,
    /// Light groups (see [`LightGroupToml`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub light_group: Vec<LightGroupToml>,
}

/// One `[[scene]]` entry: a glTF file and its placement.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneEntry {
    /// `.gltf` or `.glb` file, relative to the recipe.
    pub file: String,
    /// Translation in metres.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub translation: Option<[f32; 3]>,
    /// Rotation as a quaternion `[x, y, z, w]`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rotation: Option<[f32; 4]>,
    /// Rotation as Euler angles in degrees `[x, y, z]`, applied as yaw about y, then pitch
    /// about x, then roll about z (intrinsic; `glam::EulerRot::YXZ`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rotation_deg: Option<[f32; 3]>,
    /// Scale per axis.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scale: Option<[f32; 3]>,
}

/// The `[view_space]` table; which keys apply depends on `kind`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ViewSpaceToml {
    /// `"segment"`, `"rectangle"` or `"box"`.
    pub kind: String,
    /// Segment: first end point.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub a: Option<[f32; 3]>,
    /// Segment: second end point.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub b: Option<[f32; 3]>,
    /// Rectangle: `[x, z]`; box: `[x, y, z]`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub min: Option<Vec<f32>>,
    /// Rectangle: `[x, z]`; box: `[x, y, z]`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max: Option<Vec<f32>>,
    /// Rectangle: eye height.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub y: Option<f32>,
}

/// The `[time]` table.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TimeToml {
    /// First time in seconds.
    pub start: f32,
    /// Last time in seconds.
    pub end: f32,
    /// Frames per second of playback (the finest time step worth baking).
    pub frame_rate: f32,
}

/// The `[quality]` table: a preset and optional overrides of any [`Quality`] field.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
#[allow(
    missing_docs,
    reason = "each field overrides the Quality field of the same name"
)]
pub struct QualityToml {
    /// `draft`, `preview`, `production` or `final`; `production` when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub preset: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub q: Option<f32>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub id_image_size: Option<u32>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub range_image_size: Option<u32>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_space_depth: Option<u32>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_time_depth: Option<u32>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub samples_per_pixel: Option<u32>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ambient_samples: Option<u32>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ambient_rms: Option<f32>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub temporal_volume_samples: Option<u32>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_specular_depth: Option<u32>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reference_samples_per_pixel: Option<u32>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub denoise: Option<bool>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub runtime_sun: Option<bool>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub runtime_lamps: Option<bool>,
}

/// A validated recipe.
#[derive(Debug, Clone, PartialEq)]
pub struct BakeRecipe {
    /// The recipe's name in messages (its file name).
    pub name: String,
    /// Scene files with their placements, paths resolved.
    pub scenes: Vec<SceneSource>,
    /// Where the viewer may go.
    pub view_space: ViewSpace,
    /// The time range.
    pub time: TimeRange,
    /// Quality settings: the preset with overrides applied.
    pub quality: Quality,
    /// The pack to write, path resolved.
    pub output: PathBuf,
    /// Sun study and sky.
    pub daylight: daylight::Daylight,
    /// Light groups, in recipe order (empty: one group holds every emitter).
    pub light_groups: Vec<LightGroupSpec>,
}

/// A scene file and its placement.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneSource {
    /// The file, resolved against the recipe's directory.
    pub path: PathBuf,
    /// Placement of the whole file in the baked world.
    pub transform: Trs,
}

/// Where the viewer may go (the thesis's view space).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ViewSpace {
    /// A line segment between two eye points.
    Segment {
        /// One end.
        a: Vec3,
        /// The other end.
        b: Vec3,
    },
    /// An axis-aligned rectangle in the x-z plane at eye height `y`.
    Rectangle {
        /// Smallest (x, z).
        min: Vec2,
        /// Largest (x, z).
        max: Vec2,
        /// Eye height.
        y: f32,
    },
    /// An axis-aligned box.
    Box {
        /// Smallest corner.
        min: Vec3,
        /// Largest corner.
        max: Vec3,
    },
}

impl ViewSpace {
    /// The corners of the view space: 2, 4 or 8 points.
    pub fn corners(&self) -> Vec<Vec3> {
        match *self {
            Self::Segment { a, b } => vec![a, b],
            Self::Rectangle { min, max, y } => vec![
                Vec3::new(min.x, y, min.y),
                Vec3::new(max.x, y, min.y),
                Vec3::new(max.x, y, max.y),
                Vec3::new(min.x, y, max.y),
            ],
            Self::Box { min, max } => (0..8)
                .map(|i| {
                    Vec3::new(
                        if i & 1 == 0 { min.x } else { max.x },
                        if i & 2 == 0 { min.y } else { max.y },
                        if i & 4 == 0 { min.z } else { max.z },
                    )
                })
                .collect(),
        }
    }
}

/// The baked time range.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TimeRange {
    /// First time in seconds.
    pub start: f32,
    /// Last time in seconds (equal to `start` for a static bake).
    pub end: f32,
    /// Frames per second.
    pub frame_rate: f32,
}

impl TimeRange {
    /// `end − start`.
    pub fn duration(&self) -> f32 {
        self.end - self.start
    }

    /// Frames in the range, both ends included.
    pub fn frame_count(&self) -> u32 {
        (self.duration() * self.frame_rate).floor() as u32 + 1
    }
}

impl Recipe {
    /// Reads, parses and validates the recipe at `path`; relative paths in it are resolved
    /// against its directory.
    pub fn from_path(path: &Path) -> Result<BakeRecipe, RecipeError> {
        let text = std::fs::read_to_string(path).map_err(|source| RecipeError::Io {
            file: path.to_owned(),
            source,
        })?;
        let name = path.display().to_string();
        let base = path.parent().unwrap_or(Path::new("."));
        Self::from_str_named(&text, &name, base)
    }

    /// Parses and validates recipe text; `name` names it in errors, `base_dir` resolves its
    /// relative paths.
    pub fn from_str_named(
        text: &str,
        name: &str,
        base_dir: &Path,
    ) -> Result<BakeRecipe, RecipeError> {
        Self::parse(text, name)?.validate_text(name, base_dir, Some(text))
    }

    /// Parses recipe text without validating it.
    pub fn parse(text: &str, name: &str) -> Result<Recipe, RecipeError> {
        toml::from_str(text).map_err(|e| RecipeError::Parse {
            file: name.to_owned(),
            message: e.to_string().trim_end().to_owned(),
        })
    }

    /// The recipe as TOML (parses back to an equal recipe).
    pub fn to_toml_string(&self) -> String {
        toml::to_string(self).expect("a recipe always serialises")
    }

    /// Checks every value and resolves paths against `base_dir`.
    pub fn validate(&self, name: &str, base_dir: &Path) -> Result<BakeRecipe, RecipeError> {
        self.validate_text(name, base_dir, None)
    }

    /// [`Recipe::validate`], with the recipe's `text` (when it was parsed from one) for the
    /// lines that errors about light groups name.
    fn validate_text(
        &self,
        name: &str,
        base_dir: &Path,
        text: Option<&str>,
    ) -> Result<BakeRecipe, RecipeError> {
        let err = |key: &str, problem: &str| RecipeError::Invalid {
            file: name.to_owned(),
            key: key.to_owned(),
            problem: problem.to_owned(),
        };
        let finite = |key: &str, values: &[f32]| {
            if values.iter().all(|v| v.is_finite()) {
                Ok(())
            } else {
                Err(err(key, "must be finite"))
            }
        };

        if self.output.trim().is_empty() {
            return Err(err("output", "must name the pack file"));
        }
        if self.scene.is_empty() {
            return Err(err("scene", "at least one [[scene]] is required"));
        }
        let mut scenes = Vec::with_capacity(self.scene.len());
        for (i, entry) in self.scene.iter().enumerate() {
            let key = |k: &str| format!("scene[{i}].{k}");
            if entry.file.trim().is_empty() {
                return Err(err(&key("file"), "must name a .gltf or .glb file"));
            }
            let translation = Vec3::from_array(entry.translation.unwrap_or([0.0; 3]));
            finite(&key("translation"), &translation.to_array())?;
            let rotation = match (entry.rotation, entry.rotation_deg) {
                (Some(_), Some(_)) => {
                    return Err(err(
                        &key("rotation"),
                        "give either rotation or rotation_deg, not both",
                    ));
                }
                (Some(q), None) => {
                    finite(&key("rotation"), &q)?;
                    let q = Quat::from_array(q);
                    if q.length() < 1e-6 {
                        return Err(err(&key("rotation"), "quaternion must not be zero"));
                    }
                    q.normalize()
                }
                (None, Some(d)) => {
                    finite(&key("rotation_deg"), &d)?;
                    let [x, y, z] = d.map(f32::to_radians);
                    Quat::from_euler(EulerRot::YXZ, y, x, z)
                }
                (None, None) => Quat::IDENTITY,
            };
            let scale = Vec3::from_array(entry.scale.unwrap_or([1.0; 3]));
            finite(&key("scale"), &scale.to_array())?;
            if scale.to_array().contains(&0.0) {
                return Err(err(&key("scale"), "must not be zero on any axis"));
            }
            scenes.push(SceneSource {
                path: base_dir.join(&entry.file),
                transform: Trs {
                    translation,
                    rotation,
                    scale,
                },
            });
        }

        let view_space = self.view_space.validate(&err)?;

        let t = &self.time;
        finite("time.start", &[t.start])?;
        finite("time.end", &[t.end])?;
        if t.end < t.start {
            return Err(err("time.end", "must not be before time.start"));
        }
        if !(t.frame_rate.is_finite() && t.frame_rate > 0.0) {
            return Err(err("time.frame_rate", "must be positive"));
        }

        let quality = self.quality.validate(&err)?;
        let daylight = daylight::validate(self.sun.as_ref(), self.sky.as_ref(), base_dir, &err)?;
        let light_groups = groups::validate(&self.light_group, text, &err)?;
        Ok(BakeRecipe {
            name: name.to_owned(),
            scenes,
            view_space,
            time: TimeRange {
                start: t.start,
                end: t.end,
                frame_rate: t.frame_rate,
            },
            quality,
            output: base_dir.join(&self.output),
            daylight,
            light_groups,
        })
    }
}

type ErrFn<'a> = dyn Fn(&str, &str) -> RecipeError + 'a;

impl ViewSpaceToml {
    fn validate(&self, err: &ErrFn) -> Result<ViewSpace, RecipeError> {
        let unused = |key: &str, present: bool| {
            if present {
                Err(err(
                    &format!("view_space.{key}"),
                    &format!("not used by kind = \"{}\"", self.kind),
                ))
            } else {
                Ok(())
            }
        };
        let required =
            |key: &str, v: Option<Vec<f32>>, n: usize| -> Result<Vec<f32>, RecipeError> {
                let full = format!("view_space.{key}");
                let v =
                    v.ok_or_else(|| err(&full, &format!("required for kind = \"{}\"", self.kind)))?;
                if v.len() != n {
                    return Err(err(
                        &full,
                        &format!("must have {n} components, found {}", v.len()),
                    ));
                }
                if v.iter().any(|x| !x.is_finite()) {
                    return Err(err(&full, "must be finite"));
                }
                Ok(v)
            };
        let ordered = |min: &[f32], max: &[f32]| {
            if min.iter().zip(max).all(|(a, b)| b > a) {
                Ok(())
            } else {
                Err(err(
                    "view_space.max",
                    "must be greater than view_space.min on every axis",
                ))
            }
        };
        match self.kind.as_str() {
            "segment" => {
                unused("min", self.min.is_some())?;
                unused("max", self.max.is_some())?;
                unused("y", self.y.is_some())?;
                let a = Vec3::from_slice(&required("a", self.a.map(Vec::from), 3)?);
                let b = Vec3::from_slice(&required("b", self.b.map(Vec::from), 3)?);
                if a == b {
                    return Err(err("view_space.b", "must differ from view_space.a"));
                }
                Ok(ViewSpace::Segment { a, b })
            }
            "rectangle" => {
                unused("a", self.a.is_some())?;
                unused("b", self.b.is_some())?;
                let min = required("min", self.min.clone(), 2)?;
                let max = required("max", self.max.clone(), 2)?;
                let y = required("y", self.y.map(|y| vec![y]), 1)?[0];
                ordered(&min, &max)?;
                Ok(ViewSpace::Rectangle {
                    min: Vec2::from_slice(&min),
                    max: Vec2::from_slice(&max),
                    y,
                })
            }
            "box" => {
                unused("a", self.a.is_some())?;
                unused("b", self.b.is_some())?;
                unused("y", self.y.is_some())?;
                let min = required("min", self.min.clone(), 3)?;
                let max = required("max", self.max.clone(), 3)?;
                ordered(&min, &max)?;
                Ok(ViewSpace::Box {
                    min: Vec3::from_slice(&min),
                    max: Vec3::from_slice(&max),
                })
            }
            other => Err(err(
                "view_space.kind",
                &format!(
                    "unknown kind \"{other}\"; expected \"segment\", \"rectangle\" or \"box\""
                ),
            )),
        }
    }
}

impl QualityToml {
    fn validate(&self, err: &ErrFn) -> Result<Quality, RecipeError> {
        let preset = match &self.preset {
            None => Preset::Production,
            Some(name) => Preset::from_name(name).ok_or_else(|| {
                err(
                    "quality.preset",
                    &format!(
                        "unknown preset \"{name}\"; expected draft, preview, production or final"
                    ),
                )
            })?,
        };
        let mut q = preset.quality();
        macro_rules! apply {
            ($($field:ident),*) => {$(
                if let Some(v) = self.$field {
                    q.$field = v;
                }
            )*};
        }
        apply!(
            q,
            id_image_size,
            range_image_size,
            max_space_depth,
            max_time_depth,
            samples_per_pixel,
            ambient_samples,
            ambient_rms,
            temporal_volume_samples,
            max_specular_depth,
            reference_samples_per_pixel,
            denoise,
            runtime_sun,
            runtime_lamps
        );
        check_quality(&q, err)?;
        Ok(q)
    }
}

/// Checks the ranges of every quality field, naming the `quality.` key.
pub(crate) fn check_quality(q: &Quality, err: &ErrFn) -> Result<(), RecipeError> {
    if !(0.0..=1.0).contains(&q.q) {
        return Err(err("quality.q", "must be in [0, 1]"));
    }
    if !(q.ambient_rms.is_finite() && q.ambient_rms > 0.0) {
        return Err(err("quality.ambient_rms", "must be positive"));
    }
    for (key, value, max) in [
        ("id_image_size", q.id_image_size, 16_384),
        ("range_image_size", q.range_image_size, 16_384),
        ("samples_per_pixel", q.samples_per_pixel, 1 << 20),
        ("ambient_samples", q.ambient_samples, 1 << 20),
        (
            "temporal_volume_samples",
            q.temporal_volume_samples,
            1 << 30,
        ),
        (
            "reference_samples_per_pixel",
            q.reference_samples_per_pixel,
            1 << 20,
        ),
    ] {
        if value == 0 || value > max {
            return Err(err(
                &format!("quality.{key}"),
                &format!("must be in 1..={max}"),
            ));
        }
    }
    for (key, value) in [
        ("max_space_depth", q.max_space_depth),
        ("max_time_depth", q.max_time_depth),
    ] {
        if value > 24 {
            return Err(err(&format!("quality.{key}"), "must be at most 24"));
        }
    }
    if q.max_specular_depth > 64 {
        return Err(err("quality.max_specular_depth", "must be at most 64"));
    }
    Ok(())
}
