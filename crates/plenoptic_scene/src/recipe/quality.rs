//! Bake quality: one settings struct with named presets, each field documented with what it
//! costs and what it buys.

use serde::{Deserialize, Serialize};

/// Named quality presets of the recipe's `quality.preset`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Preset {
    /// Minutes: checks a recipe end to end; visible artefacts expected.
    Draft,
    /// A walk-through good enough to judge layout and lighting.
    Preview,
    /// Shippable packs for ordinary displays.
    Production,
    /// Reference quality for stills and comparisons; hours to days.
    Final,
}

impl Preset {
    /// Every preset, cheapest first.
    pub const ALL: [Preset; 4] = [Self::Draft, Self::Preview, Self::Production, Self::Final];

    /// The preset's name in a recipe.
    pub const fn name(self) -> &'static str {
        match self {
            Self::Draft => "draft",
            Self::Preview => "preview",
            Self::Production => "production",
            Self::Final => "final",
        }
    }

    /// The preset named `name`, if any.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|p| p.name() == name)
    }

    /// The preset's settings.
    pub const fn quality(self) -> Quality {
        match self {
            Self::Draft => Quality::draft(),
            Self::Preview => Quality::preview(),
            Self::Production => Quality::production(),
            Self::Final => Quality::final_bake(),
        }
    }
}

/// Whether the presets denoise the range images (see [`Quality::denoise`]).
pub const DENOISE_DEFAULT: bool = false;

/// Whether the presets leave the sun to the runtime (see [`Quality::runtime_sun`]).
pub const RUNTIME_SUN_DEFAULT: bool = true;

fn runtime_sun_default() -> bool {
    RUNTIME_SUN_DEFAULT
}

/// Whether the presets leave the lamps' direct diffuse light to the runtime (see
/// [`Quality::runtime_lamps`]).
pub const RUNTIME_LAMPS_DEFAULT: bool = true;

fn runtime_lamps_default() -> bool {
    RUNTIME_LAMPS_DEFAULT
}

/// Bake quality settings (docs/architecture.md "Baking"; thesis ch. 5–7). Start from a preset and
/// override single fields; every field states its cost.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Quality {
    /// Fitness threshold q in [0, 1] of the decomposition of space and time: a region or an
    /// interval is subdivided while the fraction of pixels whose object id agrees at all its
    /// corners is below q. Higher q gives more base views and time keys: storage and bake
    /// time grow roughly with 1 / (1 − q) in busy scenes; reconstruction error falls.
    pub q: f32,
    /// Side in pixels of the id-images rendered to measure fitness. Cost grows with the
    /// square; too small misses thin objects and under-subdivides.
    pub id_image_size: u32,
    /// Face size in pixels of the range images (colour and depth) of every base view and time
    /// key. Pack size and bake time grow with the square; sharpness grows linearly.
    pub range_image_size: u32,
    /// Deepest subdivision of the view space. Bounds the number of base views (at most
    /// 2^depth per axis) whatever q asks for.
    pub max_space_depth: u32,
    /// Deepest subdivision of the time range. Bounds the number of time keys per base view
    /// (at most 2^depth) whatever q asks for.
    pub max_time_depth: u32,
    /// Radiance samples per range-image pixel (direct light with soft shadows and specular
    /// paths). Bake time is linear in it; noise falls with its square root.
    pub samples_per_pixel: u32,
    /// Hemisphere samples per point of the ambient field (indirect diffuse), each traced
    /// once and reused for every bounce. Linear cost; too few gives blotchy indirect light.
    pub ambient_samples: u32,
    /// Relative RMS change of irradiance between interval ends above which the ambient field
    /// gets another key time. Smaller values cost more ambient keys and catch subtler changes.
    /// An ambient key time between two of a base view's keys becomes a key of that view where
    /// the view's indirect light there is more than 5 % from the blend of its keys
    /// (docs/architecture.md, "Baking", step 5): on the tour 58 more range images
    /// than the 225 of the light keys, 1.24× the bake time and 1.21× the pack.
    pub ambient_rms: f32,
    /// Sample budget per base view of the temporal volume, the (x, y, t) samples that stand
    /// in where no range image saw a point. Memory and bake time are linear in it.
    pub temporal_volume_samples: u32,
    /// Longest chain of specular reflections and refractions followed. Glass and mirrors
    /// facing each other need more; cost grows with it only where such paths exist.
    pub max_specular_depth: u32,
    /// Samples per pixel of the reference path tracer that renders ground truth for the
    /// metrics. Not part of the pack: only the error report's trustworthiness depends on it.
    pub reference_samples_per_pixel: u32,
    /// Denoise the range images' diffuse lighting before quantisation (edge-aware à-trous
    /// filter guided by object id, normal and distance; `plenoptic_bake::denoise`). Textures,
    /// emission and reflections are not filtered. Costs well under the rendering of a range
    /// image; removes most of the pixel noise of few samples per pixel.
    #[serde(default)]
    pub denoise: bool,
    /// Leave the sun's direct light out of the stored lighting for the runtime to evaluate at
    /// screen resolution (pack 3's `direct_sun`; docs/architecture.md, "The runtime sun").
    /// The time decomposition then ignores where the sun falls in each view, which only
    /// direct light shows (what the sun sees still sets the light keys: the indirect light
    /// follows it): fewer time keys for a moving sun. Off: the sun is baked into the lighting
    /// (cube resolution) and each view follows its sun patches with keys of its own.
    #[serde(default = "runtime_sun_default")]
    pub runtime_sun: bool,
    /// Leave the direct diffuse light of the scene's point and spot lights out of the stored
    /// lighting for the runtime to evaluate per pixel, with a shadow ray per lamp against the
    /// proxies (pack 5's `lamps_at_runtime`; docs/architecture.md, "The runtime lamps"). Only
    /// where every lamp stands still and there are at most 4; otherwise, or off, the lamps'
    /// light is baked at cube resolution. On the tour the lamp's lit top, a sliver one or two
    /// pixels tall, is lit per pixel instead of mixed with its side in a 64-pixel texel; each pixel
    /// pays a shadow ray per lamp.
    #[serde(default = "runtime_lamps_default")]
    pub runtime_lamps: bool,
}

