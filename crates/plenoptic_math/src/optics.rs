//! The scalar terms of the glTF metallic-roughness BSDF: the exact unpolarised Fresnel
//! reflectance of a dielectric, Schlick's approximation for metals, the GGX (Trowbridge–Reitz)
//! normal distribution and the separable Smith masking term (Walter et al. 2007).

use glam::Vec3;
use std::f32::consts::PI;

/// Perceptual roughness below which reflection and refraction are treated as ideal (mirror,
/// clear glass): delta lobes that no light sample can reach.
pub const DELTA_ROUGHNESS: f32 = 0.02;

/// Fresnel reflectance of a dielectric interface for unpolarised light; `cos_i` on the
/// incident side (clamped to [0, 1]), `eta` = n_transmitted / n_incident. Returns 1 under
/// total internal reflection.
#[inline]
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> f32 {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let r_par = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    0.5 * (r_par * r_par + r_perp * r_perp)
}

/// Schlick's Fresnel approximation with reflectance `f0` at normal incidence, for the cosine
/// `cos` (clamped to [0, 1]) between the direction and the microfacet normal.
#[inline]
pub fn fresnel_schlick(f0: Vec3, cos: f32) -> Vec3 {
    let m = (1.0 - cos.clamp(0.0, 1.0)).powi(5);
    f0 + (Vec3::ONE - f0) * m
}

/// The GGX normal distribution D(h) for roughness `alpha` (perceptual roughness squared) and
/// the cosine `cos_h` between the half vector and the normal; 0 below the surface.
#[inline]
pub fn ggx_d(alpha: f32, cos_h: f32) -> f32 {
    if cos_h <= 0.0 {
        return 0.0;
    }
    let a2 = alpha * alpha;
    let d = cos_h * cos_h * (a2 - 1.0) + 1.0;
    a2 / (PI * d * d)
}

/// The Smith masking term G1 of GGX for roughness `alpha` and the cosine `cos` (either sign)
/// between a direction and the normal.
#[inline]
pub fn smith_g1(alpha: f32, cos: f32) -> f32 {
    let c = cos.abs();
    let a2 = alpha * alpha;
    2.0 * c / (c + (a2 + (1.0 - a2) * c * c).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fresnel_limits() {
        // Normal incidence at IOR 1.5: ((1.5 − 1)/(1.5 + 1))² = 0.04.
        assert!((fresnel_dielectric(1.0, 1.5) - 0.04).abs() < 1e-6);
        // Grazing incidence reflects everything; IOR 1 reflects nothing.
        assert!((fresnel_dielectric(0.0, 1.5) - 1.0).abs() < 1e-6);
        assert!(fresnel_dielectric(0.7, 1.0).abs() < 1e-6);
        // Total internal reflection leaving glass beyond the critical angle.
        assert_eq!(fresnel_dielectric(0.3, 1.0 / 1.5), 1.0);
        assert_eq!(fresnel_schlick(Vec3::splat(0.5), 1.0), Vec3::splat(0.5));
        assert_eq!(fresnel_schlick(Vec3::splat(0.5), 0.0), Vec3::ONE);
    }

    #[test]
    fn ggx_normalised() {
        // ∫ D(h) cos θ_h dω = 1 over the hemisphere, by the midpoint rule in cos θ.
        for alpha in [0.1f32, 0.5, 1.0] {
            let n = 20_000;
            let sum: f32 = (0..n)
                .map(|i| {
                    let c = (i as f32 + 0.5) / n as f32;
                    ggx_d(alpha, c) * c
                })
                .sum();
            let integral = 2.0 * PI * sum / n as f32;
            assert!((integral - 1.0).abs() < 2e-2, "alpha {alpha}: {integral}");
        }
        assert_eq!(ggx_d(0.5, -0.1), 0.0);
        assert!((smith_g1(0.3, 1.0) - 1.0).abs() < 1e-6);
        assert_eq!(smith_g1(0.3, -0.4), smith_g1(0.3, 0.4));
    }
}
