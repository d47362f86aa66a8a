//! The environment a pack was baked with (see `docs/pack-format.md`, "Environment"): what
//! rays that leave the scene see, for the runtime's background. The manifest's optional
//! `environment` entry names the kind (none, a uniform colour, the Hosek–Wilkie sky with its
//! parameters, an equirectangular image with intensity and rotation) and the sun's track over
//! the bake's time range; an image's texels are one [`crate::ChunkKind::EnvironmentImage`]
//! chunk (RGB f16, zstd).
//!
//! The model itself (radiance per direction) is `plenoptic_sky`'s; this module only stores
//! and checks it. Everything read is untrusted: sizes are checked against
//! [`EquirectImage::MAX_SIDE`] and [`SunTrack::MAX_SAMPLES`] before anything is allocated.

use std::sync::Arc;

use glam::Vec3;
use half::f16;
use plenoptic_sky::{Environment, EquirectImage, SkyParams, SunTrack};
use serde::{Deserialize, Serialize};

use crate::bytes::{ByteReader, PutLe, zstd_compress, zstd_decompress_exact};
use crate::error::{PackError, Result};

/// Magic of an environment-image chunk.
pub const ENVIRONMENT_IMAGE_MAGIC: [u8; 4] = *b"PEI1";
/// Bytes before the zstd frame of an environment-image chunk.
pub const ENVIRONMENT_IMAGE_HEADER_LEN: usize = 16;
/// Largest texel value an environment image stores (f16's largest finite value); brighter
/// texels are clamped to it.
pub const ENVIRONMENT_TEXEL_MAX: f32 = 65504.0;

/// What the manifest says about the environment.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EnvironmentEntry {
    /// Which environment, with its parameters.
    pub source: EnvironmentSource,
    /// The sun over the bake's time range (drives a sky; stored for any kind when the scene
    /// has a sun).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sun: Option<SunTrack>,
    /// Present when the sun's direct light is the runtime's (pack 3): the lighting and
    /// non-diffuse cubes and the volume samples leave out the direct light of this sun at the
    /// surfaces they store, and the runtime adds it with shadow rays against the proxies.
    /// The radiance cubes keep it. Requires `sun`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub direct_sun: Option<DirectSun>,
}

/// The sun whose direct light the runtime evaluates ([`EnvironmentEntry::direct_sun`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct DirectSun {
    /// Angular radius of the sun's disc, radians: 0 is a delta light with hard shadows (the
    /// tracers sample the disc for soft ones). At most [`DirectSun::MAX_ANGULAR_RADIUS`].
    pub angular_radius: f32,
}

impl DirectSun {
    /// Largest angular radius a pack may give (the tracers clamp the disc there too).
    pub const MAX_ANGULAR_RADIUS: f32 = 0.5;
}

/// The kind of environment and its parameters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum EnvironmentSource {
    /// Rays that leave the scene see nothing.
    None,
    /// The same linear RGB radiance from every direction.
    Uniform {
        /// The radiance.
        colour: Vec3,
    },
    /// The Hosek–Wilkie sky, lit from the sun's direction at each time.
    Sky {
        /// Turbidity, ground albedo, scale.
        params: SkyParams,
    },
    /// An equirectangular image; its texels are the pack's environment-image chunk.
    Image {
        /// Width of the image, texels.
        width: u32,
        /// Height of the image, texels.
        height: u32,
        /// Multiplies every texel.
        intensity: f32,
        /// Turn about +Y, degrees (plenoptic_sky's convention).
        rotation_deg: f32,
    },
}

impl EnvironmentSource {
    /// Checks the sky's ranges, a finite non-negative colour or intensity and the image size.
    fn validate(&self) -> std::result::Result<(), String> {
        match self {
            Self::None => Ok(()),
            Self::Uniform { colour } => {
                if colour.is_finite() && colour.min_element() >= 0.0 {
                    Ok(())
                } else {
                    Err(format!(
                        "uniform colour {:?} is not finite and non-negative",
                        colour.to_array()
                    ))
                }
            }
            Self::Sky { params } => params.validate().map_err(|e| format!("sky: {e}")),
            Self::Image {
                width,
                height,
                intensity,
                rotation_deg,
            } => {
                check_image_size(*width, *height).map_err(|e| e.to_string())?;
                if !(intensity.is_finite() && *intensity >= 0.0 && rotation_deg.is_finite()) {
                    return Err(format!(
                        "image intensity {intensity} or rotation {rotation_deg}° is not valid"
                    ));
                }
                Ok(())
            }
        }
    }
}

