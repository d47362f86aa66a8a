//! Textures sampled on the CPU (docs/architecture.md, "Pack v2": the albedo at the pixel's
//! UV, its mip chosen by the pixel's footprint): trilinear filtering through a binding's
//! `KHR_texture_transform` and wrap modes, as a GPU's sampler filters.
//!
//! A texture is decoded once, when first used, into [`LinearTexture`]: linear RGBA at 16 bits
//! per channel, sRGB colour decoded through a table. Filtering is then four 8-byte loads per
//! level, where sampling the pack's sRGB bytes directly would cost three dependent table loads
//! per texel at every sample. The sampler's cost is part of every textured frame's (`cargo
//! bench --no-default-features --bench recon -- geometry_textured`). 16 bits keep the decoded
//! value within 8·10⁻⁶ of the exact one, below the darkest sRGB step (3·10⁻⁴); the texels take
//! twice the pack's 8-bit size in memory.

use std::sync::OnceLock;

use glam::{Vec2, Vec4};
use plenoptic_pack::{ColourSpace, TextureBinding, TextureImage, UvTransform, WrapMode};

/// The decoded value of 1.0.
const UNIT: u16 = u16::MAX;

/// A texture's mip chain decoded to linear RGBA at 16 bits per channel ([`UNIT`] = 1).
pub(crate) struct LinearTexture {
    /// Level 0 (full resolution) to the 1×1 level.
    pub levels: Vec<LinearLevel>,
}

/// One mip level of a [`LinearTexture`], rows top to bottom.
pub(crate) struct LinearLevel {
    pub width: u32,
    pub height: u32,
    pub texels: Vec<[u16; 4]>,
}

/// Byte → 16-bit linear value: the sRGB transfer function's inverse for colour in sRGB, a
/// plain rescale for linear channels and alpha.
fn tables() -> &'static ([u16; 256], [u16; 256]) {
    static TABLES: OnceLock<([u16; 256], [u16; 256])> = OnceLock::new();
    TABLES.get_or_init(|| {
        let srgb = std::array::from_fn(|i| {
            let l = plenoptic_pack::texture::srgb_to_linear(i as f32 / 255.0);
            (l.clamp(0.0, 1.0) * UNIT as f32).round() as u16
        });
        (srgb, std::array::from_fn(|i| i as u16 * 257))
    })
}

impl LinearTexture {
    /// `texture` decoded; a level whose texels are fewer than its size says is left empty
    /// (sampling it gives white, as a texture that cannot be read).
    pub fn decode(texture: &TextureImage) -> Self {
        let (srgb, linear) = tables();
        let colour = if texture.colour_space == ColourSpace::Srgb {
            srgb
        } else {
            linear
        };
        let levels = texture
            .levels
            .iter()
            .map(|l| {
                let n = l.width as usize * l.height as usize;
                let texels = if l.texels.len() < 4 * n {
                    Vec::new()
                } else {
                    l.texels[..4 * n]
                        .chunks_exact(4)
                        .map(|p| {
                            let c = |i: usize| colour[p[i] as usize];
                            [c(0), c(1), c(2), linear[p[3] as usize]]
                        })
                        .collect()
                };
                LinearLevel {
                    width: l.width,
                    height: l.height,
                    texels,
                }
            })
            .collect();
        LinearTexture { levels }
    }
}

/// `KHR_texture_transform` applied to `uv`.
#[inline]
fn transform(t: &UvTransform, uv: Vec2) -> Vec2 {
    let s = uv * t.scale;
    if t.rotation == 0.0 {
        return t.offset + s;
    }
    let (sin, cos) = t.rotation.sin_cos();
    t.offset + Vec2::new(cos * s.x + sin * s.y, -sin * s.x + cos * s.y)
}

/// Wraps texel coordinate `i` of a side of `n` texels.
#[inline]
fn wrap(i: i64, n: i64, mode: WrapMode) -> usize {
    let n = n.max(1);
    if (0..n).contains(&i) {
        return i as usize;
    }
    (match mode {
        // One period off (the texel beside an edge of a reduced coordinate): no division.
        WrapMode::Repeat if (-n..0).contains(&i) => i + n,
        WrapMode::Repeat if (n..2 * n).contains(&i) => i - n,
        WrapMode::Repeat => i.rem_euclid(n),
        WrapMode::ClampToEdge => i.clamp(0, n - 1),
        WrapMode::MirroredRepeat => {
            let p = i.rem_euclid(2 * n);
            if p < n { p } else { 2 * n - 1 - p }
        }
    }) as usize
}

