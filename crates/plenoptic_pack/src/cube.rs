//! Cube-face addressing and the quantizers shared by cubes and volume blocks.
//!
//! # Cube convention
//!
//! Faces are stored in the KTX2/Vulkan order +X, −X, +Y, −Y, +Z, −Z (face index 0..6). Within a
//! face, `u` runs along texel columns (left → right) and `v` along rows (row 0 first in memory),
//! both in `[0, 1]`. The mapping between a direction `r` and `(face, u, v)` is Vulkan's cube
//! map face selection (Vulkan spec, "Cube Map Face Selection"; wgpu and WGSL `textureSample` on a
//! cube view use the same): with major axis `ma`,
//!
//! | face | sc | tc | ma |
//! |---|---|---|---|
//! | +X | −rz | −ry | rx |
//! | −X | +rz | −ry | rx |
//! | +Y | +rx | +rz | ry |
//! | −Y | +rx | −rz | ry |
//! | +Z | +rx | −ry | rz |
//! | −Z | −rx | −ry | rz |
//!
//! and `u = (sc/|ma| + 1)/2`, `v = (tc/|ma| + 1)/2`. Texel `(i, j)` of a face of size `n` has
//! its centre at `u = (i + ½)/n`, `v = (j + ½)/n` and index `face·n² + j·n + i`.

use glam::{Vec2, Vec3};

/// Maps a direction (need not be unit length, must be non-zero) to `(face, u, v)`.
/// A zero or non-finite direction maps to face 0 centre.
///
/// Inlined into callers in other crates: the reconstruction's per-pixel loops call it.
#[inline(always)]
pub fn direction_to_face_uv(dir: Vec3) -> (usize, f32, f32) {
    let a = dir.abs();
    let (face, sc, tc, ma) = if a.x >= a.y && a.x >= a.z {
        if dir.x >= 0.0 {
            (0, -dir.z, -dir.y, a.x)
        } else {
            (1, dir.z, -dir.y, a.x)
        }
    } else if a.y >= a.z {
        if dir.y >= 0.0 {
            (2, dir.x, dir.z, a.y)
        } else {
            (3, dir.x, -dir.z, a.y)
        }
    } else if dir.z >= 0.0 {
        (4, dir.x, -dir.y, a.z)
    } else {
        (5, -dir.x, -dir.y, a.z)
    };
    if !(ma > 0.0 && ma.is_finite()) {
        return (0, 0.5, 0.5);
    }
    (face, 0.5 * (sc / ma + 1.0), 0.5 * (tc / ma + 1.0))
}

/// Maps `(face, u, v)` to the unit direction through that point of the face. Faces ≥ 6 are
/// taken modulo 6.
pub fn face_uv_to_direction(face: usize, u: f32, v: f32) -> Vec3 {
    face_plane_direction(face % 6, u, v).normalize()
}

/// The direction through `(u, v)` on the plane of face `face` (at distance 1 from the
/// centre), not normalized; `u` and `v` may lie outside [0, 1], which reaches beyond the
/// face's edges (as seamless filtering does). Faces ≥ 5 are −Z.
#[inline]
pub fn face_plane_direction(face: usize, u: f32, v: f32) -> Vec3 {
    let sc = 2.0 * u - 1.0;
    let tc = 2.0 * v - 1.0;
    match face {
        0 => Vec3::new(1.0, -tc, -sc),
        1 => Vec3::new(-1.0, -tc, sc),
        2 => Vec3::new(sc, 1.0, tc),
        3 => Vec3::new(sc, -1.0, -tc),
        4 => Vec3::new(sc, -tc, 1.0),
        _ => Vec3::new(-sc, -tc, -1.0),
    }
}

/// Unit direction through the centre of texel `index` (as laid out in a cube of face size `n`).
pub fn texel_direction(face_size: u32, index: usize) -> Vec3 {
    let n = face_size.max(1) as usize;
    let face = index / (n * n);
    let rem = index % (n * n);
    let (j, i) = (rem / n, rem % n);
    face_uv_to_direction(
        face,
        (i as f32 + 0.5) / n as f32,
        (j as f32 + 0.5) / n as f32,
    )
}