impl EnvironmentEntry {
    /// The entry for `environment` with the sun `sun` (the image's texels go in a chunk of
    /// their own: [`crate::PackWriter::add_environment_image`]).
    pub fn new(environment: &Environment, sun: Option<SunTrack>) -> Self {
        let source = match environment {
            Environment::None => EnvironmentSource::None,
            Environment::Uniform(c) => EnvironmentSource::Uniform { colour: *c },
            Environment::Sky(p) => EnvironmentSource::Sky { params: *p },
            Environment::Image {
                image,
                intensity,
                rotation_deg,
            } => EnvironmentSource::Image {
                width: image.width,
                height: image.height,
                intensity: *intensity,
                rotation_deg: *rotation_deg,
            },
        };
        EnvironmentEntry {
            source,
            sun,
            direct_sun: None,
        }
    }

    /// Checks what serde cannot: the sky's ranges, finite non-negative colours and intensity,
    /// image sizes within [`EquirectImage::MAX_SIDE`], a valid sun track. The message says
    /// what is wrong.
    pub fn validate(&self) -> std::result::Result<(), String> {
        if let Some(sun) = &self.sun {
            sun.validate().map_err(|e| format!("sun track: {e}"))?;
        }
        if let Some(d) = &self.direct_sun {
            if self.sun.is_none() {
                return Err("direct_sun is given without a sun track".into());
            }
            if !(0.0..=DirectSun::MAX_ANGULAR_RADIUS).contains(&d.angular_radius) {
                return Err(format!(
                    "direct_sun: angular radius {} is not within [0, {}]",
                    d.angular_radius,
                    DirectSun::MAX_ANGULAR_RADIUS
                ));
            }
        }
        self.source.validate()
    }

    /// The environment this entry describes, with `image` the decoded image chunk (needed for
    /// the image kind only; its size must match the entry's).
    pub fn environment(
        &self,
        image: Option<EquirectImage>,
    ) -> std::result::Result<Environment, String> {
        Ok(match &self.source {
            EnvironmentSource::None => Environment::None,
            EnvironmentSource::Uniform { colour } => Environment::Uniform(*colour),
            EnvironmentSource::Sky { params } => Environment::Sky(*params),
            EnvironmentSource::Image {
                width,
                height,
                intensity,
                rotation_deg,
            } => {
                let image = image.ok_or("the pack has no environment-image chunk")?;
                if (image.width, image.height) != (*width, *height) {
                    return Err(format!(
                        "the manifest says {width} × {height}, the image chunk is {} × {}",
                        image.width, image.height
                    ));
                }
                Environment::Image {
                    image: Arc::new(image),
                    intensity: *intensity,
                    rotation_deg: *rotation_deg,
                }
            }
        })
    }
}

fn check_image_size(width: u32, height: u32) -> Result<()> {
    let max = EquirectImage::MAX_SIDE;
    for (what, side) in [
        ("environment image width", width),
        ("environment image height", height),
    ] {
        if side > max {
            return Err(PackError::CountTooLarge {
                what,
                count: u64::from(side),
                max: u64::from(max),
            });
        }
        if side == 0 {
            return Err(PackError::payload(format!("{what} is 0")));
        }
    }
    Ok(())
}

/// Encodes an environment image as a chunk: header, then one zstd frame of RGB f16 texels
/// (row 0 at +Y first). Texels above [`ENVIRONMENT_TEXEL_MAX`] are clamped to it. Returns
/// the bytes and the uncompressed payload length.
pub fn encode_environment_image(image: &EquirectImage) -> Result<(Vec<u8>, u64)> {
    check_image_size(image.width, image.height)?;
    let n = image.width as usize * image.height as usize;
    if image.texels.len() != n {
        return Err(PackError::input(format!(
            "environment image has {} texels for {} × {}",
            image.texels.len(),
            image.width,
            image.height
        )));
    }
    let mut raw = Vec::with_capacity(n * 6);
    for t in &image.texels {
        for c in t.to_array() {
            // NaN and negatives become 0 (the image type forbids them anyway).
            let v = if c > 0.0 {
                c.min(ENVIRONMENT_TEXEL_MAX)
            } else {
                0.0
            };
            raw.put_u16(f16::from_f32(v).to_bits());
        }
    }
    let mut out = Vec::with_capacity(ENVIRONMENT_IMAGE_HEADER_LEN + raw.len() / 2);
    out.extend_from_slice(&ENVIRONMENT_IMAGE_MAGIC);
    out.put_u32(image.width);
    out.put_u32(image.height);
    out.put_u32(0);
    out.extend_from_slice(&zstd_compress(&raw)?);
    Ok((out, raw.len() as u64))
}

/// Checks an environment-image chunk's header; returns (width, height, uncompressed length).
pub(crate) fn environment_image_header(bytes: &[u8]) -> Result<(u32, u32, u64)> {
    let mut r = ByteReader::payload(bytes);
    if r.array::<4>()? != ENVIRONMENT_IMAGE_MAGIC {
        return Err(r.fail("not an environment-image chunk (bad magic)"));
    }
    let width = r.u32()?;
    let height = r.u32()?;
    let reserved = r.u32()?;
    if reserved != 0 {
        return Err(r.fail(format!("reserved field is {reserved:#x}, expected 0")));
    }
    check_image_size(width, height)?;
    Ok((width, height, u64::from(width) * u64::from(height) * 6))
}

