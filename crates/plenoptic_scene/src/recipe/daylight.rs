//! The recipe's daylight: `[sun]` (a sun study: place, date, time of day) and `[sky]` (the
//! environment), validated into a [`Daylight`] (docs/architecture.md, "Daylight").
//!
//! ```toml
//! [sun]                          # a sun study over the bake's time range
//! latitude = 48.8566             # degrees north
//! longitude = 2.3522             # degrees east
//! date = "2026-06-21"
//! utc_offset = 2.0               # hours of local time ahead of UTC
//! local_time = [6.0, 21.0]       # hours, mapped onto [time.start, time.end]
//! north_deg = 0.0                # compass north: degrees from the model's −Z towards +X
//! illuminance = 100000.0         # lux with the sun at the zenith (falls with air mass)
//! color = [1.0, 1.0, 1.0]
//! angular_diameter_deg = 0.533   # the sun's disc: soft shadows (0: hard)
//! light = "Sun"                  # optional: drive this glTF directional light instead of adding one
//!
//! [sky]
//! kind = "hosek-wilkie"          # or "image", "uniform", "none"
//! turbidity = 3.0                # hosek-wilkie: 1 (clear) to 10 (hazy)
//! ground_albedo = [0.2, 0.2, 0.2]
//! scale = 1000.0                 # hosek-wilkie: model kcd/m² to the scene's lux units
//! ground = true                  # hosek-wilkie: below the horizon a ground of ground_albedo, lit by sky and sun (default false: black)
//! sun = "Sun"                    # hosek-wilkie without [sun]: the glTF directional light that is the sun
//! # file = "studio.exr"          # image: equirectangular .hdr or .exr
//! # intensity = 1.0              # image: multiplies the texels
//! # rotation_deg = 0.0           # image: turn about +Y
//! # color = [0.5, 0.6, 0.8]      # uniform: radiance
//! ```
//!
//! With `[sun]` and no `[sky]` the sky is Hosek–Wilkie with its defaults. A `[sky]` of kind
//! hosek-wilkie without `[sun]` takes its sun from the light named by `sky.sun`, else from
//! the scene's first directional light.

use std::path::{Path, PathBuf};

use glam::Vec3;
use plenoptic_sky::{SkyParams, SunStudy};
use serde::{Deserialize, Serialize};

use super::ErrFn;
use crate::error::RecipeError;

/// The `[sun]` table: a sun study. Its cost in the bake: a sun that moves adds light keys
/// where what it sees changes (with `quality.runtime_sun`, the default, its direct light is
/// evaluated at runtime and does not add keys of its own).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SunToml {
    /// Degrees north, in [−90, 90].
    pub latitude: f64,
    /// Degrees east, in [−180, 180].
    pub longitude: f64,
    /// The day, `"YYYY-MM-DD"`.
    pub date: String,
    /// Hours of local time ahead of UTC. Default 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub utc_offset: Option<f64>,
    /// Local hours `[from, to]`, mapped onto `[time.start, time.end]`.
    pub local_time: [f64; 2],
    /// Compass north, in degrees from the model's −Z towards +X. Default 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub north_deg: Option<f32>,
    /// Illuminance in lux with the sun at the zenith; it falls with the air mass. Default
    /// 100,000.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub illuminance: Option<f32>,
    /// Linear colour of the sun. Default white.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub color: Option<[f32; 3]>,
    /// Angular diameter of the sun's disc in degrees: soft shadows; 0 gives hard ones.
    /// Default 0.533. Costs nothing at bake time; at runtime the CPU spends more shadow rays
    /// along softer edges.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub angular_diameter_deg: Option<f32>,
    /// The glTF directional light the study drives (its animation is replaced). Default: a
    /// light named "Sun" is added.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub light: Option<String>,
}

/// The `[sky]` table: what rays that leave the scene see. Both tracers importance-sample
/// it; its cost in the bake is the samples it draws, not more keys.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SkyToml {
    /// `"hosek-wilkie"`, `"image"`, `"uniform"` or `"none"`.
    pub kind: String,
    /// hosek-wilkie: atmospheric turbidity, 1 (clear) to 10 (hazy). Default 3.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub turbidity: Option<f32>,
    /// hosek-wilkie: linear albedo of the ground. Default 0.2 on every channel.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ground_albedo: Option<[f32; 3]>,
    /// hosek-wilkie: the model's kcd/m² in the scene's lux-based units. Default 1000.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scale: Option<f32>,
    /// hosek-wilkie: below the horizon a ground of `ground_albedo` lit by the sky and the sun
    /// (no shadows), in both tracers and at runtime. Default false: black.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ground: Option<bool>,
    /// hosek-wilkie without `[sun]`: the glTF directional light that is the sun. Default:
    /// the scene's first directional light.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sun: Option<String>,
    /// image: an equirectangular `.hdr` or `.exr` file, relative to the recipe. Stored in
    /// the pack.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub file: Option<String>,
    /// image: multiplies the texels. Default 1.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub intensity: Option<f32>,
    /// image: turn about +Y in degrees. Default 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rotation_deg: Option<f32>,
    /// uniform: linear radiance `[r, g, b]`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub color: Option<[f32; 3]>,
}

