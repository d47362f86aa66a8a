//! The [`PlenopticCamera`] component, playback, and each camera's render layer
//! ([`layers`]).

pub mod layers;
pub mod lights;

use bevy::core_pipeline::prepass::DepthPrepass;
use bevy::prelude::*;
pub use plenoptic_recon::ReconSettings;

pub use lights::LightSettings;

use crate::asset::RadiancePack;
use crate::settings::PlenopticSystems;

/// Adds playback of [`PlenopticCamera`]s.
#[derive(Debug, Default)]
pub struct PlenopticCameraPlugin;

impl Plugin for PlenopticCameraPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<layers::ViewLayers>().add_systems(
            Update,
            (layers::assign_view_layers, advance_playback)
                .chain()
                .in_set(PlenopticSystems::Playback),
        );
    }
}

/// The EV100 at which Bevy's exposure multiplier (`2^−EV100 / 1.2`) is 1: a camera with
/// `Exposure { ev100: EV100_UNIT }` shows a pack's radiance as it is stored. For packs
/// baked with non-physical light levels (a sun of a few lux, like the tour's); a pack lit by
/// a real sun (about 100,000 lux) wants a daylight exposure such as
/// `Exposure::SUNLIGHT` (EV100 15).
pub const EV100_UNIT: f32 = -0.263_034_4;

/// A camera that shows a radiance pack: which pack, at which time, reconstructed how.
///
/// Requires a [`Camera3d`] (the proxy geometry is rasterised by it) with a
/// [`DepthPrepass`] (the GPU reconstruction's hole fill reads the depth of neighbouring
/// pixels). The streaming layer adds its per-camera state to it as a required component.
///
/// Any number of plenoptic cameras may render in one app, each with its own pack, time and
/// mode: each draws its own proxy geometry on a render layer of its own, which the plugin
/// adds to the camera's `RenderLayers` ([`layers`]).
///
/// The reconstructed radiance honours the camera's `Exposure` (EV100) as Bevy's own lights
/// do: it is multiplied by `2^−EV100 / 1.2` before it reaches the HDR target, and the
/// camera's `Tonemapping` then applies as to any other mesh. Bevy's default exposure (EV100
/// 9.7, "Blender") suits physical light levels; see [`EV100_UNIT`] for packs without them.
#[derive(Component, Debug, Clone)]
#[require(Camera3d, DepthPrepass)]
pub struct PlenopticCamera {
    /// The pack shown.
    pub pack: Handle<RadiancePack>,
    /// Animation time, seconds (clamped to, or wrapped into, the pack's time range).
    pub time: f32,
    /// The reconstruction mode.
    pub mode: ReconMode,
    /// How `time` advances.
    pub playback: Playback,
    /// How this camera's frames are reconstructed: the one definition of every tunable, read
    /// by the GPU passes (as uniforms) and the CPU backend alike, and by streaming (which
    /// base views the camera blends, `max_views` of them, must be resident).
    pub settings: ReconSettings,
    /// A colour × intensity per light group of the pack ([`lights`]; as baked by default).
    pub lights: LightSettings,
}

impl PlenopticCamera {
    /// A camera on `pack` at time 0, geometry-assisted, playing at normal speed in a loop.
    pub fn new(pack: Handle<RadiancePack>) -> Self {
        Self {
            pack,
            time: 0.0,
            mode: ReconMode::GeometryAssisted,
            playback: Playback::Clock {
                speed: 1.0,
                looping: true,
            },
            settings: ReconSettings::default(),
            lights: LightSettings::default(),
        }
    }

    /// Playback direction (+1 forward, −1 backward, 0 paused or manual), used by prefetch.
    pub fn direction(&self) -> f32 {
        match self.playback {
            Playback::Clock { speed, .. } => speed.signum() * (speed != 0.0) as u8 as f32,
            Playback::Manual => 0.0,
        }
    }
}

/// Reconstruction mode (thesis chapter 7; `plenoptic_recon::Mode`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ReconMode {
    /// Geometry-assisted: proxy geometry gives every pixel its object and point, looked up
    /// in the base views' cubes at the bracketing time keys. The cheapest and sharpest mode.
    #[default]
    GeometryAssisted,
    /// Image-based warping of the nearest base views (no proxy geometry needed).
    Image,
    /// Temporal volumes (continuous time).
    Volume,
}

impl From<ReconMode> for plenoptic_recon::Mode {
    fn from(m: ReconMode) -> Self {
        match m {
            ReconMode::GeometryAssisted => plenoptic_recon::Mode::GeometryAssisted,
            ReconMode::Image => plenoptic_recon::Mode::Image,
            ReconMode::Volume => plenoptic_recon::Mode::Volume,
        }
    }
}

/// How a camera's time advances.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Playback {
    /// Driven by Bevy's [`Time`]: `time += speed · Δt` each frame.
    Clock {
        /// Seconds of animation per second of real time (negative: backwards).
        speed: f32,
        /// Wrap around at the ends of the time range (else clamp and stop there).
        looping: bool,
    },
    /// The game sets [`PlenopticCamera::time`] itself (before [`PlenopticSystems::Playback`]).
    Manual,
}

/// Advances clock-driven cameras and keeps every camera's time inside its pack's range.
pub fn advance_playback(
    time: Res<Time>,
    packs: Res<Assets<RadiancePack>>,
    mut cameras: Query<&mut PlenopticCamera>,
) {
    for mut cam in &mut cameras {
        let Some(pack) = packs.get(&cam.pack) else {
            continue;
        };
        let range = pack.reader.manifest().time_range;
        let (start, end) = (range.start, range.end.max(range.start));
        let mut t = cam.time;
        let mut looping = false;
        if let Playback::Clock { speed, looping: l } = cam.playback {
            t += speed * time.delta_secs();
            looping = l;
        }
        let span = end - start;
        t = if looping && span > 0.0 {
            start + (t - start).rem_euclid(span)
        } else {
            t.clamp(start, end)
        };
        if t != cam.time {
            cam.time = t;
        }
    }
}
