//! # plenoptic_sky
//!
//! The environment light of plenoptic (docs/architecture.md, "Daylight"): what a ray that
//! leaves the scene sees, for the tracers, the baker and the runtime alike, so that the sky
//! in a baked pack and the sky behind a window at runtime are one function.
//!
//! - [`sky`]: the Hosek–Wilkie clear-sky model (Hosek & Wilkie 2012, RGB fit, through the
//!   `hw-skymodel` crate) for a sun direction, turbidity and ground albedo, with its
//!   coefficients exported for shaders ([`SkyCoefficients`]).
//! - [`sun`]: sun studies: the solar position for a place, a date and a local time range
//!   (`spa` crate), mapped onto the bake's time range and the model's north, with the sun's
//!   illuminance falling with air mass; sampled into a [`SunTrack`].
//! - [`environment`]: the three kinds of environment, a uniform colour, an equirectangular
//!   HDR image or the sky, and their radiance per direction at a time
//!   ([`Environment::at`]).
//!
//! Units are the scene's (see `plenoptic_scene::model`): glTF's photometric numbers used as
//! radiometric ones. The sky model's RGB output is in kcd/m² (its zenith at noon is a few
//! units); [`SkyParams::scale`] defaults to 1000 so that the sky sits beside a sun of about
//! 100,000 lux as Blender exports it.
//!
//! ```
//! use glam::Vec3;
//! use plenoptic_sky::{Environment, SkyParams};
//!
//! let env = Environment::Sky(SkyParams::default());
//! let sun = Vec3::new(0.0, 1.0, -1.0).normalize();
//! let sky = env.at(Some(sun));
//! let zenith = sky.radiance(Vec3::Y);
//! let horizon_away = sky.radiance(Vec3::new(0.0, 0.05, 1.0).normalize());
//! assert!(zenith.z > zenith.x, "a clear sky is blue");
//! assert!(sky.radiance(Vec3::NEG_Y) == Vec3::ZERO, "no sky below the horizon");
//! assert!(horizon_away.length() > 0.0);
//! ```

pub mod environment;
pub mod sky;
pub mod sun;

pub use environment::{
    Environment, EquirectImage, PlacedEnvironment, equirect_direction, equirect_uv,
};
pub use sky::{Sky, SkyCoefficients, SkyParams};
pub use sun::{SunStudy, SunTrack, SunTrackSample};

/// Errors of the environment model.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SkyError {
    /// A parameter is out of its range; the message names it.
    #[error("{0}")]
    OutOfRange(String),
    /// A date or time that does not exist.
    #[error("invalid date or time: {0}")]
    InvalidDate(String),
    /// An image whose size does not match its texels.
    #[error("environment image: {0}")]
    InvalidImage(String),
}

/// Result of the environment model.
pub type Result<T, E = SkyError> = std::result::Result<T, E>;
