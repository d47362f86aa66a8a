//! Frame files: linear OpenEXR (radiance as 32-bit float `R`, `G`, `B`, depth as `Z`) and
//! tonemapped 8-bit PNG.
//!
//! EXR goes through the `exr` crate. [`write_exr`] writes scanlines with lossless ZIP
//! compression (16 lines per block). [`read_exr`] and [`read_exr_frame`] read what other
//! tools write too: any compression the crate decodes (ZIP, PIZ, RLE, PXR24, B44, …), half,
//! float or integer samples, scanlines or tiles, in the first layer that has `R`, `G` and `B`
//! channels; depth from `Z` (or `depth`) when present. Every error names the file.
//!
//! Tonemapping for PNG ([`tonemap`]): `exposure × radiance`, then the ACES filmic curve fitted
//! by Narkowicz (2015), `x(2.51x + 0.03) / (x(2.43x + 0.59) + 0.14)` per channel, then the sRGB
//! transfer function. [`auto_exposure`] maps the log-average luminance to 0.18.

use std::path::Path;

use exr::prelude::*;
use glam::Vec3;

use crate::{EvalError, Result};

fn exr_error(path: &Path, e: impl std::fmt::Display) -> EvalError {
    EvalError::Exr {
        path: path.to_path_buf(),
        message: e.to_string(),
    }
}

/// The compression [`write_exr`] uses.
pub const WRITE_ENCODING: Encoding = Encoding::SMALL_LOSSLESS;

/// Writes linear radiance (and optionally depth as `Z`; non-finite depth as `f32::MAX`) as a
/// ZIP-compressed float EXR.
pub fn write_exr(
    path: impl AsRef<Path>,
    width: u32,
    height: u32,
    radiance: &[Vec3],
    depth: Option<&[f32]>,
) -> Result<()> {
    let path = path.as_ref();
    let (w, h) = (width as usize, height as usize);
    let n = w * h;
    if radiance.len() != n || depth.is_some_and(|d| d.len() != n) || n == 0 {
        return Err(EvalError::invalid(
            path,
            format!("pixel count does not match {width}×{height}"),
        ));
    }
    let rgb = |p: Vec2<usize>| radiance[p.y() * w + p.x()];
    let written = match depth {
        Some(d) => {
            let channels = SpecificChannels::build()
                .with_channel("R")
                .with_channel("G")
                .with_channel("B")
                .with_channel("Z")
                .with_pixel_fn(|p| {
                    let c = rgb(p);
                    let z = d[p.y() * w + p.x()];
                    (c.x, c.y, c.z, if z.is_finite() { z } else { f32::MAX })
                });
            Image::from_encoded_channels((w, h), WRITE_ENCODING, channels)
                .write()
                .to_file(path)
        }
        None => {
            let channels = SpecificChannels::rgb(|p| {
                let c = rgb(p);
                (c.x, c.y, c.z)
            });
            Image::from_encoded_channels((w, h), WRITE_ENCODING, channels)
                .write()
                .to_file(path)
        }
    };
    written.map_err(|e| exr_error(path, e))
}

/// A frame read from an EXR file.
#[derive(Clone, Debug, PartialEq)]
pub struct ExrFrame {
    /// Width, pixels.
    pub width: u32,
    /// Height, pixels.
    pub height: u32,
    /// Linear radiance, row-major from the top row.
    pub radiance: Vec<Vec3>,
    /// Depth from the `Z` (or `depth`) channel, if the file has one.
    pub depth: Option<Vec<f32>>,
}

