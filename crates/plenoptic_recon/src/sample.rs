//! Cube lookups for the per-pixel loops, in the pack's cube convention
//! ([`plenoptic_pack::cube`]: KTX2/Vulkan face order and face selection).
//!
//! [`face_uv`] and [`texel`] compute exactly what `cube::direction_to_face_uv` and
//! `cube::direction_to_texel` compute, but inline into the callers' loops (the pack's functions
//! are not inlined across crates).

use glam::Vec3;

/// `(face, u, v)` of a direction; the same arithmetic as `cube::direction_to_face_uv` (a zero or
/// non-finite direction maps to face 0 centre).
#[inline(always)]
pub(crate) fn face_uv(dir: Vec3) -> (usize, f32, f32) {
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

/// Index of the texel of a cube of face size `n` that `dir` falls in; equals
/// `cube::direction_to_texel(n, dir)`.
#[inline(always)]
pub(crate) fn texel(face_size: u32, dir: Vec3) -> usize {
    let n = face_size.max(1) as usize;
    let (face, u, v) = face_uv(dir);
    let i = ((u * n as f32) as usize).min(n - 1);
    let j = ((v * n as f32) as usize).min(n - 1);
    face * n * n + j * n + i
}

#[cfg(test)]
mod tests {
    use super::*;
    use plenoptic_pack::cube;

    #[test]
    fn texel_agrees_with_the_reference() {
        let mut s = 12345u32;
        let mut rnd = || {
            s ^= s << 13;
            s ^= s >> 17;
            s ^= s << 5;
            s as f32 / u32::MAX as f32 * 2.0 - 1.0
        };
        for _ in 0..20000 {
            let d = Vec3::new(rnd(), rnd(), rnd());
            for n in [1, 16, 128] {
                assert_eq!(texel(n, d), cube::direction_to_texel(n, d), "{d}");
            }
            assert_eq!(face_uv(d), cube::direction_to_face_uv(d));
        }
        assert_eq!(
            texel(8, Vec3::ZERO),
            cube::direction_to_texel(8, Vec3::ZERO)
        );
    }
}
