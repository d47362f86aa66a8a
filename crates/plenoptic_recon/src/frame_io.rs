//! Frame files: linear OpenEXR (uncompressed, 32-bit float `R`, `G`, `B` and `Z` = depth) and
//! tonemapped 8-bit PNG.
//!
//! The EXR writer and reader are deliberately small (scanline, no compression, float
//! channels), so that reference frames written by `plenoptic reference` and reconstructed
//! frames written by `plenoptic render` can be compared without another dependency; any
//! OpenEXR tool reads them. [`read_exr`] reads exactly this subset and names what it does not
//! support.
//!
//! Tonemapping for PNG ([`tonemap`]): `exposure × radiance`, then the ACES filmic curve fitted
//! by Narkowicz (2015), `x(2.51x + 0.03) / (x(2.43x + 0.59) + 0.14)` per channel, then the sRGB
//! transfer function. [`auto_exposure`] maps the log-average luminance to 0.18.

use std::path::Path;

use glam::Vec3;

use crate::{Error, Result};

fn io(path: &Path, e: impl std::fmt::Display) -> Error {
    Error::Io(format!("{}: {e}", path.display()))
}

fn attr(out: &mut Vec<u8>, name: &str, ty: &str, value: &[u8]) {
    out.extend_from_slice(name.as_bytes());
    out.push(0);
    out.extend_from_slice(ty.as_bytes());
    out.push(0);
    out.extend_from_slice(&(value.len() as i32).to_le_bytes());
    out.extend_from_slice(value);
}

/// Writes linear radiance (and optionally depth as `Z`) as an uncompressed float EXR.
pub fn write_exr(
    path: impl AsRef<Path>,
    width: u32,
    height: u32,
    radiance: &[Vec3],
    depth: Option<&[f32]>,
) -> Result<()> {
    let path = path.as_ref();
    let n = width as usize * height as usize;
    if radiance.len() != n || depth.is_some_and(|d| d.len() != n) || n == 0 {
        return Err(Error::Io(format!(
            "{}: pixel count does not match {width}×{height}",
            path.display()
        )));
    }
    let names: &[&str] = if depth.is_some() {
        &["B", "G", "R", "Z"]
    } else {
        &["B", "G", "R"]
    };
    let mut out = vec![0x76, 0x2f, 0x31, 0x01, 2, 0, 0, 0];
    let mut ch = Vec::new();
    for name in names {
        ch.extend_from_slice(name.as_bytes());
        ch.push(0);
        ch.extend_from_slice(&2i32.to_le_bytes()); // FLOAT
        ch.extend_from_slice(&[0, 0, 0, 0]); // pLinear + reserved
        ch.extend_from_slice(&1i32.to_le_bytes());
        ch.extend_from_slice(&1i32.to_le_bytes());
    }
    ch.push(0);
    attr(&mut out, "channels", "chlist", &ch);
    attr(&mut out, "compression", "compression", &[0]);
    let mut bx = Vec::new();
    for v in [0i32, 0, width as i32 - 1, height as i32 - 1] {
        bx.extend_from_slice(&v.to_le_bytes());
    }
    attr(&mut out, "dataWindow", "box2i", &bx);
    attr(&mut out, "displayWindow", "box2i", &bx);
    attr(&mut out, "lineOrder", "lineOrder", &[0]);
    attr(&mut out, "pixelAspectRatio", "float", &1f32.to_le_bytes());
    attr(&mut out, "screenWindowCenter", "v2f", &[0u8; 8]);
    attr(&mut out, "screenWindowWidth", "float", &1f32.to_le_bytes());
    out.push(0);
    let w = width as usize;
    let line_bytes = w * 4 * names.len();
    let table_start = out.len();
    let first = table_start + 8 * height as usize;
    for y in 0..height as usize {
        out.extend_from_slice(&((first + y * (8 + line_bytes)) as u64).to_le_bytes());
    }
    for y in 0..height as usize {
        out.extend_from_slice(&(y as i32).to_le_bytes());
        out.extend_from_slice(&(line_bytes as i32).to_le_bytes());
        let row = &radiance[y * w..(y + 1) * w];
        for c in [2usize, 1, 0] {
            for p in row {
                out.extend_from_slice(&p[c].to_le_bytes());
            }
        }
        if let Some(d) = depth {
            for z in &d[y * w..(y + 1) * w] {
                let z = if z.is_finite() { *z } else { f32::MAX };
                out.extend_from_slice(&z.to_le_bytes());
            }
        }
    }
    std::fs::write(path, out).map_err(|e| io(path, e))
}

