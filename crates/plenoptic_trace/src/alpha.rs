//! Alpha testing during traversal: glTF `alphaMode` MASK and BLEND.
//!
//! A surface's alpha is the base colour factor's alpha × the base colour texture's alpha
//! (with the reference's transform and wrap modes) × the `COLOR_0` alpha, at the hit.
//!
//! - MASK: the surface exists where alpha ≥ `alphaCutoff`; elsewhere rays pass through.
//! - BLEND is *coverage*, as in Cycles: a ray meets the surface with probability alpha and
//!   passes through with probability 1 − alpha, so an alpha-0.12 window lets 88 % of sun and
//!   sky in. The decision is a hash of the world ray (origin and direction bits), the object
//!   id and the triangle index ([`coverage_sample`]): the same ray always makes the same
//!   decision, so images do not depend on threads or on the order of traversal, and the bake
//!   stays reproducible. Different rays (each pixel sample starts elsewhere or goes
//!   elsewhere) decide independently. What this does not give: two identical rays — the same
//!   shadow ray repeated from one point to a point light — share their decision, so repeating
//!   them does not reduce the pane's noise; renderers jitter their rays anyway.
//!
//! The test is an any-hit filter inside the BVH traversal (`accel`): a rejected candidate is
//! reported as no hit and traversal carries on past it, each primitive visited at most once,
//! so there is no re-launch loop. Objects whose alpha can never fall below their threshold
//! (no texture alpha, no vertex colours, factor ≥ cutoff) are traced as opaque at no cost.

use glam::{Vec2, Vec3};
use plenoptic_scene::{AlphaMode, Material, Mesh, ObjectId, Scene};

use crate::sampling::mix64;
use crate::texture::{mesh_color, mesh_uv, sample_ref};

/// How the traversal treats an object's hits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum AlphaTest {
    /// Every hit counts.
    Opaque,
    /// Hits with alpha below the cutoff are skipped.
    Mask(f32),
    /// Hits count with probability alpha.
    Blend,
}

impl AlphaTest {
    /// The test of every object of `scene`, by object id.
    pub(crate) fn per_object(scene: &Scene) -> Vec<Self> {
        let mut min_texture_alpha: Vec<Option<f32>> = vec![None; scene.textures.len()];
        scene
            .objects
            .iter()
            .map(|object| {
                let (Some(material), Some(mesh)) = (
                    scene.materials.get(object.material),
                    scene.meshes.get(object.mesh),
                ) else {
                    return Self::Opaque;
                };
                let threshold = match material.alpha_mode {
                    AlphaMode::Opaque => return Self::Opaque,
                    AlphaMode::Mask { cutoff } => cutoff,
                    AlphaMode::Blend => 1.0,
                };
                // The smallest alpha the surface can have: bilinear filtering and vertex
                // interpolation stay within the extremes of the texels and vertices.
                let mut lowest = material.base_color.w;
                if let Some(r) = material.base_color_texture
                    && let Some(t) = scene.textures.get(r.texture)
                {
                    let m = *min_texture_alpha[r.texture].get_or_insert_with(|| {
                        t.texels.iter().map(|c| c.w).fold(f32::INFINITY, f32::min)
                    });
                    lowest *= m.min(1.0);
                }
                if mesh.colors.len() == mesh.positions.len() {
                    lowest *= mesh.colors.iter().map(|c| c.w).fold(1.0, f32::min);
                }
                if lowest >= threshold {
                    Self::Opaque
                } else if let AlphaMode::Mask { cutoff } = material.alpha_mode {
                    Self::Mask(cutoff)
                } else {
                    Self::Blend
                }
            })
            .collect()
    }
}

/// The alpha of `material` on `mesh` at barycentrics (b1, b2) of triangle `triangle`.
pub fn alpha_at(scene: &Scene, material: &Material, mesh: &Mesh, triangle: u32, bary: Vec2) -> f32 {
    let mut alpha = material.base_color.w;
    if let Some(r) = &material.base_color_texture {
        alpha *= sample_ref(scene, r, mesh_uv(mesh, triangle, bary)).w;
    }
    if !mesh.colors.is_empty() {
        alpha *= mesh_color(mesh, triangle, bary).w;
    }
    alpha
}

