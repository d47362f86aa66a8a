//! The manifest: everything about a pack that is not a chunk, stored as UTF-8 JSON (see
//! `docs/pack-format.md`, "Manifest").

use std::collections::BTreeMap;

use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::environment::EnvironmentEntry;
use crate::error::{PackError, Result};
use crate::material::{MaterialEntry, TextureEntry};

/// Largest manifest the reader accepts, in bytes.
pub const MAX_MANIFEST_BYTES: u64 = 64 << 20;

/// Everything a reader needs to know about the pack besides its chunks.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Manifest {
    /// Units of every length, time and radiance value in the pack.
    pub units: Units,
    /// Axis-aligned bounds of the whole scene over the whole time range, metres.
    pub scene_bounds: Aabb,
    /// The region of space the camera may move in.
    pub view_space: ViewSpace,
    /// The animation's time range, seconds.
    pub time_range: TimeRange,
    /// Length of one temporal-volume time bucket, seconds (> 0). Bucket `i` covers
    /// `[start + i·span, start + (i+1)·span)`; see [`Manifest::bucket_of`].
    pub bucket_span: f32,
    /// The base views. Directory rows refer to them by index in this list.
    pub base_views: Vec<BaseView>,
    /// The objects of the scene.
    pub objects: Vec<ObjectEntry>,
    /// The lights of the scene.
    pub lights: Vec<Light>,
    /// The settings the pack was baked with.
    pub bake: BakeSettings,
    /// What the bake measured.
    pub stats: BakeStatistics,
    /// The environment rays that leave the scene see, and the sun's track (version 1.1;
    /// absent in older packs and in packs without an environment).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub environment: Option<EnvironmentEntry>,
    /// The material textures (version 1.2; empty in older packs): entry `i` is the
    /// [`crate::ChunkKind::MaterialTexture`] chunk with key `i`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub textures: Vec<TextureEntry>,
    /// The materials objects refer to (version 1.2; empty in older packs).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub materials: Vec<MaterialEntry>,
    /// The light groups stored apart and each emitter's group (version 4.2; absent: one
    /// group, [`crate::groups`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub light_groups: Option<crate::LightGroupsEntry>,
    /// Whether the lighting and the volume samples' lighting leave out the direct diffuse
    /// light of the point and spot lights (version 5.0), which the runtime adds per pixel
    /// with a shadow ray against the proxies. True only where every such light is `placed`.
    /// Absent (every older pack): the lamps' light is stored.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub lamps_at_runtime: bool,
}

impl Manifest {
    /// A manifest with no views, objects or lights over `time_range`, with default units,
    /// empty bounds, a point-like segment view space and the given bucket span.
    pub fn new(time_range: TimeRange, bucket_span: f32) -> Self {
        Manifest {
            units: Units::default(),
            scene_bounds: Aabb::default(),
            view_space: ViewSpace::Segment {
                a: Vec3::ZERO,
                b: Vec3::ZERO,
            },
            time_range,
            bucket_span,
            base_views: Vec::new(),
            objects: Vec::new(),
            lights: Vec::new(),
            bake: BakeSettings::default(),
            stats: BakeStatistics::default(),
            environment: None,
            textures: Vec::new(),
            materials: Vec::new(),
            light_groups: None,
            lamps_at_runtime: false,
        }
    }

    /// The time bucket holding time `t` (clamped to bucket 0 before the start; a non-finite `t`
    /// or a non-positive span gives bucket 0).
    pub fn bucket_of(&self, t: f32) -> u32 {
        let b = (t - self.time_range.start) / self.bucket_span;
        if b.is_finite() && b > 0.0 {
            b.floor().min(u32::MAX as f32) as u32
        } else {
            0
        }
    }

    /// The time interval `[start, end)` that bucket `index` covers.
    pub fn bucket_range(&self, index: u32) -> (f32, f32) {
        let s = self.time_range.start + index as f32 * self.bucket_span;
        (s, s + self.bucket_span)
    }

    /// Number of buckets covering the time range (at least 1).
    pub fn bucket_count(&self) -> u32 {
        self.bucket_of(self.time_range.end).saturating_add(1)
    }

    /// Serializes the manifest as compact JSON.
    pub fn to_json(&self) -> Result<Vec<u8>> {
        serde_json::to_vec(self).map_err(|e| PackError::input(format!("manifest: {e}")))
    }