/// Index of the texel of a cube of face size `n` that direction `dir` falls in.
///
/// Inlined into callers in other crates: the reconstruction's per-pixel loops call it.
#[inline(always)]
pub fn direction_to_texel(face_size: u32, dir: Vec3) -> usize {
    let n = face_size.max(1) as usize;
    let (face, u, v) = direction_to_face_uv(dir);
    let i = ((u * n as f32) as usize).min(n - 1);
    let j = ((v * n as f32) as usize).min(n - 1);
    face * n * n + j * n + i
}

/// Octahedral encoding of a unit vector into `[-1, 1]²` (Cigolle et al. 2014, "A Survey of
/// Efficient Representations for Independent Unit Vectors"). Non-finite or zero input maps to
/// `(0, 0)` (+Z).
pub fn oct_encode(n: Vec3) -> Vec2 {
    let l1 = n.x.abs() + n.y.abs() + n.z.abs();
    if !(l1 > 0.0 && l1.is_finite()) {
        return Vec2::ZERO;
    }
    let p = Vec2::new(n.x, n.y) / l1;
    if n.z < 0.0 {
        let s = Vec2::new(
            if p.x >= 0.0 { 1.0 } else { -1.0 },
            if p.y >= 0.0 { 1.0 } else { -1.0 },
        );
        (Vec2::ONE - Vec2::new(p.y.abs(), p.x.abs())) * s
    } else {
        p
    }
}

/// Inverse of [`oct_encode`]; returns a unit vector for any input in `[-1, 1]²`.
pub fn oct_decode(e: Vec2) -> Vec3 {
    let e = e.clamp(Vec2::splat(-1.0), Vec2::ONE);
    let mut v = Vec3::new(e.x, e.y, 1.0 - e.x.abs() - e.y.abs());
    if v.z < 0.0 {
        let x = (1.0 - v.y.abs()) * if v.x >= 0.0 { 1.0 } else { -1.0 };
        let y = (1.0 - v.x.abs()) * if v.y >= 0.0 { 1.0 } else { -1.0 };
        v.x = x;
        v.y = y;
    }
    v.normalize()
}

/// Quantizes `[-1, 1]` to a 16-bit signed normalized integer (Vulkan SNORM rule).
pub fn snorm16(x: f32) -> i16 {
    (x.clamp(-1.0, 1.0) * 32767.0).round() as i16
}

/// Unit `n` as one RG16Snorm word: [`oct_encode`]d, x in the low 16 bits (the normal cubes'
/// texel, as little-endian bytes; WGSL's `unpack2x16snorm` reads it back).
pub fn oct_snorm16_pack(n: Vec3) -> u32 {
    let e = oct_encode(n);
    u32::from(snorm16(e.x) as u16) | (u32::from(snorm16(e.y) as u16) << 16)
}

/// Inverse of [`snorm16`] (−32768 maps to −1 as Vulkan specifies).
pub fn from_snorm16(x: i16) -> f32 {
    (x as f32 / 32767.0).max(-1.0)
}

/// Quantizes `[0, 1]` to a 16-bit unsigned normalized integer.
pub fn unorm16(x: f32) -> u16 {
    if x.is_nan() {
        return 0;
    }
    (x.clamp(0.0, 1.0) * 65535.0).round() as u16
}

/// Inverse of [`unorm16`].
pub fn from_unorm16(x: u16) -> f32 {
    x as f32 / 65535.0
}

/// Unit vector as two 16-bit unorm octahedral coordinates (used in volume blocks).
pub fn oct_unorm16(n: Vec3) -> [u16; 2] {
    let e = oct_encode(n) * 0.5 + Vec2::splat(0.5);
    [unorm16(e.x), unorm16(e.y)]
}

/// Inverse of [`oct_unorm16`].
pub fn from_oct_unorm16(q: [u16; 2]) -> Vec3 {
    oct_decode(Vec2::new(from_unorm16(q[0]), from_unorm16(q[1])) * 2.0 - Vec2::ONE)
}

const RGB9E5_MANTISSA_BITS: i32 = 9;
const RGB9E5_EXP_BIAS: i32 = 15;
const RGB9E5_MAX_EXP: i32 = 31;
/// Largest value RGB9E5 represents: (2⁹−1)/2⁹ · 2¹⁶ = 65408.
pub const RGB9E5_MAX: f32 = 65408.0;

