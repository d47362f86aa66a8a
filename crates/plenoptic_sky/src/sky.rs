//! The Hosek–Wilkie clear sky (Hosek & Wilkie, "An Analytic Model for Full Spectral Sky-Dome
//! Radiance", SIGGRAPH 2012), RGB fit, evaluated with the `hw-skymodel` crate.
//!
//! The model covers solar elevations 0–90°. Below the horizon the sun is clamped to it and
//! the whole sky fades linearly to black at [`TWILIGHT_DEG`] below it (civil twilight): a
//! documented approximation so that a sun study may start before sunrise. The model has no
//! solar disc: the sun is a separate directional light. Directions below the horizon see no
//! sky: the ground is geometry, nothing, or with [`SkyParams::ground`] an infinite
//! Lambertian ground of the model's own `ground_albedo`, lit by the sky and the sun without
//! shadows: radiance `albedo / π · (E_sky + E_sun · max(0, sun.y))`, where E_sky is the
//! sky's irradiance on a horizontal plane (512 cosine-distributed directions, stratified)
//! and E_sun the sun's illuminance facing it ([`Sky::new_lit`]). What users see through a
//! window at eye height is then the ground's light, not black.

use glam::Vec3;
use hw_skymodel::rgb::{SkyParams as HwParams, SkyState};
use serde::{Deserialize, Serialize};

use crate::{Result, SkyError};

/// Solar depression, degrees, at which the sky has faded to black.
pub const TWILIGHT_DEG: f32 = 6.0;

/// Parameters of the sky apart from the sun's direction.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SkyParams {
    /// Atmospheric turbidity, 1 (very clear) to 10 (hazy); 3 is a clear day.
    pub turbidity: f32,
    /// Linear RGB albedo of the ground under the sky, each in [0, 1].
    pub ground_albedo: Vec3,
    /// Multiplies the model's kcd/m² (1000: the scene's lux-based units).
    pub scale: f32,
    /// Directions below the horizon see a ground of `ground_albedo` lit by the sky and the
    /// sun (module docs) instead of black. Off by default (packs before 3.1 have none).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub ground: bool,
}

impl Default for SkyParams {
    fn default() -> Self {
        Self {
            turbidity: 3.0,
            ground_albedo: Vec3::splat(0.2),
            scale: 1000.0,
            ground: false,
        }
    }
}

impl SkyParams {
    /// Checks the ranges the model accepts; the message names the parameter.
    pub fn validate(&self) -> Result<()> {
        if !(1.0..=10.0).contains(&self.turbidity) {
            return Err(SkyError::OutOfRange(format!(
                "turbidity must be in [1, 10], got {}",
                self.turbidity
            )));
        }
        if !self.ground_albedo.is_finite()
            || self.ground_albedo.min_element() < 0.0
            || self.ground_albedo.max_element() > 1.0
        {
            return Err(SkyError::OutOfRange(format!(
                "ground_albedo must be in [0, 1], got {:?}",
                self.ground_albedo.to_array()
            )));
        }
        if !self.scale.is_finite() || self.scale < 0.0 {
            return Err(SkyError::OutOfRange(format!(
                "scale must be finite and non-negative, got {}",
                self.scale
            )));
        }
        Ok(())
    }
}

/// The model's state for one sun direction: per channel nine distribution coefficients and
/// the zenith radiance, with the scale and twilight fade folded into the radiances. This is
/// what a shader needs to evaluate the same sky ([`Sky::radiance`] written in WGSL).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SkyCoefficients {
    /// Coefficients A–I of channel R, then G, then B (the order of Hosek–Wilkie's formula:
    /// A, B, C, D, E, F, G, H, I at indices 0–8).
    pub params: [f32; 27],
    /// Radiance scale per channel, times [`SkyParams::scale`] and the twilight fade.
    pub radiances: [f32; 3],
    /// Unit direction towards the sun (its elevation clamped to the horizon).
    pub sun: Vec3,
    /// Linear RGB radiance of every direction below the horizon (zero without
    /// [`SkyParams::ground`]).
    #[serde(default)]
    pub ground: [f32; 3],
}

/// The sky for one sun direction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sky {
    coefficients: SkyCoefficients,
}

impl Sky {
    /// The sky with `params` and the sun towards `sun` (world, +Y up; need not be unit), its
    /// ground (if any) lit by the sky alone.
    pub fn new(params: &SkyParams, sun: Vec3) -> Result<Self> {
        Self::new_lit(params, sun, Vec3::ZERO)
    }