/// A validated sun study.
#[derive(Debug, Clone, PartialEq)]
pub struct SunSpec {
    /// Where, when, how bright.
    pub study: SunStudy,
    /// Angular diameter of the disc, degrees.
    pub angular_diameter_deg: f32,
    /// The glTF directional light it drives; `None`: a light named "Sun" is added.
    pub light: Option<String>,
}

/// A validated sky.
#[derive(Debug, Clone, PartialEq, Default)]
pub enum SkySpec {
    /// No environment.
    #[default]
    None,
    /// Hosek–Wilkie, with the light that is its sun when there is no `[sun]`.
    HosekWilkie {
        /// Model parameters.
        params: SkyParams,
        /// `sky.sun`.
        sun_light: Option<String>,
    },
    /// An equirectangular image file.
    Image {
        /// The file, resolved against the recipe's directory.
        path: PathBuf,
        /// Multiplies the texels.
        intensity: f32,
        /// Turn about +Y, degrees.
        rotation_deg: f32,
    },
    /// A uniform radiance.
    Uniform(Vec3),
}

/// The recipe's daylight.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Daylight {
    /// The sun study, if any.
    pub sun: Option<SunSpec>,
    /// The sky.
    pub sky: SkySpec,
}

fn vec3(key: &str, v: [f32; 3], err: &ErrFn) -> Result<Vec3, RecipeError> {
    let v = Vec3::from_array(v);
    if !v.is_finite() || v.min_element() < 0.0 {
        return Err(err(key, "must be finite and non-negative"));
    }
    Ok(v)
}

fn date(text: &str, err: &ErrFn) -> Result<(i32, u32, u32), RecipeError> {
    let bad = || err("sun.date", "must be a date written YYYY-MM-DD");
    let mut parts = text.trim().split('-');
    let (Some(y), Some(m), Some(d), None) =
        (parts.next(), parts.next(), parts.next(), parts.next())
    else {
        return Err(bad());
    };
    Ok((
        y.parse().map_err(|_| bad())?,
        m.parse().map_err(|_| bad())?,
        d.parse().map_err(|_| bad())?,
    ))
}

impl SunToml {
    pub(super) fn validate(&self, err: &ErrFn) -> Result<SunSpec, RecipeError> {
        let defaults = SunStudy::default();
        let study = SunStudy {
            latitude: self.latitude,
            longitude: self.longitude,
            date: date(&self.date, err)?,
            utc_offset_hours: self.utc_offset.unwrap_or(0.0),
            local_hours: (self.local_time[0], self.local_time[1]),
            north_deg: self.north_deg.unwrap_or(0.0),
            illuminance: self.illuminance.unwrap_or(defaults.illuminance),
            color: match self.color {
                Some(c) => vec3("sun.color", c, err)?,
                None => Vec3::ONE,
            },
        };
        study.validate().map_err(|e| {
            let text = e.to_string();
            let key = [
                "latitude",
                "longitude",
                "utc_offset",
                "local_time",
                "north_deg",
                "illuminance",
                "color",
            ]
            .into_iter()
            .find(|k| text.starts_with(k))
            .map_or("sun.date".to_owned(), |k| format!("sun.{k}"));
            err(&key, &text)
        })?;
        let angular_diameter_deg = self
            .angular_diameter_deg
            .unwrap_or(plenoptic_sky::sun::SUN_ANGULAR_DIAMETER_DEG);
        if !(0.0..=20.0).contains(&angular_diameter_deg) {
            return Err(err(
                "sun.angular_diameter_deg",
                "must be in [0, 20] degrees",
            ));
        }
        if self.light.as_deref().is_some_and(|l| l.trim().is_empty()) {
            return Err(err(
                "sun.light",
                "must name a directional light of the scene",
            ));
        }
        Ok(SunSpec {
            study,
            angular_diameter_deg,
            light: self.light.clone(),
        })
    }
}

