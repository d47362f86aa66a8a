//! Sun studies: where the sun is for a place, a date and a local time of day, mapped onto the
//! bake's time range (docs/architecture.md, "Daylight").
//!
//! The solar position comes from the `spa` crate (the PSA algorithm of Blanco-Muriel et al.,
//! 0.5′ accuracy; within 0.002° of NREL's SPA test case, see the tests). The model's
//! orientation is given by `north_deg`: the compass north of the site, as an angle from the
//! model's −Z turning towards +X (clockwise seen from above, +Y up). East is north turned a
//! further 90°.
//!
//! The sun's illuminance falls with air mass: E(z) = E · 0.7^(AM^0.678) / 0.7 (Meinel &
//! Meinel's clear-sky attenuation, normalised to `illuminance` with the sun at the zenith),
//! AM from Kasten & Young (1989), zero once the sun is below the horizon. Colour does not
//! change with elevation.

use chrono::{NaiveDate, TimeDelta, TimeZone, Utc};
use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::{Result, SkyError};

/// The sun's mean angular diameter, degrees.
pub const SUN_ANGULAR_DIAMETER_DEG: f32 = 0.533;

/// A day's sun at one site.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SunStudy {
    /// Latitude, degrees north (WGS84), in [−90, 90].
    pub latitude: f64,
    /// Longitude, degrees east (WGS84), in [−180, 180].
    pub longitude: f64,
    /// The day: year, month (1–12), day of month.
    pub date: (i32, u32, u32),
    /// Offset of local time from UTC, hours (e.g. 2 for Paris in summer).
    pub utc_offset_hours: f64,
    /// Local times of day, hours, mapped linearly onto the bake's start and end.
    pub local_hours: (f64, f64),
    /// Compass north in the model: degrees from −Z towards +X.
    pub north_deg: f32,
    /// Illuminance of the sun at the zenith on a clear day, lux (glTF units).
    pub illuminance: f32,
    /// Linear colour of the sun.
    pub color: Vec3,
}

impl Default for SunStudy {
    fn default() -> Self {
        Self {
            latitude: 0.0,
            longitude: 0.0,
            date: (2026, 6, 21),
            utc_offset_hours: 0.0,
            local_hours: (6.0, 18.0),
            north_deg: 0.0,
            illuminance: 100_000.0,
            color: Vec3::ONE,
        }
    }
}

impl SunStudy {
    /// Checks every field; the message names the field.
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(SkyError::OutOfRange(m));
        if !(-90.0..=90.0).contains(&self.latitude) {
            return bad(format!(
                "latitude must be in [-90, 90], got {}",
                self.latitude
            ));
        }
        if !(-180.0..=180.0).contains(&self.longitude) {
            return bad(format!(
                "longitude must be in [-180, 180], got {}",
                self.longitude
            ));
        }
        if !(-14.0..=14.0).contains(&self.utc_offset_hours) {
            return bad(format!(
                "utc_offset must be in [-14, 14] hours, got {}",
                self.utc_offset_hours
            ));
        }
        let (a, b) = self.local_hours;
        if !(a.is_finite()
            && b.is_finite()
            && (0.0..=48.0).contains(&a)
            && (0.0..=48.0).contains(&b))
        {
            return bad(format!(
                "local_time must be two hours in [0, 48], got [{a}, {b}]"
            ));
        }
        if !self.north_deg.is_finite() {
            return bad("north_deg must be finite".into());
        }
        if !self.illuminance.is_finite() || self.illuminance < 0.0 {
            return bad(format!(
                "illuminance must be non-negative, got {}",
                self.illuminance
            ));
        }
        if !self.color.is_finite() || self.color.min_element() < 0.0 {
            return bad("color must be non-negative".into());
        }
        self.day().map(|_| ())
    }

    fn day(&self) -> Result<NaiveDate> {
        let (y, m, d) = self.date;
        NaiveDate::from_ymd_opt(y, m, d)
            .ok_or_else(|| SkyError::InvalidDate(format!("{y:04}-{m:02}-{d:02} is not a date")))
    }

    /// Solar azimuth (degrees clockwise from north) and zenith angle (degrees, no
    /// atmospheric refraction) at local time `hours` of the study's day.
    pub fn solar_position(&self, hours: f64) -> Result<(f64, f64)> {
        let day = self.day()?;
        let midnight = Utc.from_utc_datetime(
            &day.and_hms_opt(0, 0, 0)
                .ok_or_else(|| SkyError::InvalidDate("midnight".into()))?,
        );
        let utc_hours = hours - self.utc_offset_hours;
        let ms = (utc_hours * 3_600_000.0).round() as i64;
        let when = midnight
            .checked_add_signed(TimeDelta::milliseconds(ms))
            .ok_or_else(|| SkyError::InvalidDate(format!("{hours} h")))?;
        let p = spa::solar_position::<spa::StdFloatOps>(when, self.latitude, self.longitude)
            .map_err(|e| SkyError::OutOfRange(format!("solar position: {e:?}")))?;
        Ok((p.azimuth, p.zenith_angle))
    }

    /// Unit world direction towards the sun for `azimuth` and `zenith` (degrees).
    pub fn direction(&self, azimuth_deg: f64, zenith_deg: f64) -> Vec3 {
        let n = self.north_deg.to_radians();
        let north = Vec3::new(n.sin(), 0.0, -n.cos());
        let east = Vec3::new(n.cos(), 0.0, n.sin());
        let (az, el) = (
            azimuth_deg.to_radians() as f32,
            (90.0 - zenith_deg).to_radians() as f32,
        );
        (el.cos() * (az.cos() * north + az.sin() * east) + el.sin() * Vec3::Y).normalize()
    }

    /// The sun's linear illuminance (colour × lux) with the sun at `zenith_deg`.
    pub fn illuminance_at(&self, zenith_deg: f64) -> Vec3 {
        self.color * self.illuminance * attenuation(zenith_deg)
    }

    /// The local time of day at bake time `t` of the range `[start, end]`.
    pub fn hours_at(&self, t: f32, start: f32, end: f32) -> f64 {
        let (a, b) = self.local_hours;
        if end <= start {
            return a;
        }
        let f = f64::from(((t - start) / (end - start)).clamp(0.0, 1.0));
        a + (b - a) * f
    }

    /// The study sampled at `samples` (≥ 2) evenly spaced bake times over `[start, end]`.
    pub fn track(&self, start: f32, end: f32, samples: usize) -> Result<SunTrack> {
        self.validate()?;
        let n = samples.max(2);
        let mut out = Vec::with_capacity(n);
        for i in 0..n {
            let t = if end > start {
                start + (end - start) * i as f32 / (n - 1) as f32
            } else {
                start
            };
            let (az, zen) = self.solar_position(self.hours_at(t, start, end))?;
            out.push(SunTrackSample {
                time: t,
                direction: self.direction(az, zen),
                illuminance: self.illuminance_at(zen),
            });
        }
        SunTrack::new(out)
    }
}