    /// [`Sky::new`] with the sun's illuminance on a plane facing it (linear RGB), which
    /// lights the ground as well.
    pub fn new_lit(params: &SkyParams, sun: Vec3, sun_illuminance: Vec3) -> Result<Self> {
        params.validate()?;
        let sun = sun.normalize_or(Vec3::Y);
        let elevation = sun.y.clamp(-1.0, 1.0).asin();
        let fade = (1.0 + elevation.to_degrees() / TWILIGHT_DEG).clamp(0.0, 1.0);
        let clamped = elevation.clamp(0.0, std::f32::consts::FRAC_PI_2);
        let state = SkyState::new(&HwParams {
            elevation: clamped,
            turbidity: params.turbidity,
            albedo: params.ground_albedo.to_array(),
        })
        .map_err(|e| SkyError::OutOfRange(e.to_string()))?;
        let (p, r) = state.raw();
        let horizontal = Vec3::new(sun.x, 0.0, sun.z).normalize_or(Vec3::X);
        let sun_clamped = horizontal * clamped.cos() + Vec3::Y * clamped.sin();
        let mut sky = Self {
            coefficients: SkyCoefficients {
                params: p,
                radiances: r.map(|x| x * params.scale * fade),
                sun: sun_clamped,
                ground: [0.0; 3],
            },
        };
        if params.ground {
            let e = sky.horizontal_irradiance() + sun_illuminance.max(Vec3::ZERO) * sun.y.max(0.0);
            sky.coefficients.ground = (params.ground_albedo * e / std::f32::consts::PI).to_array();
        }
        Ok(sky)
    }

    /// Whether the sky sends no light at all: every channel's radiance scale and its ground
    /// are zero (a night below the twilight fade, or a sky whose light group is off).
    pub fn is_black(&self) -> bool {
        let c = &self.coefficients;
        c.radiances.iter().chain(&c.ground).all(|&x| x <= 0.0)
    }

    /// The same sky with every radiance, its ground's included, multiplied by `weight` per
    /// channel: a light group's colour × intensity (light transport is linear in it).
    pub fn scaled(&self, weight: Vec3) -> Self {
        let mut sky = *self;
        let c = &mut sky.coefficients;
        c.radiances = (Vec3::from_array(c.radiances) * weight).to_array();
        c.ground = (Vec3::from_array(c.ground) * weight).to_array();
        sky
    }

    /// The sky's irradiance on a horizontal plane (ground excluded): π × the mean radiance of
    /// 512 cosine-distributed directions, one per cell of a 32 × 16 grid (Malley's method).
    fn horizontal_irradiance(&self) -> Vec3 {
        const NU: usize = 32;
        const NV: usize = 16;
        let mut sum = Vec3::ZERO;
        for i in 0..NU {
            for j in 0..NV {
                let u = (i as f32 + 0.5) / NU as f32;
                let v = (j as f32 + 0.5) / NV as f32;
                let r = v.sqrt();
                let phi = std::f32::consts::TAU * u;
                let d = Vec3::new(r * phi.cos(), (1.0 - v).sqrt(), r * phi.sin());
                sum += self.radiance(d);
            }
        }
        sum * (std::f32::consts::PI / (NU * NV) as f32)
    }

    /// The coefficients, for a shader.
    pub fn coefficients(&self) -> &SkyCoefficients {
        &self.coefficients
    }

    /// Linear RGB radiance arriving from unit direction `dir` (below the horizon, the
    /// ground's, which is zero without [`SkyParams::ground`]).
    pub fn radiance(&self, dir: Vec3) -> Vec3 {
        if dir.y <= 0.0 {
            return Vec3::from_array(self.coefficients.ground);
        }
        let c = &self.coefficients;
        let cos_theta = dir.y.min(1.0);
        let cos_gamma = dir.dot(c.sun).clamp(-1.0, 1.0);
        let gamma = cos_gamma.acos();
        let mut out = [0.0f32; 3];
        for (ch, o) in out.iter_mut().enumerate() {
            *o = eval_channel(
                &c.params[9 * ch..9 * ch + 9],
                c.radiances[ch],
                cos_theta,
                gamma,
                cos_gamma,
            );
        }
        Vec3::from_array(out).max(Vec3::ZERO)
    }
}

/// Hosek–Wilkie's formula for one channel (equation 9 of the paper), as `hw-skymodel` writes
/// it; kept here with cos θ and cos γ precomputed so that the shader port has one reference.
fn eval_channel(p: &[f32], radiance: f32, cos_theta: f32, gamma: f32, cos_gamma: f32) -> f32 {
    let cos_gamma2 = cos_gamma * cos_gamma;
    let exp_m = (p[4] * gamma).exp();
    let mie = (1.0 + cos_gamma2) / (1.0 + p[8] * p[8] - 2.0 * p[8] * cos_gamma).powf(1.5);
    let lhs = 1.0 + p[0] * (p[1] / (cos_theta + 0.01)).exp();
    let rhs = p[2] + p[3] * exp_m + p[5] * cos_gamma2 + p[6] * mie + p[7] * cos_theta.sqrt();
    radiance * lhs * rhs
}