impl SkyToml {
    pub(super) fn validate(&self, base_dir: &Path, err: &ErrFn) -> Result<SkySpec, RecipeError> {
        let kind = self.kind.as_str();
        let allowed: &[&str] = match kind {
            "none" => &[],
            "hosek-wilkie" => &["turbidity", "ground_albedo", "scale", "ground", "sun"],
            "image" => &["file", "intensity", "rotation_deg"],
            "uniform" => &["color"],
            _ => {
                return Err(err(
                    "sky.kind",
                    "must be \"hosek-wilkie\", \"image\", \"uniform\" or \"none\"",
                ));
            }
        };
        let present = [
            ("turbidity", self.turbidity.is_some()),
            ("ground_albedo", self.ground_albedo.is_some()),
            ("scale", self.scale.is_some()),
            ("ground", self.ground.is_some()),
            ("sun", self.sun.is_some()),
            ("file", self.file.is_some()),
            ("intensity", self.intensity.is_some()),
            ("rotation_deg", self.rotation_deg.is_some()),
            ("color", self.color.is_some()),
        ];
        if let Some((k, _)) = present.iter().find(|(k, p)| *p && !allowed.contains(k)) {
            return Err(err(
                &format!("sky.{k}"),
                &format!("not used by kind = \"{kind}\""),
            ));
        }
        Ok(match kind {
            "none" => SkySpec::None,
            "hosek-wilkie" => {
                let d = SkyParams::default();
                let params = SkyParams {
                    turbidity: self.turbidity.unwrap_or(d.turbidity),
                    ground_albedo: match self.ground_albedo {
                        Some(a) => vec3("sky.ground_albedo", a, err)?,
                        None => d.ground_albedo,
                    },
                    scale: self.scale.unwrap_or(d.scale),
                    ground: self.ground.unwrap_or(d.ground),
                };
                params.validate().map_err(|e| {
                    let text = e.to_string();
                    let key = ["turbidity", "ground_albedo", "scale"]
                        .into_iter()
                        .find(|k| text.starts_with(k))
                        .unwrap_or("turbidity");
                    err(&format!("sky.{key}"), &text)
                })?;
                SkySpec::HosekWilkie {
                    params,
                    sun_light: self.sun.clone(),
                }
            }
            "image" => {
                let file = self.file.as_deref().unwrap_or("");
                let lower = file.to_ascii_lowercase();
                if !(lower.ends_with(".hdr") || lower.ends_with(".exr")) {
                    return Err(err(
                        "sky.file",
                        "must name an equirectangular .hdr or .exr file",
                    ));
                }
                let intensity = self.intensity.unwrap_or(1.0);
                if !(intensity.is_finite() && intensity >= 0.0) {
                    return Err(err("sky.intensity", "must be finite and non-negative"));
                }
                let rotation_deg = self.rotation_deg.unwrap_or(0.0);
                if !rotation_deg.is_finite() {
                    return Err(err("sky.rotation_deg", "must be finite"));
                }
                SkySpec::Image {
                    path: base_dir.join(file),
                    intensity,
                    rotation_deg,
                }
            }
            _ => SkySpec::Uniform(vec3(
                "sky.color",
                self.color
                    .ok_or_else(|| err("sky.color", "required for kind = \"uniform\""))?,
                err,
            )?),
        })
    }
}

/// Validates the two tables together.
pub(super) fn validate(
    sun: Option<&SunToml>,
    sky: Option<&SkyToml>,
    base_dir: &Path,
    err: &ErrFn,
) -> Result<Daylight, RecipeError> {
    let sun = sun.map(|s| s.validate(err)).transpose()?;
    let sky = match sky {
        Some(s) => s.validate(base_dir, err)?,
        None if sun.is_some() => SkySpec::HosekWilkie {
            params: SkyParams::default(),
            sun_light: None,
        },
        None => SkySpec::None,
    };
    if sun.is_some()
        && let SkySpec::HosekWilkie {
            sun_light: Some(_), ..
        } = sky
    {
        return Err(err(
            "sky.sun",
            "not used with [sun]: name the light in sun.light",
        ));
    }
    Ok(Daylight { sun, sky })
}

#[cfg(test)]
mod tests {
    use crate::recipe::Recipe;
    use std::path::Path;

    const BASE: &str = r#"
output = "out.pack"
[[scene]]
file = "a.glb"
[view_space]
kind = "segment"
a = [0.0, 1.0, 0.0]
b = [1.0, 1.0, 0.0]
[time]
start = 0.0
end = 14.0
frame_rate = 30.0
"#;

    fn parse(extra: &str) -> Result<super::Daylight, String> {
        Recipe::from_str_named(&format!("{BASE}{extra}"), "r.toml", Path::new("/d"))
            .map(|r| r.daylight)
            .map_err(|e| e.to_string())
    }