/// Decodes an environment-image chunk.
pub fn decode_environment_image(bytes: &[u8]) -> Result<EquirectImage> {
    let (width, height, len) = environment_image_header(bytes)?;
    let frame = &bytes[ENVIRONMENT_IMAGE_HEADER_LEN..];
    // The frame must declare the size the header implies before anything is allocated.
    match zstd::zstd_safe::get_frame_content_size(frame) {
        Ok(Some(n)) if n == len => {}
        Ok(Some(n)) => {
            return Err(PackError::payload(format!(
                "zstd frame declares {n} bytes, {width} × {height} texels need {len}"
            )));
        }
        _ => {
            return Err(PackError::payload(
                "zstd frame is truncated or does not declare its size",
            ));
        }
    }
    let raw = zstd_decompress_exact(frame, len as usize, PackError::payload)?;
    let texels: Vec<Vec3> = raw
        .chunks_exact(6)
        .map(|c| {
            let h = |i: usize| f16::from_bits(u16::from_le_bytes([c[i], c[i + 1]])).to_f32();
            Vec3::new(h(0), h(2), h(4))
        })
        .collect();
    EquirectImage::new(width, height, texels)
        .map_err(|e| PackError::payload(format!("environment image: {e}")))
}

impl crate::PackReader {
    /// The environment the pack was baked with ([`Environment::None`] for packs without an
    /// entry), with the image read from its chunk. Errors name the pack file and the problem.
    pub fn environment(&self) -> Result<Environment> {
        let fail = |reason: String| PackError::InvalidEnvironment {
            path: self.path().to_path_buf(),
            reason,
        };
        let Some(entry) = &self.manifest().environment else {
            return Ok(Environment::None);
        };
        let image = match entry.source {
            EnvironmentSource::Image { .. } => {
                Some(self.environment_image().map_err(|e| match e {
                    PackError::InvalidEnvironment { .. } => e,
                    other => fail(other.to_string()),
                })?)
            }
            _ => None,
        };
        entry.environment(image).map_err(fail)
    }

    /// The sun's track, when the pack has one.
    pub fn sun_track(&self) -> Option<&SunTrack> {
        self.manifest().environment.as_ref()?.sun.as_ref()
    }

    /// The sun whose direct light the runtime adds, with its track, when the pack leaves it
    /// out of the lighting ([`EnvironmentEntry::direct_sun`]; checked at open).
    pub fn direct_sun(&self) -> Option<(&SunTrack, DirectSun)> {
        let env = self.manifest().environment.as_ref()?;
        Some((env.sun.as_ref()?, env.direct_sun?))
    }

    /// The environment-image chunk, decoded.
    pub fn environment_image(&self) -> Result<EquirectImage> {
        match self.get(crate::ChunkKind::EnvironmentImage, crate::NO_BASE_VIEW, 0)? {
            crate::Chunk::EnvironmentImage(i) => Ok(i),
            _ => unreachable!("decoded by kind"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn image_chunk_round_trips_within_f16_and_clamps() {
        let texels = (0..8 * 4)
            .map(|i| Vec3::new(i as f32 * 0.37, 1.0, 1e6))
            .collect();
        let image = EquirectImage::new(8, 4, texels).unwrap();
        let (bytes, len) = encode_environment_image(&image).unwrap();
        assert_eq!(len, 8 * 4 * 6);
        let back = decode_environment_image(&bytes).unwrap();
        for (a, b) in image.texels.iter().zip(&back.texels) {
            assert!((a.x - b.x).abs() <= a.x * 2f32.powi(-11) + 1e-6, "{a} {b}");
            assert!((b.y - 1.0).abs() < 1e-6);
            assert!((b.z - ENVIRONMENT_TEXEL_MAX).abs() < 1.0, "clamped: {b}");
        }
    }

    #[test]
    fn bad_headers_are_errors_before_allocation() {
        let image = EquirectImage::new(2, 1, vec![Vec3::ONE; 2]).unwrap();
        let (bytes, _) = encode_environment_image(&image).unwrap();
        let mut huge = bytes.clone();
        huge[4..8].copy_from_slice(&(EquirectImage::MAX_SIDE + 1).to_le_bytes());
        let e = decode_environment_image(&huge).unwrap_err();
        assert!(e.to_string().contains("width"), "{e}");
        // A header claiming more texels than the frame holds.
        let mut lying = bytes.clone();
        lying[8..12].copy_from_slice(&2u32.to_le_bytes());
        let e = decode_environment_image(&lying).unwrap_err();
        assert!(e.to_string().contains("zstd"), "{e}");
        let e = decode_environment_image(&bytes[..10]).unwrap_err();
        assert!(matches!(e, PackError::MalformedChunk { .. }), "{e}");
    }
}