#[cfg(test)]
mod tests {
    use super::*;
    use hw_skymodel::rgb::Channel;

    /// `hw-skymodel`'s own evaluation, channel by channel.
    fn reference(state: &SkyState, theta: f32, gamma: f32) -> Vec3 {
        Vec3::new(
            state.radiance(theta, gamma, Channel::R),
            state.radiance(theta, gamma, Channel::G),
            state.radiance(theta, gamma, Channel::B),
        )
    }

    #[test]
    fn matches_hw_skymodel() {
        let params = SkyParams {
            scale: 1.0,
            ..SkyParams::default()
        };
        let sun = Vec3::new(0.3, 0.6, -0.5).normalize();
        let sky = Sky::new(&params, sun).unwrap();
        let state = SkyState::new(&HwParams {
            elevation: sun.y.asin(),
            turbidity: 3.0,
            albedo: [0.2; 3],
        })
        .unwrap();
        for dir in [
            Vec3::Y,
            Vec3::new(1.0, 0.2, 0.0),
            Vec3::new(-0.4, 0.9, 0.3),
            sun,
        ] {
            let d = dir.normalize();
            let ours = sky.radiance(d);
            let theirs = reference(&state, d.y.acos(), d.dot(sun).clamp(-1.0, 1.0).acos());
            assert!((ours - theirs).abs().max_element() <= 1e-4 * theirs.max_element().max(1.0));
        }
    }

    /// The ground is `albedo / π` × the horizontal irradiance of sky and sun, against a fine
    /// midpoint integration of the sky; without `ground` it is black.
    #[test]
    fn the_ground_is_lit_by_the_sky_and_the_sun() {
        let sun = Vec3::new(0.3, 0.5, -0.6).normalize();
        let e_sun = Vec3::new(8000.0, 7600.0, 6800.0);
        let params = SkyParams {
            ground: true,
            ground_albedo: Vec3::new(0.3, 0.2, 0.1),
            ..SkyParams::default()
        };
        let sky = Sky::new_lit(&params, sun, e_sun).unwrap();
        let n = 256;
        let (dt, dp) = (
            std::f32::consts::FRAC_PI_2 / n as f32,
            std::f32::consts::TAU / (4 * n) as f32,
        );
        let mut e_sky = glam::DVec3::ZERO;
        for i in 0..n {
            let (st, ct) = ((i as f32 + 0.5) * dt).sin_cos();
            for j in 0..4 * n {
                let phi = (j as f32 + 0.5) * dp;
                let d = Vec3::new(st * phi.cos(), ct, st * phi.sin());
                e_sky += (sky.radiance(d) * (ct * st * dt * dp)).as_dvec3();
            }
        }
        let want = params.ground_albedo * (e_sky.as_vec3() + e_sun * sun.y) / std::f32::consts::PI;
        for d in [Vec3::NEG_Y, Vec3::new(0.9, -0.1, 0.3).normalize()] {
            let got = sky.radiance(d);
            assert!(
                ((got - want) / want).abs().max_element() < 0.02,
                "{got} vs {want}"
            );
        }
        // Without the sun's illuminance only the sky lights it; without `ground` nothing.
        let unlit = Sky::new(&params, sun).unwrap().radiance(Vec3::NEG_Y);
        let sun_share = params.ground_albedo.x * e_sun.x * sun.y / std::f32::consts::PI;
        let got = sky.radiance(Vec3::NEG_Y).x - unlit.x;
        assert!((got / sun_share - 1.0).abs() < 1e-3, "{got} vs {sun_share}");
        let off = SkyParams {
            ground: false,
            ..params
        };
        assert_eq!(
            Sky::new_lit(&off, sun, e_sun)
                .unwrap()
                .radiance(Vec3::NEG_Y),
            Vec3::ZERO
        );
    }

    #[test]
    fn fades_after_sunset_and_rejects_bad_parameters() {
        let p = SkyParams::default();
        let day = Sky::new(&p, Vec3::new(1.0, 0.02, 0.0))
            .unwrap()
            .radiance(Vec3::Y);
        let dusk = Sky::new(&p, Vec3::new(1.0, -0.05, 0.0))
            .unwrap()
            .radiance(Vec3::Y);
        let night = Sky::new(&p, Vec3::new(1.0, -0.5, 0.0))
            .unwrap()
            .radiance(Vec3::Y);
        assert!(dusk.x < day.x && dusk.x > 0.0);
        assert_eq!(night, Vec3::ZERO);
        let bad = SkyParams {
            turbidity: 12.0,
            ..p
        };
        assert!(
            Sky::new(&bad, Vec3::Y)
                .unwrap_err()
                .to_string()
                .contains("turbidity")
        );
    }
}