/// The uniform number in [0, 1) that decides whether the world ray (`origin`, `direction`)
/// meets triangle `triangle` of BLEND object `object`: it does when the number is below the
/// alpha there.
pub fn coverage_sample(origin: Vec3, direction: Vec3, object: ObjectId, triangle: u32) -> f32 {
    let bits = |v: Vec3| {
        (
            u64::from(v.x.to_bits()) << 32 | u64::from(v.y.to_bits()),
            u64::from(v.z.to_bits()),
        )
    };
    let (o_xy, o_z) = bits(origin);
    let (d_xy, d_z) = bits(direction);
    let mut h = mix64(o_xy ^ 0x243f_6a88_85a3_08d3);
    h = mix64(h ^ o_z.wrapping_mul(0x9e37_79b9_7f4a_7c15));
    h = mix64(h ^ d_xy);
    h = mix64(h ^ d_z.wrapping_mul(0xd1b5_4a32_d192_ed03));
    h = mix64(h ^ (u64::from(object) << 32 | u64::from(triangle)));
    (h >> 40) as f32 * (1.0 / 16_777_216.0)
}

/// Whether the hit of the world ray (`origin`, `direction`) on triangle `triangle` at
/// barycentrics `bary` of `object` counts, under `test`.
#[inline]
#[allow(clippy::too_many_arguments)]
pub(crate) fn accepts(
    test: AlphaTest,
    scene: &Scene,
    object: ObjectId,
    mesh: &Mesh,
    triangle: u32,
    bary: Vec2,
    origin: Vec3,
    direction: Vec3,
) -> bool {
    let material = || &scene.materials[scene.objects[object as usize].material];
    match test {
        AlphaTest::Opaque => true,
        AlphaTest::Mask(cutoff) => alpha_at(scene, material(), mesh, triangle, bary) >= cutoff,
        AlphaTest::Blend => {
            let alpha = alpha_at(scene, material(), mesh, triangle, bary);
            alpha >= 1.0
                || (alpha > 0.0 && coverage_sample(origin, direction, object, triangle) < alpha)
        }
    }
}

/// The expected coverage of a surface point: alpha for BLEND (what a ray meets on average),
/// 0 or 1 for MASK, 1 for opaque. Light sampling weights emission with it, so that sampling an
/// emitter and hitting it agree.
pub fn coverage(scene: &Scene, material: &Material, mesh: &Mesh, triangle: u32, bary: Vec2) -> f32 {
    match material.alpha_mode {
        AlphaMode::Opaque => 1.0,
        AlphaMode::Mask { cutoff } => {
            if alpha_at(scene, material, mesh, triangle, bary) >= cutoff {
                1.0
            } else {
                0.0
            }
        }
        AlphaMode::Blend => alpha_at(scene, material, mesh, triangle, bary).clamp(0.0, 1.0),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn coverage_samples_are_uniform_and_deterministic() {
        let n = 20_000;
        let mut below = 0;
        let mut sum = 0.0f64;
        for i in 0..n {
            let o = Vec3::new(i as f32 * 0.01, 1.0, -(i as f32) * 0.003);
            let u = coverage_sample(o, Vec3::NEG_Y, 3, 1);
            assert_eq!(u, coverage_sample(o, Vec3::NEG_Y, 3, 1));
            assert!((0.0..1.0).contains(&u));
            sum += f64::from(u);
            if u < 0.25 {
                below += 1;
            }
        }
        let mean = sum / f64::from(n);
        let frac = f64::from(below) / f64::from(n);
        // σ of the mean 0.29/√n ≈ 0.002; of the fraction √(0.25·0.75/n) ≈ 0.003.
        assert!((mean - 0.5).abs() < 0.01, "{mean}");
        assert!((frac - 0.25).abs() < 0.012, "{frac}");
        assert_ne!(
            coverage_sample(Vec3::ZERO, Vec3::Y, 0, 0),
            coverage_sample(Vec3::ZERO, Vec3::Y, 0, 1)
        );
    }
}