impl Quality {
    /// Minutes: checks a recipe end to end.
    pub const fn draft() -> Self {
        Self {
            q: 0.8,
            id_image_size: 64,
            range_image_size: 256,
            max_space_depth: 3,
            max_time_depth: 4,
            samples_per_pixel: 4,
            ambient_samples: 128,
            ambient_rms: 0.2,
            temporal_volume_samples: 20_000,
            max_specular_depth: 2,
            reference_samples_per_pixel: 64,
            denoise: DENOISE_DEFAULT,
            runtime_sun: RUNTIME_SUN_DEFAULT,
            runtime_lamps: RUNTIME_LAMPS_DEFAULT,
        }
    }

    /// Good enough to judge layout and lighting.
    pub const fn preview() -> Self {
        Self {
            q: 0.9,
            id_image_size: 128,
            range_image_size: 512,
            max_space_depth: 4,
            max_time_depth: 6,
            samples_per_pixel: 16,
            ambient_samples: 256,
            ambient_rms: 0.1,
            temporal_volume_samples: 100_000,
            max_specular_depth: 4,
            reference_samples_per_pixel: 256,
            denoise: DENOISE_DEFAULT,
            runtime_sun: RUNTIME_SUN_DEFAULT,
            runtime_lamps: RUNTIME_LAMPS_DEFAULT,
        }
    }

    /// Shippable packs; the default when a recipe names no preset.
    pub const fn production() -> Self {
        Self {
            q: 0.95,
            id_image_size: 256,
            range_image_size: 1024,
            max_space_depth: 6,
            max_time_depth: 8,
            samples_per_pixel: 64,
            ambient_samples: 1024,
            ambient_rms: 0.05,
            temporal_volume_samples: 500_000,
            max_specular_depth: 6,
            reference_samples_per_pixel: 1024,
            denoise: DENOISE_DEFAULT,
            runtime_sun: RUNTIME_SUN_DEFAULT,
            runtime_lamps: RUNTIME_LAMPS_DEFAULT,
        }
    }

    /// Reference quality (the recipe's `preset = "final"`).
    pub const fn final_bake() -> Self {
        Self {
            q: 0.98,
            id_image_size: 512,
            range_image_size: 2048,
            max_space_depth: 8,
            max_time_depth: 10,
            samples_per_pixel: 256,
            ambient_samples: 4096,
            ambient_rms: 0.02,
            temporal_volume_samples: 2_000_000,
            max_specular_depth: 8,
            reference_samples_per_pixel: 4096,
            denoise: DENOISE_DEFAULT,
            runtime_sun: RUNTIME_SUN_DEFAULT,
            runtime_lamps: RUNTIME_LAMPS_DEFAULT,
        }
    }
}

impl Default for Quality {
    fn default() -> Self {
        Self::production()
    }
}