/// Reads radiance and depth from an EXR file (see the module docs for what is accepted).
pub fn read_exr_frame(path: impl AsRef<Path>) -> Result<ExrFrame> {
    let path = path.as_ref();
    if !path.is_file() {
        return Err(EvalError::io(
            path,
            std::io::Error::new(std::io::ErrorKind::NotFound, "no such file"),
        ));
    }
    struct Pixels {
        width: usize,
        radiance: Vec<Vec3>,
        depth: Option<Vec<f32>>,
    }
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .specific_channels()
        .required("R")
        .required("G")
        .required("B")
        .optional("Z", f32::INFINITY)
        .optional("depth", f32::INFINITY)
        .collect_pixels(
            |size, (_, _, _, z, depth)| Pixels {
                width: size.width(),
                radiance: vec![Vec3::ZERO; size.area()],
                depth: (z.is_some() || depth.is_some()).then(|| vec![0.0; size.area()]),
            },
            |px: &mut Pixels, p, (r, g, b, z, depth): (f32, f32, f32, f32, f32)| {
                let i = p.y() * px.width + p.x();
                px.radiance[i] = Vec3::new(r, g, b);
                if let Some(d) = &mut px.depth {
                    d[i] = if z.is_finite() || !depth.is_finite() {
                        z
                    } else {
                        depth
                    };
                }
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .map_err(|e| exr_error(path, e))?;
    let layer = image.layer_data;
    let (w, h) = (layer.size.width(), layer.size.height());
    Ok(ExrFrame {
        width: w as u32,
        height: h as u32,
        radiance: layer.channel_data.pixels.radiance,
        depth: layer.channel_data.pixels.depth,
    })
}

/// Reads the radiance of an EXR file: `(width, height, radiance)`.
pub fn read_exr(path: impl AsRef<Path>) -> Result<(u32, u32, Vec<Vec3>)> {
    let f = read_exr_frame(path)?;
    Ok((f.width, f.height, f.radiance))
}

/// Exposure mapping the log-average luminance of `radiance` to 0.18 (1 for a black image).
pub fn auto_exposure(radiance: &[Vec3]) -> f32 {
    let lum = |c: Vec3| c.dot(Vec3::new(0.2126, 0.7152, 0.0722));
    let n = radiance.len().max(1) as f64;
    let log: f64 = radiance
        .iter()
        .map(|&c| f64::from(lum(c).max(1e-4)).ln())
        .sum::<f64>()
        / n;
    let avg = log.exp() as f32;
    if avg > 1e-4 { 0.18 / avg } else { 1.0 }
}

/// One linear colour as the PNG frames display it, sRGB-encoded in [0, 1] per channel
/// (exposure, ACES fit, sRGB), before quantisation.
pub fn display(c: Vec3, exposure: f32) -> Vec3 {
    let aces = |x: f32| {
        let x = (x * exposure).max(0.0);
        (x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14)).clamp(0.0, 1.0)
    };
    Vec3::from_array(
        c.to_array()
            .map(|v| plenoptic_pack::texture::linear_to_srgb(aces(v))),
    )
}

/// Tonemaps one linear colour to 8-bit sRGB ([`display`], quantised).
pub fn tonemap(c: Vec3, exposure: f32) -> [u8; 3] {
    display(c, exposure)
        .to_array()
        .map(|v| (v * 255.0 + 0.5) as u8)
}

/// Writes a tonemapped PNG.
pub fn write_png(
    path: impl AsRef<Path>,
    width: u32,
    height: u32,
    radiance: &[Vec3],
    exposure: f32,
) -> Result<()> {
    let path = path.as_ref();
    let bytes: Vec<u8> = radiance
        .iter()
        .flat_map(|&c| tonemap(c, exposure))
        .collect();
    let n = width as usize * height as usize;
    if radiance.len() != n || n == 0 {
        return Err(EvalError::invalid(
            path,
            format!("{} pixels for a {width}×{height} PNG", radiance.len()),
        ));
    }
    image::save_buffer(path, &bytes, width, height, image::ExtendedColorType::Rgb8).map_err(|e| {
        EvalError::Png {
            path: path.to_path_buf(),
            message: e.to_string(),
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exr_round_trip_with_and_without_depth() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("f.exr");
        let px: Vec<Vec3> = (0..12)
            .map(|i| Vec3::new(i as f32, 0.5, 100.0 - i as f32))
            .collect();
        let mut depth = vec![1.5; 12];
        depth[5] = f32::INFINITY;
        write_exr(&p, 4, 3, &px, Some(&depth)).unwrap();
        let back = read_exr_frame(&p).unwrap();
        assert_eq!((back.width, back.height), (4, 3));
        assert_eq!(back.radiance, px);
        let d = back.depth.unwrap();
        assert_eq!((d[0], d[5]), (1.5, f32::MAX));
        write_exr(&p, 4, 3, &px, None).unwrap();
        let back = read_exr_frame(&p).unwrap();
        assert_eq!((back.radiance, back.depth), (px, None));
    }

    /// Half-float RGB + Z written by the `exr` crate itself with `compression`, read back.
    fn half_float_round_trip(compression: Compression, blocks: Blocks) {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("other_tool.exr");
        let (w, h) = (37usize, 23usize);
        let colour = |x: usize, y: usize| {
            Vec3::new(
                x as f32 / 7.0,
                0.01 + y as f32 * 3.3,
                ((x * 31 + y * 17) % 97) as f32 * 0.125,
            )
        };
        let channels = SpecificChannels::build()
            .with_channel("R")
            .with_channel("G")
            .with_channel("B")
            .with_channel("Z")
            .with_pixel_fn(|p: Vec2<usize>| {
                let c = colour(p.x(), p.y());
                (
                    f16::from_f32(c.x),
                    f16::from_f32(c.y),
                    f16::from_f32(c.z),
                    f16::from_f32(1.0 + p.x() as f32 * 0.5),
                )
            });
        let encoding = Encoding {
            compression,
            blocks,
            line_order: LineOrder::Increasing,
        };
        Image::from_encoded_channels((w, h), encoding, channels)
            .write()
            .to_file(&p)
            .unwrap();
        let f = read_exr_frame(&p).unwrap();
        assert_eq!((f.width, f.height), (w as u32, h as u32));
        // Half floats keep 11 significant bits: relative error ≤ 2⁻¹¹.
        let close = |a: f32, b: f32| (a - b).abs() <= b.abs() * 4.9e-4 + 1e-7;
        for y in 0..h {
            for x in 0..w {
                let (got, want) = (f.radiance[y * w + x], colour(x, y));
                assert!(
                    (0..3).all(|k| close(got[k], want[k])),
                    "{compression:?} ({x}, {y}): {got} vs {want}"
                );
            }
        }
        let depth = f.depth.unwrap();
        assert!(close(depth[w + 8], 5.0), "{}", depth[w + 8]);
    }

    #[test]
    fn reads_zip_compressed_half_floats() {
        half_float_round_trip(Compression::ZIP16, Blocks::ScanLines);
    }

    #[test]
    fn reads_piz_compressed_half_float_tiles() {
        half_float_round_trip(Compression::PIZ, Blocks::Tiles(Vec2(16, 16)));
    }

    #[test]
    fn errors_name_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let missing = dir.path().join("none.exr");
        let e = read_exr(&missing).unwrap_err().to_string();
        assert!(e.contains("none.exr"), "{e}");
        let junk = dir.path().join("junk.exr");
        std::fs::write(&junk, b"not an exr at all").unwrap();
        let e = read_exr(&junk).unwrap_err().to_string();
        assert!(e.contains("junk.exr"), "{e}");
        // Channels other than RGB only: named as unreadable, with the file.
        let grey = dir.path().join("grey.exr");
        let channels = SpecificChannels::build()
            .with_channel("Y")
            .with_pixel_fn(|_p: Vec2<usize>| (0.5f32,));
        Image::from_channels((4, 4), channels)
            .write()
            .to_file(&grey)
            .unwrap();
        let e = read_exr(&grey).unwrap_err().to_string();
        assert!(e.contains("grey.exr"), "{e}");
        let e = write_exr(dir.path().join("bad.exr"), 2, 2, &[Vec3::ZERO], None)
            .unwrap_err()
            .to_string();
        assert!(e.contains("bad.exr"), "{e}");
    }

    #[test]
    fn tonemap_and_exposure() {
        assert_eq!(tonemap(Vec3::ZERO, 1.0), [0, 0, 0]);
        assert_eq!(tonemap(Vec3::splat(1e6), 1.0), [255, 255, 255]);
        let e = auto_exposure(&[Vec3::splat(0.36); 4]);
        assert!((e - 0.5).abs() < 1e-4, "{e}");
        assert_eq!(auto_exposure(&[Vec3::ZERO; 4]), 1.0);
    }
}
