//! The environment: what a ray that leaves the scene sees. A uniform colour, an
//! equirectangular HDR image, or the Hosek–Wilkie sky for the sun's direction at a time.
//!
//! Equirectangular convention (shared by the image files, the tracers' importance sampling
//! and the runtime): u = ½ + atan2(x, −z) / 2π, v = acos(y) / π, so the image's centre looks
//! along −Z, its top row at +Y, and u grows towards +X. An image's `rotation_deg` turns it
//! about +Y by the right-hand rule (positive: the image's −Z moves towards −X).

use std::f32::consts::{PI, TAU};
use std::sync::Arc;

use glam::{Quat, Vec2, Vec3};

use crate::sky::{Sky, SkyParams};
use crate::{Result, SkyError};

/// An equirectangular image of linear RGB radiance, row 0 at the top (+Y).
#[derive(Debug, Clone, PartialEq)]
pub struct EquirectImage {
    /// Width in texels (covers 360°).
    pub width: u32,
    /// Height in texels (covers 180°).
    pub height: u32,
    /// Row-major texels.
    pub texels: Vec<Vec3>,
}

impl EquirectImage {
    /// Largest side accepted (a 16k × 8k image is 1.5 GiB of f32 texels).
    pub const MAX_SIDE: u32 = 16_384;

    /// An image, checked: sizes in [1, MAX_SIDE], texel count = width × height, texels finite
    /// and non-negative.
    pub fn new(width: u32, height: u32, texels: Vec<Vec3>) -> Result<Self> {
        if width == 0 || height == 0 || width > Self::MAX_SIDE || height > Self::MAX_SIDE {
            return Err(SkyError::InvalidImage(format!(
                "size {width} × {height} is outside 1 – {}",
                Self::MAX_SIDE
            )));
        }
        if texels.len() != width as usize * height as usize {
            return Err(SkyError::InvalidImage(format!(
                "{} texels for {width} × {height}",
                texels.len()
            )));
        }
        if let Some(i) = texels
            .iter()
            .position(|t| !t.is_finite() || t.min_element() < 0.0)
        {
            return Err(SkyError::InvalidImage(format!(
                "texel {i} is negative or not finite"
            )));
        }
        Ok(Self {
            width,
            height,
            texels,
        })
    }

    /// The texel at column `x`, row `y` (wrapping in x, clamped in y).
    pub fn texel(&self, x: i64, y: i64) -> Vec3 {
        let w = i64::from(self.width);
        let h = i64::from(self.height);
        let xi = x.rem_euclid(w) as usize;
        let yi = y.clamp(0, h - 1) as usize;
        self.texels[yi * self.width as usize + xi]
    }

    /// Bilinear lookup at texture coordinates `uv` (texel centres at (i + ½)/size).
    pub fn bilinear(&self, uv: Vec2) -> Vec3 {
        let x = uv.x * self.width as f32 - 0.5;
        let y = uv.y * self.height as f32 - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (xi, yi) = (x0 as i64, y0 as i64);
        let top = self.texel(xi, yi).lerp(self.texel(xi + 1, yi), fx);
        let bottom = self.texel(xi, yi + 1).lerp(self.texel(xi + 1, yi + 1), fx);
        top.lerp(bottom, fy)
    }
}

/// Texture coordinates of unit direction `d` in the equirectangular convention.
pub fn equirect_uv(d: Vec3) -> Vec2 {
    let u = 0.5 + d.x.atan2(-d.z) / TAU;
    let v = d.y.clamp(-1.0, 1.0).acos() / PI;
    Vec2::new(u.rem_euclid(1.0), v)
}

/// Unit direction at texture coordinates `uv` (inverse of [`equirect_uv`]).
pub fn equirect_direction(uv: Vec2) -> Vec3 {
    let phi = (uv.x - 0.5) * TAU;
    let theta = uv.y * PI;
    let s = theta.sin();
    Vec3::new(s * phi.sin(), theta.cos(), -s * phi.cos())
}

/// What the scene sees beyond its geometry, before a time is chosen.
#[derive(Debug, Clone, PartialEq, Default)]
pub enum Environment {
    /// Nothing: a miss returns zero radiance.
    #[default]
    None,
    /// The same radiance from every direction.
    Uniform(Vec3),
    /// An equirectangular HDR image.
    Image {
        /// The image (shared: placing it at a time copies nothing).
        image: Arc<EquirectImage>,
        /// Multiplies every texel.
        intensity: f32,
        /// Turn about +Y, degrees.
        rotation_deg: f32,
    },
    /// The Hosek–Wilkie sky; its sun direction comes with the time ([`Environment::at`]).
    Sky(SkyParams),
}