/// Clear-sky attenuation relative to the zenith (1 at the zenith, 0 below the horizon).
pub fn attenuation(zenith_deg: f64) -> f32 {
    if zenith_deg >= 90.0 {
        return 0.0;
    }
    let z = zenith_deg.max(0.0);
    let am = 1.0 / (z.to_radians().cos() + 0.50572 * (96.07995 - z).powf(-1.6364));
    (0.7f64.powf(am.powf(0.678)) / 0.7) as f32
}

/// The sun at one bake time.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SunTrackSample {
    /// Bake time, seconds.
    pub time: f32,
    /// Unit world direction towards the sun.
    pub direction: Vec3,
    /// Linear illuminance (colour × lux) on a plane facing the sun.
    pub illuminance: Vec3,
}

/// The sun over the bake's time range: samples in time order, interpolated linearly
/// (directions renormalised), held constant outside. What the pack stores for the runtime's
/// sky, and what drives the sun light in the tracers.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SunTrack {
    samples: Vec<SunTrackSample>,
}

impl SunTrack {
    /// Largest number of samples a track may have (a pack is refused beyond it).
    pub const MAX_SAMPLES: usize = 1 << 16;

    /// A track from samples, which must be non-empty, finite, in increasing time order and at
    /// most [`SunTrack::MAX_SAMPLES`].
    pub fn new(samples: Vec<SunTrackSample>) -> Result<Self> {
        let track = Self { samples };
        track.validate()?;
        Ok(track)
    }

    /// A sun that does not move.
    pub fn fixed(direction: Vec3, illuminance: Vec3) -> Self {
        Self {
            samples: vec![SunTrackSample {
                time: 0.0,
                direction: direction.normalize_or(Vec3::Y),
                illuminance,
            }],
        }
    }

    /// Checks a track read from a file.
    pub fn validate(&self) -> Result<()> {
        let s = &self.samples;
        if s.is_empty() || s.len() > Self::MAX_SAMPLES {
            return Err(SkyError::OutOfRange(format!(
                "a sun track needs 1 to {} samples, got {}",
                Self::MAX_SAMPLES,
                s.len()
            )));
        }
        for (i, x) in s.iter().enumerate() {
            if !(x.time.is_finite() && x.direction.is_finite() && x.illuminance.is_finite())
                || x.direction.length_squared() < 0.5
                || x.illuminance.min_element() < 0.0
            {
                return Err(SkyError::OutOfRange(format!(
                    "sun track sample {i} is not valid"
                )));
            }
            if i > 0 && x.time <= s[i - 1].time {
                return Err(SkyError::OutOfRange(format!(
                    "sun track sample {i}: times must increase"
                )));
            }
        }
        Ok(())
    }