/// Trilinear sample of `texture` through binding `b` at `uv`, linear RGBA. `footprint` is
/// the pixel's size in UV units; the level is `log₂(footprint · size)` (the transform's scale
/// included).
pub(crate) fn sample(texture: &LinearTexture, b: TextureBinding, uv: Vec2, footprint: f32) -> Vec4 {
    let Some(top) = texture.levels.first() else {
        return Vec4::ONE;
    };
    let (uv, scale) = match &b.transform {
        Some(t) => (transform(t, uv), t.scale.abs().max_element()),
        None => (uv, 1.0),
    };
    let texels = footprint * scale * top.width.max(top.height) as f32;
    let lod = if texels > 1.0 { log2(texels) } else { 0.0 };
    let last = texture.levels.len() - 1;
    let l0 = (floor(lod) as usize).min(last);
    let l1 = (l0 + 1).min(last);
    let f = (lod - l0 as f32).clamp(0.0, 1.0);
    let a = bilinear(texture, l0, b, uv);
    // Below one 8-bit step of the blend the second level cannot change the result.
    if l1 == l0 || f < 1.0 / 512.0 {
        return a;
    }
    a.lerp(bilinear(texture, l1, b, uv), f)
}

/// `x.log2()` within 2·10⁻⁵ for finite x ≥ 1 (∞ stays ∞): the exponent, and the mantissa
/// m ∈ [1, 2) through log₂ m = (2/ln 2)·atanh((m − 1)/(m + 1)) to its t⁷ term. A level of
/// detail needs far less, and libm's `log2f` costs a few per cent of a materials frame.
#[inline]
fn log2(x: f32) -> f32 {
    if !x.is_finite() {
        return x;
    }
    let bits = x.to_bits();
    let exponent = ((bits >> 23) & 0xff) as i32 - 127;
    let m = f32::from_bits((bits & 0x007f_ffff) | 0x3f80_0000);
    let t = (m - 1.0) / (m + 1.0);
    let t2 = t * t;
    let series = t * (1.0 + t2 * (1.0 / 3.0 + t2 * (1.0 / 5.0 + t2 * (1.0 / 7.0))));
    exponent as f32 + series * (2.0 / std::f32::consts::LN_2)
}

/// `x.floor()` without a call into libm (the baseline x86-64 target has no rounding
/// instruction, and the texture lookups are hot): exact for every finite `x`.
#[inline]
fn floor(x: f32) -> f32 {
    // From 2²³ up every f32 is an integer.
    if x.abs() >= 8_388_608.0 {
        return x;
    }
    let t = x as i32 as f32;
    if t > x { t - 1.0 } else { t }
}

/// `uv` reduced to [0, 1) where the wrap mode repeats (the same texels, without an integer
/// division per texel to wrap them).
#[inline]
fn reduce(uv: f32, mode: WrapMode) -> f32 {
    if mode == WrapMode::Repeat && !(0.0..1.0).contains(&uv) {
        uv - floor(uv)
    } else {
        uv
    }
}

