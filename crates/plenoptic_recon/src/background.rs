//! The environment behind the proxy geometry (docs/architecture.md, "Daylight"): pixels whose
//! viewing ray meets no proxy — sky through a window or a skylight, anything beyond the view
//! space's geometry — show the pack's environment for that pixel's own direction at the
//! camera's time, evaluated per pixel (not read from a cube texel), in every mode.
//!
//! The sun's direction at t comes from the pack's sun track; a sky without one has the sun at
//! the zenith. A pack whose manifest says its environment is none (rays that leave the
//! scene see nothing, as the tracer renders them) shows black there. Packs that do not say
//! (no environment entry, before 1.1) keep what the modes put there (the heaviest key's cube
//! in the pixel's direction, or the background fill).

use glam::Vec3;
use plenoptic_pack::PackReader;
pub use plenoptic_pack::plenoptic_sky::{Environment, PlacedEnvironment, SunTrack};
use rayon::prelude::*;

use crate::{Camera, Frame, GeometryMask, Mode, Reconstructor};

/// The environment of a pack, read once when the reconstructor opens it.
#[derive(Debug, Clone, Default)]
pub struct PackEnvironment {
    /// The environment ([`Environment::None`] when the pack has none or it is unreadable).
    pub environment: Environment,
    /// The sun's track, if the pack has one.
    pub sun: Option<SunTrack>,
}

impl PackEnvironment {
    /// Reads the pack's environment; what cannot be read is the error message, and the
    /// environment is then none.
    pub fn from_pack(pack: &PackReader) -> (Self, Option<String>) {
        let sun = pack.sun_track().cloned();
        let declared = pack.manifest().environment.is_some();
        match pack.environment() {
            // Declared as none: black, what the scene showed the bake (not a key's texels,
            // which a base view elsewhere saw in that direction).
            Ok(Environment::None) if declared => (
                Self {
                    environment: Environment::Uniform(Vec3::ZERO),
                    sun,
                },
                None,
            ),
            Ok(environment) => (Self { environment, sun }, None),
            Err(e) => (
                Self {
                    environment: Environment::None,
                    sun,
                },
                Some(e.to_string()),
            ),
        }
    }

    /// Whether the pack has an environment to show.
    pub fn is_none(&self) -> bool {
        self.environment.is_none()
    }

    /// Unit direction towards the sun and its illuminance at time `t`, if there is a track.
    pub fn sun_at(&self, t: f32) -> Option<(Vec3, Vec3)> {
        self.sun.as_ref().map(|s| s.at(t))
    }

    /// The environment at time `t`: the sky (and its ground) lit by the track's sun then.
    pub fn at(&self, t: f32) -> PlacedEnvironment {
        self.environment.at_lit(self.sun_at(t))
    }
}

/// Shows the reconstructor's environment at `t` where `frame` (rendered in `mode`) sees no
/// proxy: in geometry-assisted mode the frame's own mask says where; in image and volume
/// modes the proxies are rasterized for it (without proxies, pixels of object 0).
pub(crate) fn show(rec: &Reconstructor, camera: &Camera, t: f32, mode: Mode, frame: &mut Frame) {
    let e = rec.environment();
    if e.is_none() {
        return;
    }
    let env = rec.environment_at(t);
    match rec.proxy() {
        Some(proxy) if mode != Mode::GeometryAssisted => {
            let mask = proxy.mask_raster(camera, t);
            apply(&env, camera, Coverage::Mask(&mask), frame);
        }
        _ => {
            apply(&env, camera, Coverage::FrameObjects, frame);
        }
    }
}

/// Which pixels of a frame see no proxy geometry.
pub(crate) enum Coverage<'a> {
    /// The frame's own object ids (geometry-assisted mode: 0 = no proxy).
    FrameObjects,
    /// A geometry mask of the same camera and time (0 = no proxy).
    Mask(&'a GeometryMask),
}

/// Replaces every pixel that sees no proxy with `env`'s radiance in its direction; those
/// pixels get infinite depth and object 0. Returns how many pixels show the environment.
pub(crate) fn apply(
    env: &PlacedEnvironment,
    camera: &Camera,
    coverage: Coverage<'_>,
    frame: &mut Frame,
) -> usize {
    if env.is_none() {
        return 0;
    }
    let basis = camera.basis();
    let w = frame.width as usize;
    frame
        .radiance
        .par_iter_mut()
        .zip(frame.depth.par_iter_mut())
        .zip(frame.object.par_iter_mut())
        .enumerate()
        .filter(|(j, (_, object))| match &coverage {
            Coverage::FrameObjects => **object == 0,
            Coverage::Mask(m) => m.object.get(*j) == Some(&0),
        })
        .map(|(j, ((rad, depth), object))| {
            let dir = basis.direction((j % w) as f32 + 0.5, (j / w) as f32 + 0.5);
            *rad = env.radiance(dir);
            *depth = f32::INFINITY;
            *object = 0;
        })
        .count()
}
