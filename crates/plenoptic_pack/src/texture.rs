//! Material textures (pack 1.2; docs/architecture.md, "Pack v2", **Materials**: "the glTF
//! material and its textures (mipmapped KTX2)"; `docs/pack-format.md`, "Material texture"):
//! RGBA8 images with their full mip chain, stored as one KTX2 file per
//! [`crate::ChunkKind::MaterialTexture`] chunk that Bevy's own KTX2 loader opens.
//!
//! The chain goes down to 1×1 (`levelCount = ⌊log₂ max(W, H)⌋ + 1`), each level a 2×2 box
//! filter of the one above: in linear light for sRGB textures (decode, average, re-encode), on
//! the stored values for linear ones; alpha is always averaged as stored. Sides of 1 stay 1;
//! an odd side drops its last row or column (level `l` is `max(1, W >> l) × max(1, H >> l)`).
//!
//! Decoding is for untrusted bytes: the header, format, DFD, level count and every level's
//! size are checked against [`MAX_TEXTURE_SIDE`] and each other, and every zstd frame must
//! declare its exact size, before anything is allocated.

use glam::Vec4;
use ktx2::Format;
use serde::{Deserialize, Serialize};

use crate::bytes::zstd_decompress_exact;
use crate::error::{PackError, Result};
use crate::ktx::{check_header, write_ktx2};

/// Largest width or height of a material texture (Bevy's and WebGPU's default
/// `max_texture_dimension_2d`); the full chain of an 8192² texture is about 358 MB decoded.
pub const MAX_TEXTURE_SIDE: u32 = 8192;

/// The vkFormats of material textures.
pub const TEXTURE_FORMATS: [Format; 2] = [Format::R8G8B8A8_SRGB, Format::R8G8B8A8_UNORM];

/// How a texture's RGB values are encoded (alpha is always linear).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ColourSpace {
    /// sRGB transfer function: base colour and emissive textures (`R8G8B8A8_SRGB`).
    Srgb,
    /// Stored values are the values: metallic-roughness and normal maps (`R8G8B8A8_UNORM`).
    Linear,
}

impl ColourSpace {
    /// The KTX2 vkFormat a texture of this colour space is stored in.
    pub fn vk_format(self) -> Format {
        match self {
            ColourSpace::Srgb => Format::R8G8B8A8_SRGB,
            ColourSpace::Linear => Format::R8G8B8A8_UNORM,
        }
    }

    /// Whether the texture is sRGB: the value to give Bevy's image loader as `is_srgb`
    /// (`ImageLoaderSettings::is_srgb`; Bevy 0.19 takes sRGB-ness from that setting, not from
    /// the file's vkFormat).
    pub fn is_srgb(self) -> bool {
        self == ColourSpace::Srgb
    }

    fn from_format(format: Format) -> Self {
        if format == Format::R8G8B8A8_SRGB {
            ColourSpace::Srgb
        } else {
            ColourSpace::Linear
        }
    }
}

/// One mip level: `width × height` RGBA8 texels, row-major, row 0 at the top (glTF's UV
/// origin, KTX2's default orientation).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TextureLevel {
    /// Width, texels.
    pub width: u32,
    /// Height, texels.
    pub height: u32,
    /// `4·width·height` bytes: R, G, B, A per texel.
    pub texels: Vec<u8>,
}

/// A material texture with its full mip chain (level 0 the largest).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TextureImage {
    /// How RGB is encoded.
    pub colour_space: ColourSpace,
    /// Level 0 (full resolution) to the 1×1 level.
    pub levels: Vec<TextureLevel>,
}

/// Number of levels of a full mip chain of a `width × height` texture:
/// `⌊log₂ max(width, height)⌋ + 1` (1 for a 0-sized input).
pub fn mip_count(width: u32, height: u32) -> u32 {
    32 - width.max(height).max(1).leading_zeros()
}

/// Size of level `level` of a `width × height` texture: each side halved, at least 1.
pub fn mip_size(width: u32, height: u32, level: u32) -> (u32, u32) {
    let half = |s: u32| s.checked_shr(level).unwrap_or(0).max(1);
    (half(width), half(height))
}