/// Reads an EXR written by [`write_exr`] (or any scanline, uncompressed EXR with float or half
/// `R`, `G`, `B` channels): `(width, height, radiance)`.
pub fn read_exr(path: impl AsRef<Path>) -> Result<(u32, u32, Vec<Vec3>)> {
    let path = path.as_ref();
    let bytes = std::fs::read(path).map_err(|e| io(path, e))?;
    let bad = |m: &str| Error::Io(format!("{}: {m}", path.display()));
    if bytes.len() < 8 || bytes[..4] != [0x76, 0x2f, 0x31, 0x01] {
        return Err(bad("not an OpenEXR file"));
    }
    if bytes[5] & 0x06 != 0 {
        return Err(bad("tiled or multi-part EXR is not supported"));
    }
    let mut pos = 8;
    let cstr = |pos: &mut usize| -> Result<String> {
        let end = bytes[*pos..]
            .iter()
            .position(|&b| b == 0)
            .ok_or_else(|| bad("truncated header"))?;
        let s = String::from_utf8_lossy(&bytes[*pos..*pos + end]).into_owned();
        *pos += end + 1;
        Ok(s)
    };
    let i32_at = |p: usize| -> Result<i32> {
        bytes
            .get(p..p + 4)
            .map(|b| i32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .ok_or_else(|| bad("truncated"))
    };
    let mut channels: Vec<(String, i32)> = Vec::new();
    let mut window = None;
    loop {
        let name = cstr(&mut pos)?;
        if name.is_empty() {
            break;
        }
        let _ty = cstr(&mut pos)?;
        let size = i32_at(pos)?.max(0) as usize;
        pos += 4;
        let value = bytes
            .get(pos..pos + size)
            .ok_or_else(|| bad("truncated attribute"))?;
        match name.as_str() {
            "channels" => {
                let mut p = 0;
                while p < value.len() && value[p] != 0 {
                    let end = value[p..]
                        .iter()
                        .position(|&b| b == 0)
                        .ok_or_else(|| bad("bad chlist"))?;
                    let n = String::from_utf8_lossy(&value[p..p + end]).into_owned();
                    p += end + 1;
                    let t = value
                        .get(p..p + 4)
                        .map(|b| i32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                        .ok_or_else(|| bad("bad chlist"))?;
                    p += 16;
                    channels.push((n, t));
                }
            }
            "compression" if value.first() != Some(&0) => {
                return Err(bad(&format!(
                    "compression {} is not supported (write with plenoptic_recon::frame_io::write_exr)",
                    value.first().copied().unwrap_or(255)
                )));
            }
            "dataWindow" if size == 16 => {
                let v: Vec<i32> = value
                    .chunks_exact(4)
                    .map(|b| i32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                    .collect();
                window = Some((v[0], v[1], v[2], v[3]));
            }
            _ => {}
        }
        pos += size;
    }
    let (x0, y0, x1, y1) = window.ok_or_else(|| bad("no dataWindow"))?;
    let (w, h) = ((x1 - x0 + 1) as usize, (y1 - y0 + 1) as usize);
    if w == 0 || h == 0 || w > 1 << 15 || h > 1 << 15 {
        return Err(bad("bad data window"));
    }
    let sizes: Vec<usize> = channels
        .iter()
        .map(|c| if c.1 == 1 { 2 } else { 4 })
        .collect();
    let line: usize = sizes.iter().sum::<usize>() * w;
    let mut out = vec![Vec3::ZERO; w * h];
    for y in 0..h {
        let off_at = pos + 8 * y;
        let off = bytes
            .get(off_at..off_at + 8)
            .map(|b| u64::from_le_bytes(b.try_into().unwrap_or([0; 8])))
            .ok_or_else(|| bad("truncated offsets"))? as usize;
        let ly = (i32_at(off)? - y0) as usize;
        let data = bytes
            .get(off + 8..off + 8 + line)
            .ok_or_else(|| bad("truncated scanline"))?;
        if ly >= h {
            return Err(bad("scanline out of range"));
        }
        let mut p = 0;
        for (c, s) in channels.iter().zip(&sizes) {
            let comp = match c.0.as_str() {
                "R" => Some(0),
                "G" => Some(1),
                "B" => Some(2),
                _ => None,
            };
            for x in 0..w {
                let b = &data[p + x * s..p + (x + 1) * s];
                let v = match c.1 {
                    1 => half_to_f32(u16::from_le_bytes([b[0], b[1]])),
                    2 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
                    _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f32,
                };
                if let Some(k) = comp {
                    out[ly * w + x][k] = v;
                }
            }
            p += s * w;
        }
    }
    Ok((w as u32, h as u32, out))
}

fn half_to_f32(h: u16) -> f32 {
    let s = if h & 0x8000 != 0 { -1.0 } else { 1.0 };
    let e = ((h >> 10) & 0x1f) as i32;
    let m = (h & 0x3ff) as f32;
    s * match e {
        0 => m * 2f32.powi(-24),
        31 => f32::INFINITY,
        _ => (1.0 + m / 1024.0) * 2f32.powi(e - 15),
    }
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

/// Tonemaps one linear colour to 8-bit sRGB (exposure, ACES fit, sRGB).
pub fn tonemap(c: Vec3, exposure: f32) -> [u8; 3] {
    let aces = |x: f32| {
        let x = (x * exposure).max(0.0);
        (x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14)).clamp(0.0, 1.0)
    };
    let srgb = |x: f32| {
        if x <= 0.0031308 {
            12.92 * x
        } else {
            1.055 * x.powf(1.0 / 2.4) - 0.055
        }
    };
    c.to_array().map(|v| (srgb(aces(v)) * 255.0 + 0.5) as u8)
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
    image::save_buffer(path, &bytes, width, height, image::ExtendedColorType::Rgb8)
        .map_err(|e| io(path, e))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exr_round_trip() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("f.exr");
        let px: Vec<Vec3> = (0..12)
            .map(|i| Vec3::new(i as f32, 0.5, 100.0 - i as f32))
            .collect();
        write_exr(&p, 4, 3, &px, Some(&[1.0; 12])).unwrap();
        let (w, h, back) = read_exr(&p).unwrap();
        assert_eq!((w, h), (4, 3));
        assert_eq!(back, px);
        assert_eq!(tonemap(Vec3::ZERO, 1.0), [0, 0, 0]);
        assert!(read_exr(dir.path().join("none.exr")).is_err());
    }
}