    /// The samples.
    pub fn samples(&self) -> &[SunTrackSample] {
        &self.samples
    }

    /// Whether the sun moves or changes over the track.
    pub fn is_animated(&self) -> bool {
        self.samples
            .windows(2)
            .any(|w| w[0].direction != w[1].direction || w[0].illuminance != w[1].illuminance)
    }

    /// The sun at bake time `t`: unit direction towards it and its illuminance.
    pub fn at(&self, t: f32) -> (Vec3, Vec3) {
        let s = &self.samples;
        let i = s.partition_point(|x| x.time <= t);
        if i == 0 {
            return (s[0].direction, s[0].illuminance);
        }
        if i == s.len() {
            let l = s[s.len() - 1];
            return (l.direction, l.illuminance);
        }
        let (a, b) = (s[i - 1], s[i]);
        let f = (t - a.time) / (b.time - a.time);
        (
            a.direction.lerp(b.direction, f).normalize_or(b.direction),
            a.illuminance.lerp(b.illuminance, f),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// NREL's SPA test case (Reda & Andreas 2008, table A4.1): Golden, Colorado,
    /// 2003-10-17 12:30:30 local (UTC−7). Published topocentric azimuth 194.340241° and
    /// elevation without refraction 39.872046° (zenith 50.127954°).
    #[test]
    fn matches_the_nrel_spa_test_case_within_a_hundredth_of_a_degree() {
        let study = SunStudy {
            latitude: 39.742476,
            longitude: -105.1786,
            date: (2003, 10, 17),
            utc_offset_hours: -7.0,
            ..SunStudy::default()
        };
        let (az, zen) = study
            .solar_position(12.0 + 30.0 / 60.0 + 30.0 / 3600.0)
            .unwrap();
        assert!((az - 194.340241).abs() < 0.01, "azimuth {az}");
        assert!((zen - 50.127954).abs() < 0.01, "zenith {zen}");
    }

    #[test]
    fn north_and_east_follow_the_model_orientation() {
        let s = SunStudy::default();
        let north_horizon = s.direction(0.0, 90.0);
        assert!((north_horizon - Vec3::NEG_Z).length() < 1e-5);
        let east = s.direction(90.0, 90.0);
        assert!((east - Vec3::X).length() < 1e-5);
        let turned = SunStudy {
            north_deg: 90.0,
            ..SunStudy::default()
        };
        assert!((turned.direction(0.0, 90.0) - Vec3::X).length() < 1e-5);
        assert!((s.direction(0.0, 0.0) - Vec3::Y).length() < 1e-5);
    }

    #[test]
    fn a_summer_day_in_paris_rises_in_the_east_and_peaks_in_the_south() {
        let s = SunStudy {
            latitude: 48.8566,
            longitude: 2.3522,
            date: (2026, 6, 21),
            utc_offset_hours: 2.0,
            local_hours: (6.0, 21.0),
            ..SunStudy::default()
        };
        let track = s.track(0.0, 14.0, 64).unwrap();
        let (morning, e_morning) = track.at(0.0);
        assert!(morning.x > 0.5 && morning.y < 0.1, "{morning}");
        let noon = track
            .samples()
            .iter()
            .max_by(|a, b| a.direction.y.total_cmp(&b.direction.y))
            .unwrap();
        // Solar noon's elevation is 90 − 48.86 + 23.44 = 64.6°, sun due south (+Z).
        assert!((noon.direction.y.asin().to_degrees() - 64.6).abs() < 0.5);
        assert!(noon.direction.z > 0.3);
        assert!(noon.illuminance.x > 80_000.0 && e_morning.x < noon.illuminance.x * 0.5);
        assert!(track.is_animated());
    }

    #[test]
    fn bad_input_is_named() {
        let s = SunStudy {
            date: (2026, 2, 30),
            ..SunStudy::default()
        };
        assert!(s.validate().unwrap_err().to_string().contains("2026-02-30"));
        let s = SunStudy {
            latitude: 91.0,
            ..SunStudy::default()
        };
        assert!(s.validate().unwrap_err().to_string().contains("latitude"));
        let t = SunTrack::new(vec![]);
        assert!(t.is_err());
    }

    #[test]
    fn attenuation_is_one_at_the_zenith_and_falls_to_zero_at_the_horizon() {
        assert!((attenuation(0.0) - 1.0).abs() < 1e-3);
        assert!(attenuation(60.0) < attenuation(30.0));
        assert!(attenuation(89.0) < 0.2);
        assert_eq!(attenuation(95.0), 0.0);
    }
}