fn bilinear(texture: &LinearTexture, level: usize, b: TextureBinding, uv: Vec2) -> Vec4 {
    let l = &texture.levels[level];
    let (w, h) = (l.width as i64, l.height as i64);
    let x = reduce(uv.x, b.wrap_s) * w as f32 - 0.5;
    let y = reduce(uv.y, b.wrap_t) * h as f32 - 0.5;
    if !(x.is_finite() && y.is_finite()) || l.texels.len() < (w * h) as usize {
        return Vec4::ONE;
    }
    let (x0, y0) = (floor(x), floor(y));
    let (fx, fy) = (x - x0, y - y0);
    let (x0, y0) = (x0 as i64, y0 as i64);
    // The two columns and rows of the footprint, wrapped once each.
    let (i0, i1) = (wrap(x0, w, b.wrap_s), wrap(x0 + 1, w, b.wrap_s));
    let (j0, j1) = (wrap(y0, h, b.wrap_t), wrap(y0 + 1, h, b.wrap_t));
    let (r0, r1) = (j0 * w as usize, j1 * w as usize);
    let texel = |k: usize| {
        let p = l.texels[k];
        Vec4::new(p[0] as f32, p[1] as f32, p[2] as f32, p[3] as f32)
    };
    let top = texel(r0 + i0).lerp(texel(r0 + i1), fx);
    let bottom = texel(r1 + i0).lerp(texel(r1 + i1), fx);
    top.lerp(bottom, fy) * (1.0 / UNIT as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 4×4 linear texture: a black and white checker of 2×2 blocks.
    fn checker() -> LinearTexture {
        let mut texels = Vec::new();
        for j in 0..4 {
            for i in 0..4 {
                let v = if (i / 2 + j / 2) % 2 == 0 { 255 } else { 0 };
                texels.extend_from_slice(&[v, v, v, 255]);
            }
        }
        LinearTexture::decode(&TextureImage::with_mips(ColourSpace::Linear, 4, 4, texels).unwrap())
    }

    #[test]
    fn the_fast_log2_agrees_with_libm() {
        let mut x = 1.0f32;
        while x < 1e6 {
            assert!(
                (log2(x) - x.log2()).abs() < 2e-5,
                "{x}: {} {}",
                log2(x),
                x.log2()
            );
            x *= 1.0137;
        }
        assert_eq!(log2(f32::INFINITY), f32::INFINITY);
        assert_eq!(log2(1.0), 0.0);
        assert_eq!(log2(1024.0), 10.0);
    }

    fn binding() -> TextureBinding {
        TextureBinding {
            texture: 0,
            wrap_s: WrapMode::Repeat,
            wrap_t: WrapMode::Repeat,
            transform: None,
        }
    }

    #[test]
    fn texel_centres_are_exact_and_far_pixels_average_the_checker() {
        let t = checker();
        let at = |u: f32, v: f32, fp: f32| sample(&t, binding(), Vec2::new(u, v), fp).x;
        assert!((at(0.125, 0.125, 0.0) - 1.0).abs() < 1e-6);
        assert!(at(0.625, 0.125, 0.0).abs() < 1e-6);
        // A pixel covering the whole texture reads the 1×1 level: the mean (to 8 bits).
        assert!((at(0.3, 0.7, 1.0) - 0.5).abs() < 3e-3);
        // Repeat wraps; the transform's scale tiles.
        assert!((at(1.125, -0.875, 0.0) - 1.0).abs() < 1e-6);
        let scaled = TextureBinding {
            transform: Some(UvTransform {
                offset: Vec2::ZERO,
                rotation: 0.0,
                scale: Vec2::splat(2.0),
            }),
            ..binding()
        };
        assert!(sample(&t, scaled, Vec2::new(0.3125, 0.0625), 0.0).x.abs() < 1e-6);
    }

    #[test]
    fn floor_is_libm_floor() {
        for x in [
            0.0f32,
            -0.0,
            0.5,
            -0.5,
            1.0,
            -1.0,
            2.999_999_8,
            -2.999_999_8,
            1e-30,
            -1e-30,
            8_388_607.5,
            -8_388_607.5,
            3e9,
            -3e9,
            123.0,
            -123.0,
        ] {
            assert_eq!(floor(x), x.floor(), "{x}");
        }
        // Repeating coordinates reduce to the same texel coordinates as wrapping them.
        for u in [-3.25f32, -1.0, -0.001, 0.0, 0.4, 1.0, 7.75] {
            let r = reduce(u, WrapMode::Repeat);
            assert!(
                (0.0..1.0).contains(&r) && (r - u - (r - u).round()).abs() < 1e-6,
                "{u}"
            );
            assert_eq!(reduce(u, WrapMode::ClampToEdge), u);
        }
    }

    #[test]
    fn wrap_modes() {
        assert_eq!(wrap(-1, 4, WrapMode::Repeat), 3);
        assert_eq!(wrap(-1, 4, WrapMode::ClampToEdge), 0);
        assert_eq!(wrap(5, 4, WrapMode::ClampToEdge), 3);
        assert_eq!(wrap(4, 4, WrapMode::MirroredRepeat), 3);
        assert_eq!(wrap(-1, 4, WrapMode::MirroredRepeat), 0);
    }

    #[test]
    fn srgb_texels_decode_within_a_16_bit_step() {
        let texels: Vec<u8> = (0..=255u8).flat_map(|v| [v, v, v, v]).collect();
        let t = TextureImage {
            colour_space: ColourSpace::Srgb,
            levels: vec![plenoptic_pack::texture::TextureLevel {
                width: 256,
                height: 1,
                texels,
            }],
        };
        let d = LinearTexture::decode(&t);
        for (v, p) in d.levels[0].texels.iter().enumerate() {
            let exact = plenoptic_pack::texture::srgb_to_linear(v as f32 / 255.0);
            assert!(
                (p[0] as f32 / UNIT as f32 - exact).abs() <= 0.51 / UNIT as f32,
                "{v}"
            );
            // Alpha is linear.
            assert_eq!(p[3], v as u16 * 257);
        }
    }

    #[test]
    fn a_short_level_samples_as_white() {
        let mut t = TextureImage::with_mips(ColourSpace::Linear, 4, 4, vec![0; 64]).unwrap();
        t.levels[0].texels.truncate(60);
        let d = LinearTexture::decode(&t);
        assert!(d.levels[0].texels.is_empty());
        assert_eq!(sample(&d, binding(), Vec2::splat(0.5), 0.0), Vec4::ONE);
    }
}