/// The sRGB transfer function (linear in [0, 1] → encoded in [0, 1]).
pub fn linear_to_srgb(c: f32) -> f32 {
    let c = c.clamp(0.0, 1.0);
    if c <= 0.003_130_8 {
        c * 12.92
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

/// The inverse of [`linear_to_srgb`].
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.040_45 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

fn to_u8(v: f32) -> u8 {
    // NaN clamps to 0.
    (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8
}

fn check_size(width: u32, height: u32) -> Result<()> {
    for (what, side) in [("texture width", width), ("texture height", height)] {
        if side > MAX_TEXTURE_SIDE {
            return Err(PackError::CountTooLarge {
                what,
                count: u64::from(side),
                max: u64::from(MAX_TEXTURE_SIDE),
            });
        }
        if side == 0 {
            return Err(PackError::payload(format!("{what} is 0")));
        }
    }
    Ok(())
}

/// The next level of `level`: a 2×2 box filter (in linear light for sRGB), see the module doc.
pub fn next_mip(colour_space: ColourSpace, level: &TextureLevel) -> TextureLevel {
    let (w, h) = (level.width as usize, level.height as usize);
    let (nw, nh) = ((w / 2).max(1), (h / 2).max(1));
    let lut: [f32; 256] = std::array::from_fn(|i| match colour_space {
        ColourSpace::Srgb => srgb_to_linear(i as f32 / 255.0),
        ColourSpace::Linear => i as f32 / 255.0,
    });
    let mut texels = Vec::with_capacity(nw * nh * 4);
    for y in 0..nh {
        let rows = [(2 * y).min(h - 1), (2 * y + 1).min(h - 1)];
        for x in 0..nw {
            let cols = [(2 * x).min(w - 1), (2 * x + 1).min(w - 1)];
            let mut sum = [0f32; 4];
            for &r in &rows {
                for &c in &cols {
                    let t = &level.texels[(r * w + c) * 4..][..4];
                    for (s, &v) in sum.iter_mut().zip(&t[..3]) {
                        *s += lut[v as usize];
                    }
                    sum[3] += t[3] as f32 / 255.0;
                }
            }
            for (k, s) in sum.iter().enumerate() {
                let mean = s / 4.0;
                let encoded = if k < 3 && colour_space == ColourSpace::Srgb {
                    linear_to_srgb(mean)
                } else {
                    mean
                };
                texels.push(to_u8(encoded));
            }
        }
    }
    TextureLevel {
        width: nw as u32,
        height: nh as u32,
        texels,
    }
}

impl TextureImage {
    /// A texture from its level 0 (`4·width·height` RGBA8 bytes, row 0 at the top) with the
    /// full mip chain generated.
    pub fn with_mips(
        colour_space: ColourSpace,
        width: u32,
        height: u32,
        texels: Vec<u8>,
    ) -> Result<Self> {
        check_size(width, height).map_err(|e| PackError::input(e.to_string()))?;
        if texels.len() != 4 * width as usize * height as usize {
            return Err(PackError::input(format!(
                "texture of {width} × {height} has {} bytes, expected {}",
                texels.len(),
                4 * width as usize * height as usize
            )));
        }
        let mut levels = vec![TextureLevel {
            width,
            height,
            texels,
        }];
        while levels.len() < mip_count(width, height) as usize {
            let next = next_mip(colour_space, levels.last().expect("level 0"));
            levels.push(next);
        }
        Ok(TextureImage {
            colour_space,
            levels,
        })
    }

    /// A texture from linear RGBA values in [0, 1] (out-of-range values clamp; RGB is
    /// sRGB-encoded for [`ColourSpace::Srgb`]), with the full mip chain generated.
    pub fn from_linear(
        colour_space: ColourSpace,
        width: u32,
        height: u32,
        texels: &[Vec4],
    ) -> Result<Self> {
        if texels.len() != width as usize * height as usize {
            return Err(PackError::input(format!(
                "texture of {width} × {height} has {} texels",
                texels.len()
            )));
        }
        let mut bytes = Vec::with_capacity(texels.len() * 4);
        for t in texels {
            let rgb = t.truncate().to_array().map(|c| match colour_space {
                ColourSpace::Srgb => linear_to_srgb(c),
                ColourSpace::Linear => c,
            });
            bytes.extend(rgb.map(to_u8));
            bytes.push(to_u8(t.w));
        }
        Self::with_mips(colour_space, width, height, bytes)
    }

    /// Width of level 0.
    pub fn width(&self) -> u32 {
        self.levels.first().map_or(0, |l| l.width)
    }

    /// Height of level 0.
    pub fn height(&self) -> u32 {
        self.levels.first().map_or(0, |l| l.height)
    }
}

/// What the header of a material-texture chunk says.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TextureInfo {
    /// sRGB or linear (from the vkFormat).
    pub colour_space: ColourSpace,
    /// Width of level 0.
    pub width: u32,
    /// Height of level 0.
    pub height: u32,
    /// Number of levels (always the full chain).
    pub levels: u32,
    /// Sum of the levels' uncompressed byte lengths.
    pub uncompressed_length: u64,
}

/// Encodes a texture as a KTX2 chunk; returns the bytes and the uncompressed length (all
/// levels). The chain must be complete and each level the size [`mip_size`] gives.
pub fn encode_texture(texture: &TextureImage) -> Result<(Vec<u8>, u64)> {
    let (w, h) = (texture.width(), texture.height());
    check_size(w, h).map_err(|e| PackError::input(e.to_string()))?;
    if texture.levels.len() != mip_count(w, h) as usize {
        return Err(PackError::input(format!(
            "a {w} × {h} texture has {} levels, its full chain {}",
            texture.levels.len(),
            mip_count(w, h)
        )));
    }
    for (l, level) in texture.levels.iter().enumerate() {
        let (lw, lh) = mip_size(w, h, l as u32);
        if (level.width, level.height) != (lw, lh) || level.texels.len() != 4 * (lw * lh) as usize {
            return Err(PackError::input(format!(
                "level {l} is {} × {} with {} bytes, expected {lw} × {lh} RGBA8",
                level.width,
                level.height,
                level.texels.len()
            )));
        }
    }
    let raw: Vec<&[u8]> = texture.levels.iter().map(|l| l.texels.as_slice()).collect();
    let bytes = write_ktx2(texture.colour_space.vk_format(), (w, h), 1, &raw)?;
    let len = raw.iter().map(|l| l.len() as u64).sum();
    Ok((bytes, len))
}

/// Checks a material-texture chunk's header without decompressing it.
pub fn inspect_texture(bytes: &[u8]) -> Result<TextureInfo> {
    let (h, format) = check_header(bytes, &TEXTURE_FORMATS)?;
    if h.face_count != 1 || h.layer_count != 0 || h.pixel_depth != 0 {
        return Err(PackError::ktx(format!(
            "not a 2-D texture: faceCount {}, layerCount {}, pixelDepth {}",
            h.face_count, h.layer_count, h.pixel_depth
        )));
    }
    let (w, ht) = (h.pixel_width, h.pixel_height);
    check_size(w, ht).map_err(|e| PackError::ktx(e.to_string()))?;
    let full = mip_count(w, ht);
    if h.level_count != full {
        return Err(PackError::ktx(format!(
            "levelCount {} but a {w} × {ht} texture's full mip chain has {full} levels",
            h.level_count
        )));
    }
    let uncompressed_length = (0..full)
        .map(|l| {
            let (a, b) = mip_size(w, ht, l);
            4 * u64::from(a) * u64::from(b)
        })
        .sum();
    Ok(TextureInfo {
        colour_space: ColourSpace::from_format(format),
        width: w,
        height: ht,
        levels: full,
        uncompressed_length,
    })
}

/// Decodes a material-texture chunk: every level, checked (see the module doc).
pub fn decode_texture(bytes: &[u8]) -> Result<TextureImage> {
    let info = inspect_texture(bytes)?;
    let reader = ktx2::Reader::new(bytes).map_err(|e| PackError::ktx(format!("{e:?}")))?;
    let mut levels = Vec::with_capacity(info.levels as usize);
    for (l, level) in reader.levels().enumerate() {
        let (w, h) = mip_size(info.width, info.height, l as u32);
        let expected = 4 * u64::from(w) * u64::from(h);
        if level.uncompressed_byte_length != expected {
            return Err(PackError::ktx(format!(
                "level {l}: uncompressedByteLength {} but a {w} × {h} RGBA8 level has {expected}",
                level.uncompressed_byte_length
            )));
        }
        match zstd::zstd_safe::get_frame_content_size(level.data) {
            Ok(Some(n)) if n == expected => {}
            Ok(Some(n)) => {
                return Err(PackError::ktx(format!(
                    "level {l}: zstd frame declares {n} bytes, the level has {expected}"
                )));
            }
            _ => {
                return Err(PackError::ktx(format!(
                    "level {l}: zstd frame is truncated or does not declare its size"
                )));
            }
        }
        let texels = zstd_decompress_exact(level.data, expected as usize, PackError::ktx)?;
        levels.push(TextureLevel {
            width: w,
            height: h,
            texels,
        });
    }
    Ok(TextureImage {
        colour_space: info.colour_space,
        levels,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chain_sizes() {
        assert_eq!(mip_count(1, 1), 1);
        assert_eq!(mip_count(64, 64), 7);
        assert_eq!(mip_count(5, 3), 3);
        assert_eq!(mip_count(1, 8192), 14);
        assert_eq!(mip_size(5, 3, 1), (2, 1));
        assert_eq!(mip_size(5, 3, 2), (1, 1));
        assert_eq!(mip_size(5, 3, 40), (1, 1));
    }

    #[test]
    fn srgb_round_trips_every_byte() {
        for i in 0..=255u8 {
            let c = srgb_to_linear(i as f32 / 255.0);
            assert_eq!(to_u8(linear_to_srgb(c)), i);
        }
    }

    #[test]
    fn encode_decode_non_square() {
        let texels: Vec<u8> = (0..5 * 3 * 4).map(|i| (i * 7) as u8).collect();
        let t = TextureImage::with_mips(ColourSpace::Linear, 5, 3, texels).unwrap();
        assert_eq!(t.levels.len(), 3);
        let (bytes, len) = encode_texture(&t).unwrap();
        assert_eq!(len, 4 * (15 + 2 + 1));
        assert_eq!(decode_texture(&bytes).unwrap(), t);
        assert_eq!(inspect_texture(&bytes).unwrap().uncompressed_length, len);
    }
}