impl Environment {
    /// Checks parameters (the sky's ranges, a finite non-negative colour or intensity).
    pub fn validate(&self) -> Result<()> {
        match self {
            Environment::None => Ok(()),
            Environment::Uniform(c) => {
                if c.is_finite() && c.min_element() >= 0.0 {
                    Ok(())
                } else {
                    Err(SkyError::OutOfRange(
                        "color must be finite and non-negative".into(),
                    ))
                }
            }
            Environment::Image {
                intensity,
                rotation_deg,
                ..
            } => {
                if intensity.is_finite() && *intensity >= 0.0 && rotation_deg.is_finite() {
                    Ok(())
                } else {
                    Err(SkyError::OutOfRange(
                        "intensity must be non-negative and rotation_deg finite".into(),
                    ))
                }
            }
            Environment::Sky(p) => p.validate(),
        }
    }

    /// Whether this is [`Environment::None`].
    pub fn is_none(&self) -> bool {
        matches!(self, Environment::None)
    }

    /// Whether the environment depends on the sun's direction.
    pub fn follows_the_sun(&self) -> bool {
        matches!(self, Environment::Sky(_))
    }

    /// The environment with the sun towards `sun` (a sky without a sun has it at the zenith).
    /// Parameters should have passed [`Environment::validate`]; a sky that does not gives
    /// [`PlacedEnvironment::None`].
    pub fn at(&self, sun: Option<Vec3>) -> PlacedEnvironment {
        self.at_lit(sun.map(|d| (d, Vec3::ZERO)))
    }

    /// [`Environment::at`] with the sun's direction and its illuminance on a plane facing it,
    /// which also lights a sky's ground ([`SkyParams::ground`](crate::SkyParams::ground)).
    pub fn at_lit(&self, sun: Option<(Vec3, Vec3)>) -> PlacedEnvironment {
        match self {
            Environment::None => PlacedEnvironment::None,
            Environment::Uniform(c) => PlacedEnvironment::Uniform(*c),
            Environment::Image {
                image,
                intensity,
                rotation_deg,
            } => PlacedEnvironment::Image {
                image: Arc::clone(image),
                intensity: Vec3::splat(*intensity),
                to_image: Quat::from_rotation_y(rotation_deg.to_radians()),
            },
            Environment::Sky(p) => {
                let (direction, illuminance) = sun.unwrap_or((Vec3::Y, Vec3::ZERO));
                Sky::new_lit(p, direction, illuminance)
                    .map_or(PlacedEnvironment::None, PlacedEnvironment::Sky)
            }
        }
    }
}

/// The environment at one time: radiance per direction.
#[derive(Debug, Clone, PartialEq, Default)]
pub enum PlacedEnvironment {
    /// No environment.
    #[default]
    None,
    /// A uniform colour.
    Uniform(Vec3),
    /// An image, turned.
    Image {
        /// The image.
        image: Arc<EquirectImage>,
        /// Multiplies every texel, per channel.
        intensity: Vec3,
        /// Turns a world direction into the image's frame.
        to_image: Quat,
    },
    /// The sky for one sun direction.
    Sky(Sky),
}

impl PlacedEnvironment {
    /// Whether rays that miss see nothing.
    pub fn is_none(&self) -> bool {
        matches!(self, PlacedEnvironment::None)
    }

    /// Irradiance on a horizontal plane facing +Y with nothing around it: ∫ L cos θ dω over
    /// the upper hemisphere by the midpoint rule on `steps` × 4·`steps` cells in (θ, φ). The
    /// reference for tests of the tracers and the sampling tables.
    pub fn horizontal_irradiance(&self, steps: usize) -> Vec3 {
        let n = steps.max(1);
        let (dt, dp) = (PI / 2.0 / n as f32, TAU / (4 * n) as f32);
        let mut e = glam::DVec3::ZERO;
        for i in 0..n {
            let theta = (i as f32 + 0.5) * dt;
            let (st, ct) = theta.sin_cos();
            for j in 0..4 * n {
                let phi = (j as f32 + 0.5) * dp;
                let d = Vec3::new(st * phi.cos(), ct, st * phi.sin());
                e += (self.radiance(d) * (ct * st * dt * dp)).as_dvec3();
            }
        }
        e.as_vec3()
    }