    /// Parses the manifest from JSON (capped at [`MAX_MANIFEST_BYTES`]).
    pub fn from_json(bytes: &[u8]) -> Result<Self> {
        if bytes.len() as u64 > MAX_MANIFEST_BYTES {
            return Err(PackError::CountTooLarge {
                what: "manifest bytes",
                count: bytes.len() as u64,
                max: MAX_MANIFEST_BYTES,
            });
        }
        let m: Manifest =
            serde_json::from_slice(bytes).map_err(|e| PackError::InvalidManifest {
                reason: e.to_string(),
            })?;
        m.validate()?;
        Ok(m)
    }

    /// Checks the values serde cannot: finite, ordered times and a positive bucket span.
    pub fn validate(&self) -> Result<()> {
        let bad = |reason: String| Err(PackError::InvalidManifest { reason });
        let (s, e) = (self.time_range.start, self.time_range.end);
        if !(s.is_finite() && e.is_finite() && s <= e) {
            return bad(format!(
                "time range {s}..{e} is not a finite, ordered interval"
            ));
        }
        if !(self.bucket_span.is_finite() && self.bucket_span > 0.0) {
            return bad(format!("bucket span {} is not positive", self.bucket_span));
        }
        for (i, v) in self.base_views.iter().enumerate() {
            if v.time_keys.iter().any(|t| !t.is_finite()) {
                return bad(format!("base view {i} has a non-finite time key"));
            }
        }
        for o in &self.objects {
            if let Some(c) = o.coverage
                && !(c > 0.0 && c < 1.0)
            {
                return bad(format!(
                    "object {} ({:?}) has coverage {c}, outside (0, 1)",
                    o.id, o.name
                ));
            }
        }
        if let Some(g) = &self.light_groups {
            g.validate(self.lights.len(), self.objects.len())
                .or_else(&bad)?;
        }
        for (i, l) in self.lights.iter().enumerate() {
            if let Some(p) = &l.placed {
                let unit = (p.direction.length() - 1.0).abs() < 1e-3;
                let range = p.range.is_none_or(|r| r.is_finite() && r > 0.0);
                if !(p.position.is_finite() && p.direction.is_finite() && unit && range) {
                    return bad(format!(
                        "light {i} is placed at {} along {} with range {:?}: not a finite \
                         position, a unit direction and a positive range",
                        p.position, p.direction, p.range
                    ));
                }
            }
            if !(l.colour.is_finite() && l.intensity.is_finite()) {
                return bad(format!("light {i} has a non-finite colour or intensity"));
            }
        }
        if self.lamps_at_runtime && !lamps_placed(&self.lights) {
            return bad(format!(
                "lamps_at_runtime with lights a runtime cannot evaluate: an unplaced point or \
                 spot light, an area light, or more than {MAX_RUNTIME_LAMPS} lamps"
            ));
        }
        Ok(())
    }
}

/// Most point and spot lights a runtime evaluates per pixel (the GPU's view buffer holds this
/// many).
pub const MAX_RUNTIME_LAMPS: usize = 4;

/// Whether a runtime can evaluate the direct light of every lamp among `lights`: every point
/// and spot light is `placed`, there is no area light, and there are at most
/// [`MAX_RUNTIME_LAMPS`] lamps. Directional lights are not lamps.
pub fn lamps_placed(lights: &[Light]) -> bool {
    let mut lamps = 0;
    for l in lights {
        match l.kind {
            LightKind::Directional => {}
            LightKind::Area { .. } => return false,
            LightKind::Point | LightKind::Spot { .. } => {
                if l.placed.is_none() {
                    return false;
                }
                lamps += 1;
            }
        }
    }
    lamps <= MAX_RUNTIME_LAMPS
}

/// Units of the pack's values.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Units {
    /// Metres per scene unit (1.0: scene units are metres).
    pub metres_per_unit: f32,
    /// Seconds per time unit (1.0: times are seconds).
    pub seconds_per_unit: f32,
    /// What a radiance value of 1.0 means, e.g. `"W/(sr·m²)"` or `"relative"`.
    pub radiance: String,
}

impl Default for Units {
    fn default() -> Self {
        Units {
            metres_per_unit: 1.0,
            seconds_per_unit: 1.0,
            radiance: "W/(sr·m²)".to_string(),
        }
    }
}

/// An axis-aligned box.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Aabb {
    /// Smallest corner.
    pub min: Vec3,
    /// Largest corner.
    pub max: Vec3,
}