    #[test]
    fn a_sun_study_with_the_default_sky() {
        let d = parse(
            "[sun]\nlatitude = 48.85\nlongitude = 2.35\ndate = \"2026-06-21\"\nutc_offset = 2.0\nlocal_time = [6.0, 21.0]\n",
        )
        .unwrap();
        let sun = d.sun.unwrap();
        assert_eq!(sun.study.date, (2026, 6, 21));
        assert_eq!(sun.study.local_hours, (6.0, 21.0));
        assert!((sun.angular_diameter_deg - 0.533).abs() < 1e-6);
        assert!(matches!(d.sky, super::SkySpec::HosekWilkie { .. }));
        assert_eq!(parse("").unwrap(), super::Daylight::default());
    }

    #[test]
    fn skies_of_each_kind() {
        let d = parse("[sky]\nkind = \"image\"\nfile = \"sky.exr\"\nintensity = 2.0\n").unwrap();
        match d.sky {
            super::SkySpec::Image {
                path, intensity, ..
            } => {
                assert_eq!(path, Path::new("/d/sky.exr"));
                assert_eq!(intensity, 2.0);
            }
            other => panic!("{other:?}"),
        }
        let d = parse("[sky]\nkind = \"uniform\"\ncolor = [0.1, 0.2, 0.3]\n").unwrap();
        assert!(matches!(d.sky, super::SkySpec::Uniform(_)));
        let d = parse("[sky]\nkind = \"hosek-wilkie\"\nturbidity = 5.0\nsun = \"Key\"\n").unwrap();
        assert!(matches!(
            d.sky,
            super::SkySpec::HosekWilkie {
                sun_light: Some(_),
                params: plenoptic_sky::SkyParams { ground: false, .. },
            }
        ));
        let d = parse("[sky]\nkind = \"hosek-wilkie\"\nground = true\n").unwrap();
        assert!(matches!(
            d.sky,
            super::SkySpec::HosekWilkie {
                params: plenoptic_sky::SkyParams { ground: true, .. },
                ..
            }
        ));
        let e = parse("[sky]\nkind = \"uniform\"\ncolor = [0.1, 0.2, 0.3]\nground = true\n")
            .unwrap_err();
        assert!(e.contains("sky.ground"), "{e}");
    }

    #[test]
    fn errors_name_the_key() {
        let sun = |extra: &str| {
            parse(&format!(
                "[sun]\nlatitude = 48.85\nlongitude = 2.35\ndate = \"2026-06-21\"\nlocal_time = [6.0, 21.0]\n{extra}"
            ))
        };
        for (extra, key) in [
            ("", ""),
            ("angular_diameter_deg = -1.0\n", "sun.angular_diameter_deg"),
            ("illuminance = -5.0\n", "sun.illuminance"),
        ] {
            match sun(extra) {
                Ok(_) => assert!(key.is_empty(), "{extra} should fail"),
                Err(e) => assert!(e.contains(key) && !key.is_empty(), "{e}"),
            }
        }
        let e = parse("[sun]\nlatitude = 95.0\nlongitude = 0.0\ndate = \"2026-06-21\"\nlocal_time = [6.0, 21.0]\n").unwrap_err();
        assert!(e.contains("sun.latitude"), "{e}");
        let e = parse("[sun]\nlatitude = 0.0\nlongitude = 0.0\ndate = \"2026-13-01\"\nlocal_time = [6.0, 21.0]\n").unwrap_err();
        assert!(e.contains("sun.date"), "{e}");
        let e = parse("[sky]\nkind = \"rainbow\"\n").unwrap_err();
        assert!(e.contains("sky.kind"), "{e}");
        let e = parse("[sky]\nkind = \"uniform\"\ncolor = [1.0, 1.0, 1.0]\nturbidity = 3.0\n")
            .unwrap_err();
        assert!(e.contains("sky.turbidity") && e.contains("not used"), "{e}");
        let e = parse("[sky]\nkind = \"image\"\nfile = \"sky.png\"\n").unwrap_err();
        assert!(e.contains("sky.file"), "{e}");
        let e = parse("[sky]\nkind = \"hosek-wilkie\"\nturbidity = 11.0\n").unwrap_err();
        assert!(e.contains("sky.turbidity"), "{e}");
        let e = parse("[sky]\nkind = \"uniform\"\n").unwrap_err();
        assert!(e.contains("sky.color"), "{e}");
        let e = parse("[sun]\nlatitude = 0.0\nlongitude = 0.0\ndate = \"2026-06-21\"\nlocal_time = [6.0, 21.0]\nbogus = 1\n").unwrap_err();
        assert!(e.contains("bogus"), "{e}");
    }
}