    /// Whether no direction sends light: none, a black colour, an image at zero intensity or
    /// a black sky ([`Sky::is_black`]). Known without evaluating a direction, so that the
    /// tracers need not build a sampling table to find that there is nothing to sample.
    pub fn is_black(&self) -> bool {
        match self {
            PlacedEnvironment::None => true,
            PlacedEnvironment::Uniform(c) => c.max_element() <= 0.0,
            PlacedEnvironment::Image { intensity, .. } => intensity.max_element() <= 0.0,
            PlacedEnvironment::Sky(sky) => sky.is_black(),
        }
    }

    /// The environment with its radiance multiplied by `weight` per channel: the sky's light
    /// group at a colour × intensity (the `sky` emitter of a recipe's `[[light_group]]`).
    pub fn scaled(self, weight: Vec3) -> Self {
        if weight == Vec3::ONE {
            return self;
        }
        match self {
            PlacedEnvironment::None => PlacedEnvironment::None,
            PlacedEnvironment::Uniform(c) => PlacedEnvironment::Uniform(c * weight),
            PlacedEnvironment::Image {
                image,
                intensity,
                to_image,
            } => PlacedEnvironment::Image {
                image,
                intensity: intensity * weight,
                to_image,
            },
            PlacedEnvironment::Sky(sky) => PlacedEnvironment::Sky(sky.scaled(weight)),
        }
    }

    /// Linear RGB radiance arriving from unit direction `dir`.
    pub fn radiance(&self, dir: Vec3) -> Vec3 {
        match self {
            PlacedEnvironment::None => Vec3::ZERO,
            PlacedEnvironment::Uniform(c) => *c,
            PlacedEnvironment::Image {
                image,
                intensity,
                to_image,
            } => image.bilinear(equirect_uv(to_image.inverse() * dir)) * *intensity,
            PlacedEnvironment::Sky(sky) => sky.radiance(dir),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_uniform_sky_gives_pi_l_on_a_plane() {
        let e = Environment::Uniform(Vec3::new(1.0, 2.0, 0.5))
            .at(None)
            .horizontal_irradiance(64);
        assert!(
            (e / PI - Vec3::new(1.0, 2.0, 0.5)).abs().max_element() < 1e-3,
            "{e}"
        );
    }

    #[test]
    fn equirect_mapping_round_trips_and_follows_the_convention() {
        for d in [
            Vec3::NEG_Z,
            Vec3::X,
            Vec3::new(0.3, 0.5, 0.8).normalize(),
            Vec3::new(-0.7, -0.2, 0.1).normalize(),
        ] {
            let back = equirect_direction(equirect_uv(d));
            assert!((back - d).length() < 1e-5, "{d} -> {back}");
        }
        assert!((equirect_uv(Vec3::NEG_Z) - Vec2::new(0.5, 0.5)).length() < 1e-6);
        assert!(equirect_uv(Vec3::Y).y < 1e-6);
        assert!((equirect_uv(Vec3::X).x - 0.75).abs() < 1e-6);
    }

    #[test]
    fn image_lookup_rotation_and_bad_images() {
        // A 4 × 2 image: each column a different colour.
        let cols = [Vec3::X, Vec3::Y, Vec3::Z, Vec3::ONE];
        let texels = (0..8).map(|i| cols[i % 4]).collect();
        let image = Arc::new(EquirectImage::new(4, 2, texels).unwrap());
        let env = Environment::Image {
            image: Arc::clone(&image),
            intensity: 2.0,
            rotation_deg: 0.0,
        };
        // −Z is u = 0.5: between columns 1 and 2 → (Y + Z)/2 × 2.
        let r = env.at(None).radiance(Vec3::NEG_Z);
        assert!((r - (Vec3::Y + Vec3::Z)).length() < 1e-5, "{r}");
        let unturned = env.at(None).radiance(Vec3::NEG_Z);
        let turned = Environment::Image {
            image,
            intensity: 2.0,
            rotation_deg: 90.0,
        };
        // Turned by +90° about +Y, what the image had at −Z is seen towards −X.
        let r = turned.at(None).radiance(Vec3::NEG_X);
        assert!((r - unturned).length() < 1e-5, "{r} vs {unturned}");
        assert!((turned.at(None).radiance(Vec3::NEG_Z) - unturned).length() > 0.1);
        assert!(EquirectImage::new(4, 2, vec![Vec3::ONE; 7]).is_err());
        assert!(EquirectImage::new(1, 1, vec![Vec3::splat(-1.0)]).is_err());
        assert!(EquirectImage::new(0, 1, vec![]).is_err());
    }
}
