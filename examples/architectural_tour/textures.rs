//! The tour's material textures, made in code (deterministic: the same code writes the same
//! bytes) and embedded in `tour.glb`: oak planks, atrium floor tiles, plaster with fine
//! variation, stone slabs, bench fabric, brushed steel and brick.
//!
//! Each texture covers [`Texture::metres`] of surface per repeat; the scene's meshes carry
//! UVs in metres (box-mapped, see `scene.rs`), and the material's `KHR_texture_transform`
//! scales them by 1 / metres. Colours are sRGB-encoded RGBA8, as glTF stores base colour.

use glam::Vec3;

/// A generated texture: RGBA8 texels (sRGB) and the surface size one repeat covers.
pub struct Texture {
    /// Width and height, texels.
    pub size: u32,
    /// `4·size²` bytes.
    pub rgba8: Vec<u8>,
    /// Metres of surface per repeat.
    pub metres: f32,
}

/// A small deterministic hash of integer coordinates to [0, 1).
fn hash(x: i32, y: i32, seed: u32) -> f32 {
    let mut h = (x as u32).wrapping_mul(0x8da6_b343)
        ^ (y as u32).wrapping_mul(0xd816_3841)
        ^ seed.wrapping_mul(0xcb1a_b31f);
    h ^= h >> 13;
    h = h.wrapping_mul(0x5bd1_e995);
    h ^= h >> 15;
    (h & 0x00ff_ffff) as f32 / 16_777_216.0
}

/// Smooth value noise with period `period` texels (tileable over `size`).
fn noise(x: f32, y: f32, period: u32, size: u32, seed: u32) -> f32 {
    let cells = (size / period.max(1)).max(1) as i32;
    let (fx, fy) = (x / period as f32, y / period as f32);
    let (x0, y0) = (fx.floor() as i32, fy.floor() as i32);
    let (tx, ty) = (fx - x0 as f32, fy - y0 as f32);
    let s = |t: f32| t * t * (3.0 - 2.0 * t);
    let at = |i: i32, j: i32| hash(i.rem_euclid(cells), j.rem_euclid(cells), seed);
    let a = at(x0, y0) + (at(x0 + 1, y0) - at(x0, y0)) * s(tx);
    let b = at(x0, y0 + 1) + (at(x0 + 1, y0 + 1) - at(x0, y0 + 1)) * s(tx);
    a + (b - a) * s(ty)
}

/// Noise summed over octaves of periods `size / 2`, `size / 4`, … down to `finest`.
fn fractal(x: f32, y: f32, size: u32, finest: u32, seed: u32) -> f32 {
    let (mut sum, mut weight, mut amp) = (0.0, 0.0, 1.0);
    let mut period = size / 2;
    let mut k = 0;
    while period >= finest.max(1) {
        sum += amp * noise(x, y, period, size, seed + k);
        weight += amp;
        amp *= 0.55;
        period /= 2;
        k += 1;
    }
    sum / weight
}

fn to_srgb8(c: f32) -> u8 {
    (plenoptic_pack::texture::linear_to_srgb(c) * 255.0).round() as u8
}

/// A texture of `size`² texels whose linear colour at texel (x, y) is `f(x, y)`.
fn make(size: u32, metres: f32, f: impl Fn(u32, u32) -> Vec3) -> Texture {
    let mut rgba8 = Vec::with_capacity((4 * size * size) as usize);
    for y in 0..size {
        for x in 0..size {
            let c = f(x, y).clamp(Vec3::ZERO, Vec3::ONE);
            rgba8.extend_from_slice(&[to_srgb8(c.x), to_srgb8(c.y), to_srgb8(c.z), 255]);
        }
    }
    Texture {
        size,
        rgba8,
        metres,
    }
}

/// Oak planks 12.5 cm wide with staggered joints and grain along their length (x), 1 m per
/// repeat. `tint` is the mean colour.
pub fn oak_planks(tint: Vec3) -> Texture {
    let n = 256;
    make(n, 1.0, |x, y| {
        let plank = y / 32;
        // Joints every 1 m, staggered by a third per plank.
        let offset = (plank * 85) % n;
        let along = (x + offset) % n;
        let joint = along < 2 || y % 32 < 1;
        let shade = 0.8 + 0.4 * hash(plank as i32, ((x + offset) / n) as i32, 7);
        let grain = 0.85
            + 0.3 * noise(x as f32 * 0.25, y as f32 * 4.0, 8, n, 11 + plank)
            + 0.1 * (y as f32 * 1.7 + 6.0 * noise(x as f32, y as f32, 32, n, 3)).sin();
        let c = tint * shade * grain;
        if joint { c * 0.45 } else { c }
    })
}