/// Packs linear RGB into `VK_FORMAT_E5B9G9R9_UFLOAT_PACK32` (R in bits 0..9, G 9..18, B 18..27,
/// shared exponent 27..32), following `EXT_texture_shared_exponent`. Negative and NaN channels
/// become 0; values above [`RGB9E5_MAX`] clamp. Each channel's error is at most
/// `max(r, g, b) · 2⁻⁹` (plus 2⁻²⁴ absolute for tiny values).
pub fn rgb9e5_pack(rgb: Vec3) -> u32 {
    let c = |x: f32| {
        if x.is_nan() {
            0.0
        } else {
            x.clamp(0.0, RGB9E5_MAX)
        }
    };
    let (r, g, b) = (c(rgb.x), c(rgb.y), c(rgb.z));
    let maxc = r.max(g).max(b);
    // floor(log2(maxc)) via the float's exponent bits, robust for subnormals.
    let floor_log2 = if maxc > 0.0 {
        maxc.log2().floor() as i32
    } else {
        -RGB9E5_EXP_BIAS - 1
    };
    let mut exp = (floor_log2.max(-RGB9E5_EXP_BIAS - 1)) + 1 + RGB9E5_EXP_BIAS;
    let denom = |e: i32| 2f32.powi(e - RGB9E5_EXP_BIAS - RGB9E5_MANTISSA_BITS);
    let maxm = (maxc / denom(exp) + 0.5).floor() as i32;
    if maxm == 1 << RGB9E5_MANTISSA_BITS {
        exp += 1;
    }
    let exp = exp.clamp(0, RGB9E5_MAX_EXP);
    let d = denom(exp);
    let q = |x: f32| ((x / d + 0.5).floor() as u32).min(511);
    q(r) | (q(g) << 9) | (q(b) << 18) | ((exp as u32) << 27)
}

/// Unpacks `VK_FORMAT_E5B9G9R9_UFLOAT_PACK32`.
pub fn rgb9e5_unpack(v: u32) -> Vec3 {
    let exp = (v >> 27) as i32;
    let scale = 2f32.powi(exp - RGB9E5_EXP_BIAS - RGB9E5_MANTISSA_BITS);
    Vec3::new(
        (v & 511) as f32 * scale,
        ((v >> 9) & 511) as f32 * scale,
        ((v >> 18) & 511) as f32 * scale,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn face_uv_round_trip() {
        for face in 0..6 {
            for &(u, v) in &[(0.1, 0.2), (0.5, 0.5), (0.9, 0.3), (0.7, 0.95)] {
                let d = face_uv_to_direction(face, u, v);
                let (f2, u2, v2) = direction_to_face_uv(d);
                assert_eq!(f2, face);
                assert!((u - u2).abs() < 1e-5 && (v - v2).abs() < 1e-5);
            }
        }
        // Face centres are the axes in KTX2 order.
        let axes = [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
        for (f, a) in axes.iter().enumerate() {
            assert!(face_uv_to_direction(f, 0.5, 0.5).abs_diff_eq(*a, 1e-6));
        }
        // Vulkan: on +X, u grows towards -Z and v towards -Y.
        assert!(face_uv_to_direction(0, 1.0, 0.5).z < 0.0);
        assert!(face_uv_to_direction(0, 0.5, 1.0).y < 0.0);
        // On +Y, v grows towards +Z.
        assert!(face_uv_to_direction(2, 0.5, 1.0).z > 0.0);
    }

    #[test]
    fn texel_direction_round_trip() {
        let n = 7;
        for i in 0..6 * n * n {
            assert_eq!(
                direction_to_texel(n as u32, texel_direction(n as u32, i)),
                i
            );
        }
    }

    #[test]
    fn rgb9e5_known_values() {
        assert_eq!(rgb9e5_unpack(rgb9e5_pack(Vec3::ONE)), Vec3::ONE);
        assert_eq!(rgb9e5_unpack(rgb9e5_pack(Vec3::ZERO)), Vec3::ZERO);
        let big = rgb9e5_unpack(rgb9e5_pack(Vec3::splat(1e9)));
        assert_eq!(big, Vec3::splat(RGB9E5_MAX));
        assert_eq!(
            rgb9e5_unpack(rgb9e5_pack(Vec3::new(-1.0, f32::NAN, 2.0))).x,
            0.0
        );
    }
}
