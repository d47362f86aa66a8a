//! Seamless bilinear cube lookups for the per-pixel loops, in the pack's cube convention
//! ([`plenoptic_pack::cube`]: KTX2/Vulkan face order and face selection).
//!
//! [`bilinear_taps`] is the seamless bilinear filter: the four texels around a direction and
//! their weights, where a tap that falls off the face is taken from the neighbouring face
//! (the texel its direction, on the face's extended plane, falls in), as seamless cube map
//! filtering does on GPUs. At a cube corner only three faces meet: the missing tap is left out
//! and the others renormalized.

use glam::Vec3;
use plenoptic_pack::CubeImage;
use plenoptic_pack::cube::{direction_to_face_uv, direction_to_texel, face_plane_direction};

/// The four texels of a cube of face size `n` around direction `dir` and their bilinear
/// weights (summing to 1), seamless across faces (module docs).
pub(crate) fn bilinear_taps(face_size: u32, dir: Vec3) -> [(usize, f32); 4] {
    let n = face_size.max(1) as i64;
    let nf = n as f32;
    let (face, u, v) = direction_to_face_uv(dir);
    let (s, t) = (u * nf - 0.5, v * nf - 0.5);
    let (i0, j0) = (s.floor(), t.floor());
    let (fx, fy) = (s - i0, t - j0);
    let (i0, j0) = (i0 as i64, j0 as i64);
    let mut taps = [(0usize, 0.0f32); 4];
    let mut total = 0.0;
    for (k, (di, dj, w)) in [
        (0, 0, (1.0 - fx) * (1.0 - fy)),
        (1, 0, fx * (1.0 - fy)),
        (0, 1, (1.0 - fx) * fy),
        (1, 1, fx * fy),
    ]
    .into_iter()
    .enumerate()
    {
        let (i, j) = (i0 + di, j0 + dj);
        let (in_i, in_j) = ((0..n).contains(&i), (0..n).contains(&j));
        let index = if in_i && in_j {
            face * (n * n) as usize + (j * n + i) as usize
        } else if in_i || in_j {
            // Off one edge: the neighbouring face's texel in the tap's direction.
            let d = face_plane_direction(face, (i as f32 + 0.5) / nf, (j as f32 + 0.5) / nf);
            direction_to_texel(face_size, d)
        } else {
            continue; // a cube corner: no fourth texel
        };
        taps[k] = (index, w);
        total += w;
    }
    if total > 0.0 {
        for t in &mut taps {
            t.1 /= total;
        }
    } else {
        taps = [
            (direction_to_texel(face_size, dir), 1.0),
            (0, 0.0),
            (0, 0.0),
            (0, 0.0),
        ];
    }
    taps
}

/// Seamless bilinear lookup of a radiance cube in direction `dir`.
pub(crate) fn bilinear(cube: &CubeImage<Vec3>, dir: Vec3) -> Vec3 {
    let mut c = Vec3::ZERO;
    for (i, w) in bilinear_taps(cube.face_size, dir) {
        if w > 0.0 {
            c += cube.texels.get(i).copied().unwrap_or(Vec3::ZERO) * w;
        }
    }
    c
}

#[cfg(test)]
mod tests {
    use super::*;
    use plenoptic_pack::cube;

    /// The smooth function of direction the test cubes hold.
    fn smooth(d: Vec3) -> Vec3 {
        let d = d.normalize();
        Vec3::new(1.0 + d.x, 2.0 + d.y * d.z, 1.5 + 0.5 * d.z)
    }

    #[test]
    fn bilinear_interpolates_texel_centres_and_weights_sum_to_one() {
        let n = 8;
        let c = CubeImage::from_fn(n, |_, d| smooth(d));
        for idx in [0, 9, 27, 100, 6 * 64 - 1] {
            let d = cube::texel_direction(n, idx);
            assert!(bilinear(&c, d).abs_diff_eq(c.texels[idx], 1e-5), "{idx}");
        }
        for d in [
            Vec3::new(0.3, -0.2, 0.9),
            Vec3::new(1.0, 1.0, 1.0),
            Vec3::new(-1.0, 0.999, 0.2),
        ] {
            let s: f32 = bilinear_taps(n, d).iter().map(|t| t.1).sum();
            assert!((s - 1.0).abs() < 1e-5, "{d}: {s}");
        }
    }

    #[test]
    fn bilinear_is_seamless_across_faces() {
        let n = 8;
        let c = CubeImage::from_fn(n, |_, d| smooth(d));
        // On the edge between +X (face 0, column 0) and +Z (face 4, column n − 1), at the
        // height of texel row 3: half the edge texel of each face.
        let v = (3.0 + 0.5) / n as f32;
        let seam = Vec3::new(1.0, -(2.0 * v - 1.0), 1.0);
        let plus_x = c.texels[n as usize * 3];
        let plus_z = c.texels[4 * 64 + n as usize * 3 + n as usize - 1];
        let got = bilinear(&c, seam);
        assert!(
            got.abs_diff_eq(0.5 * (plus_x + plus_z), 1e-5),
            "{got} {plus_x} {plus_z}"
        );
        // Approaching the seam from either face gives the same value, close to the function
        // (a lookup clamped at the face edge would give the edge texel of one face only).
        let a = bilinear(&c, seam + Vec3::new(0.0, 0.0, -1e-4));
        let b = bilinear(&c, seam + Vec3::new(-1e-4, 0.0, 0.0));
        assert!(a.abs_diff_eq(b, 1e-3), "{a} {b}");
        assert!(
            got.abs_diff_eq(smooth(seam), 0.02),
            "{got} {}",
            smooth(seam)
        );
        // Along a circle through four faces and their seams: no jumps, close to the function.
        let mut last = bilinear(&c, Vec3::new(1.0, 0.31, 0.0));
        for k in 1..=2000 {
            let a = k as f32 / 2000.0 * std::f32::consts::TAU;
            let d = Vec3::new(a.cos(), 0.31, a.sin());
            let v = bilinear(&c, d);
            assert!(v.abs_diff_eq(last, 0.01), "jump at {d}: {last} → {v}");
            assert!(v.abs_diff_eq(smooth(d), 0.03), "{d}: {v} vs {}", smooth(d));
            last = v;
        }
        // A cube corner: three faces meet, the weights still sum to one.
        let s: f32 = bilinear_taps(n, Vec3::ONE).iter().map(|t| t.1).sum();
        assert!((s - 1.0).abs() < 1e-5);
        assert!(bilinear(&c, Vec3::ONE).abs_diff_eq(smooth(Vec3::ONE), 0.05));
    }
}