/// The region of space the camera may move in, given by its corners.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum ViewSpace {
    /// A line segment from `a` to `b`.
    Segment {
        /// One end.
        a: Vec3,
        /// The other end.
        b: Vec3,
    },
    /// A planar rectangle given by its four corners in order around the boundary.
    Rectangle {
        /// Corners in boundary order.
        corners: [Vec3; 4],
    },
    /// An axis-aligned box.
    Box {
        /// Smallest corner.
        min: Vec3,
        /// Largest corner.
        max: Vec3,
    },
}

/// A time interval in seconds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TimeRange {
    /// First time.
    pub start: f32,
    /// Last time.
    pub end: f32,
}

/// One base view: a point the range images were rendered from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BaseView {
    /// Stable id (survives merging shards); chunks refer to the view by index, not id.
    pub id: u32,
    /// Position, metres.
    pub position: Vec3,
    /// Times (seconds) of this view's range images; chunk key `k` is `time_keys[k]`.
    pub time_keys: Vec<f32>,
}

/// Whether an object moves.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Motion {
    /// Never moves.
    Static,
    /// Has animation tracks.
    Animated,
}

/// One object of the scene: what ids in object-id cubes and volume samples refer to.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ObjectEntry {
    /// The id stored in object-id cubes and volume samples. 0 means "no object" (background).
    pub id: u32,
    /// Human-readable name.
    pub name: String,
    /// Path of the glTF node, e.g. `"/Scene/Room/Chair"`.
    pub node_path: String,
    /// Static or animated.
    pub motion: Motion,
    /// Key of this object's [`crate::ChunkKind::ProxyMesh`] chunk (by convention the object id),
    /// if it has one.
    pub proxy_mesh: Option<u32>,
    /// Index of the object's material in [`Manifest::materials`] (version 1.2); `None`: no
    /// material (every object of an older pack).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub material: Option<u32>,
    /// Coverage of a see-through surface (glTF `alphaMode: BLEND`, e.g. glass exported that
    /// way): the mean fraction of rays that stop at it, in (0, 1). A runtime composites the
    /// object over what lies behind it with this weight, so the sky shows through glazing at
    /// full resolution. `None` (absent, as in every older pack): opaque.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub coverage: Option<f32>,
}

/// The shape of a light.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum LightKind {
    /// A point light.
    Point,
    /// A spot light with glTF-style cone angles (radians).
    Spot {
        /// Inner cone angle.
        inner_cone: f32,
        /// Outer cone angle.
        outer_cone: f32,
    },
    /// A directional light.
    Directional,
    /// A rectangular emitter, width × height metres.
    Area {
        /// Width, metres.
        width: f32,
        /// Height, metres.
        height: f32,
    },
}

/// A light of the scene.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Light {
    /// Shape.
    pub kind: LightKind,
    /// Linear RGB colour.
    pub colour: Vec3,
    /// Intensity in glTF units (candela, lux, or nits for area lights).
    pub intensity: f32,
    /// The object whose motion the light follows, if any.
    pub follows_object: Option<u32>,
    /// The glTF node the light is attached to, if any.
    pub node_path: Option<String>,
    /// Where a point or spot light that never moves shines from (4.1): the runtime evaluates
    /// its highlight on the glossy surfaces whose reflections it marches for the camera.
    /// `None` (absent, as in every older pack): directional lights, area lights, lights that
    /// move, whose highlights stay in the baked non-diffuse radiance.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub placed: Option<LightPlacement>,
}

/// Where a punctual light is, in the world.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct LightPlacement {
    /// Position, metres.
    pub position: Vec3,
    /// Unit direction the light shines along (a spot light's axis, the node's −Z).
    pub direction: Vec3,
    /// Distance beyond which it gives no light, metres; `None`: unlimited.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub range: Option<f32>,
}

/// The settings a pack was baked with.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct BakeSettings {
    /// Quality parameter q in (0, 1]: the fitness threshold of the decompositions.
    pub quality: f32,
    /// Face size of the range-image cubes, texels.
    pub cube_face_size: u32,
    /// Samples per texel of the range images.
    pub samples_per_texel: u32,
    /// Target number of temporal-volume samples per base view.
    pub volume_samples_per_view: u64,
    /// Free-form settings (recipe name, renderer options, ...).
    pub extra: BTreeMap<String, String>,
}

/// What the bake measured.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct BakeStatistics {
    /// Wall-clock seconds per phase (e.g. `"range_images"`).
    pub phase_seconds: BTreeMap<String, f64>,
    /// Sample counts by what was sampled (e.g. `"camera_rays"`).
    pub sample_counts: BTreeMap<String, u64>,
    /// Bytes by what they hold (e.g. `"radiance"`).
    pub bytes: BTreeMap<String, u64>,
}