/// Square floor tiles 25 cm across with 1 cm grout, each tile its own shade, 1 m per repeat.
pub fn floor_tiles(tint: Vec3) -> Texture {
    let n = 256;
    make(n, 1.0, |x, y| {
        let (tx, ty) = (x / 64, y / 64);
        let grout = x % 64 < 3 || y % 64 < 3;
        if grout {
            return Vec3::splat(0.55);
        }
        let shade = 0.85 + 0.3 * hash(tx as i32, ty as i32, 21);
        let speckle = 0.95 + 0.1 * fractal(x as f32, y as f32, n, 2, 23);
        tint * shade * speckle
    })
}

/// Plaster: fine, low-contrast variation, 0.5 m per repeat.
pub fn plaster(tint: Vec3) -> Texture {
    let n = 128;
    make(n, 0.5, |x, y| {
        tint * (0.92 + 0.16 * fractal(x as f32, y as f32, n, 2, 31))
    })
}

/// Stone slabs 50 cm square with thin joints and cloudy variation, 1 m per repeat.
pub fn stone_slabs(tint: Vec3) -> Texture {
    let n = 256;
    make(n, 1.0, |x, y| {
        if x % 128 < 2 || y % 128 < 2 {
            return tint * 0.6;
        }
        let slab = hash((x / 128) as i32, (y / 128) as i32, 41);
        tint * (0.85 + 0.15 * slab) * (0.85 + 0.3 * fractal(x as f32, y as f32, n, 4, 43))
    })
}

/// Woven fabric: a basket weave of 2.5 mm threads, 5 cm per repeat.
pub fn fabric(tint: Vec3) -> Texture {
    let n = 64;
    make(n, 0.05, |x, y| {
        let over = ((x / 4) + (y / 4)) % 2 == 0;
        let thread = if over { (x % 4) as f32 } else { (y % 4) as f32 };
        let shade = 0.75 + 0.12 * thread + 0.1 * hash(x as i32, y as i32, 51);
        tint * shade
    })
}

/// Brushed steel: fine streaks along x, 0.5 m per repeat.
pub fn brushed_steel(tint: Vec3) -> Texture {
    let n = 128;
    make(n, 0.5, |x, y| {
        let streak = noise(x as f32 * 0.05, y as f32 * 2.0, 4, n, 61);
        tint * (0.88 + 0.2 * streak)
    })
}

/// Brick in running bond: bricks 25 × 6.25 cm with 1 cm mortar, 1 m per repeat.
pub fn brick(tint: Vec3) -> Texture {
    let n = 256;
    make(n, 1.0, |x, y| {
        let course = y / 16;
        let shift = if course % 2 == 0 { 0 } else { 32 };
        let col = (x + shift) % n / 64;
        let mortar = y % 16 < 2 || (x + shift) % 64 < 2;
        if mortar {
            return Vec3::splat(0.62);
        }
        let shade = 0.75 + 0.45 * hash(col as i32, course as i32, 71);
        tint * shade * (0.9 + 0.2 * fractal(x as f32, y as f32, n, 2, 73))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn textures_have_their_size_and_mean_near_the_tint() {
        let tint = Vec3::new(0.5, 0.4, 0.3);
        for t in [
            oak_planks(tint),
            floor_tiles(tint),
            plaster(tint),
            stone_slabs(tint),
            fabric(tint),
            brushed_steel(tint),
            brick(tint),
        ] {
            assert_eq!(t.rgba8.len(), (4 * t.size * t.size) as usize);
            let mean: f32 = t
                .rgba8
                .chunks_exact(4)
                .map(|p| plenoptic_pack::texture::srgb_to_linear(p[0] as f32 / 255.0))
                .sum::<f32>()
                / (t.size * t.size) as f32;
            assert!(mean > 0.2 && mean < 0.8, "{mean}");
        }
    }
}
