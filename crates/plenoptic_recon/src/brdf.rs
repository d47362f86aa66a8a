//! The BSDF of a surface for one incident direction: what the runtime sun needs (pack 3,
//! docs/architecture.md, "The runtime sun"). It is the tracer's glTF metallic-roughness model
//! (`plenoptic_trace::material`: Lambert + GGX with separable Smith masking, the exact
//! dielectric Fresnel for the IOR, Schlick's for metals, Walter et al. 2007's rough BTDF for
//! transmission into a solid, the mirrored reflection lobe through a thin wall), evaluated
//! only, not sampled. The scalar terms (Fresnel, GGX, Smith) are `plenoptic_math::optics`,
//! which the tracer evaluates too; `tests/runtime_sun.rs` checks that both BSDFs give the
//! same value for random surfaces and directions.
//!
//! Everything is in world space: the model is isotropic, so only dot products with the
//! shading normal matter and no tangent frame is built.

use glam::Vec3;
use std::f32::consts::PI;

pub(crate) use plenoptic_math::optics::{DELTA_ROUGHNESS, fresnel_dielectric, fresnel_schlick};
use plenoptic_math::optics::{ggx_d, smith_g1};

/// A material at a surface point, as the tracer's `SurfaceProps` holds it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceMaterial {
    /// Base colour, textured, linear.
    pub base: Vec3,
    /// Metalness in [0, 1].
    pub metallic: f32,
    /// Perceptual roughness in [0, 1].
    pub roughness: f32,
    /// Transmission in [0, 1].
    pub transmission: f32,
    /// Index of refraction (> 0).
    pub ior: f32,
    /// Whether transmission crosses a thin wall without bending (glTF's default; the pack's
    /// thickness 0) rather than refracting into a solid.
    pub thin_walled: bool,
}

impl SurfaceMaterial {
    /// The diffuse albedo the bake divides the lighting by: `(1 − metallic)(1 − transmission)
    /// · base`.
    pub fn albedo(&self) -> Vec3 {
        self.base * ((1.0 - self.metallic) * (1.0 - self.transmission))
    }
}

/// The BSDF at a surface point seen along `wo`.
#[derive(Clone, Copy, Debug)]
pub struct Bsdf {
    n: Vec3,
    ng: Vec3,
    wo: Vec3,
    m: SurfaceMaterial,
    alpha: f32,
    eta: f32,
    delta: bool,
    /// Whether the Lambertian lobe has any weight (the tracer skips light sampling on
    /// surfaces whose every lobe is ideal).
    diffuse: bool,
}

impl Bsdf {
    /// The BSDF of `m` at a point with geometric normal `ng` and shading normal `ns` (unit,
    /// either side), seen from direction `wo` (unit, towards the viewer); `front_face`: the
    /// viewer is on `ng`'s side of the triangle as the mesh winds it.
    pub fn new(m: SurfaceMaterial, ng: Vec3, ns: Vec3, wo: Vec3, front_face: bool) -> Self {
        let side = if wo.dot(ng) >= 0.0 { 1.0 } else { -1.0 };
        let ng = ng * side;
        let mut n = ns * side;
        if n.dot(wo) < 1e-4 {
            n = (n - wo * (n.dot(wo) - 1e-4)).normalize_or(ng);
        }
        let ior = if m.ior > 0.0 { m.ior } else { 1.5 };
        let eta = if front_face || m.thin_walled {
            ior
        } else {
            1.0 / ior
        };
        let fd = fresnel_dielectric(wo.dot(n).clamp(1e-4, 1.0), eta);
        let lum = 0.2126 * m.base.x + 0.7152 * m.base.y + 0.0722 * m.base.z;
        Self {
            n,
            ng,
            wo,
            m,
            alpha: (m.roughness * m.roughness).max(1e-4),
            eta,
            delta: m.roughness < DELTA_ROUGHNESS,
            diffuse: (1.0 - m.metallic) * (1.0 - m.transmission) * (1.0 - fd) * lum.max(0.0) > 0.0,
        }
    }

    /// The shading normal on the viewer's side (what the cosine factor uses).
    pub fn normal(&self) -> Vec3 {
        self.n
    }

    /// The direction towards the viewer.
    pub fn outgoing(&self) -> Vec3 {
        self.wo
    }

    /// Whether light from a direction can be reflected at all: false where every lobe is
    /// ideal (a mirror, clear glass), which the tracer lights through its specular paths
    /// only.
    pub fn takes_light_samples(&self) -> bool {
        self.diffuse || !self.delta
    }

    /// The glossy reflection lobe alone (the GGX term of [`Bsdf::eval`], without the
    /// Lambertian and transmission lobes) for incident direction `wi`: what a lamp's
    /// highlight is ([`crate::lamps`]); zero on ideal surfaces.
    pub fn eval_glossy(&self, wi: Vec3) -> Vec3 {
        let (wo, n) = (self.wo, self.n);
        let cos_i = wi.dot(n);
        if self.delta || cos_i <= 0.0 || wi.dot(self.ng) <= 0.0 {
            return Vec3::ZERO;
        }
        let h = (wo + wi).normalize_or_zero();
        if h == Vec3::ZERO {
            return Vec3::ZERO;
        }
        let d = ggx_d(self.alpha, h.dot(n));
        let g = smith_g1(self.alpha, wo.dot(n)) * smith_g1(self.alpha, cos_i);
        self.glossy_fresnel(wo.dot(h)) * (d * g / (4.0 * wo.dot(n) * cos_i).max(1e-8))
    }

    /// The Lambertian lobe alone (the diffuse term of [`Bsdf::eval`]) for incident direction
    /// `wi`: what a lamp's diffuse light is lit through ([`crate::lamps::diffuse`]); zero
    /// below the surface.
    pub fn eval_diffuse(&self, wi: Vec3) -> Vec3 {
        if wi.dot(self.n) <= 0.0 || wi.dot(self.ng) <= 0.0 {
            return Vec3::ZERO;
        }
        let h = (self.wo + wi).normalize_or_zero();
        if h == Vec3::ZERO {
            return Vec3::ZERO;
        }
        self.lambert(self.wo.dot(h))
    }

    /// The Lambertian lobe at `ω_o·h`: what the dielectric Fresnel lets into the surface,
    /// scattered uniformly.
    fn lambert(&self, voh: f32) -> Vec3 {
        let m = &self.m;
        let fd = fresnel_dielectric(voh.clamp(0.0, 1.0), self.eta);
        m.base * ((1.0 - m.metallic) * (1.0 - m.transmission) * (1.0 - fd) / PI)
    }

    /// The glossy lobe's Fresnel term at `ω_o·h`: the exact dielectric one for the
    /// non-metallic part, Schlick's with the base colour for the metallic part.
    fn glossy_fresnel(&self, voh: f32) -> Vec3 {
        let (m, voh) = (&self.m, voh.clamp(0.0, 1.0));
        Vec3::splat((1.0 - m.metallic) * fresnel_dielectric(voh, self.eta))
            + fresnel_schlick(m.base, voh) * m.metallic
    }

    /// The glossy lobe's weight `f · cos θ_i / pdf` for a direction `wi` reflected about the
    /// half-vector `h` drawn from the GGX distribution `D(h)(n·h)`: `F · G · (ω_o·h) /
    /// ((n·ω_o)(n·h))`. The mean of these weights times the radiance from `wi` estimates the
    /// lobe's reflected radiance without bias ([`crate::specular`]).
    pub fn glossy_weight(&self, h: Vec3, wi: Vec3) -> Vec3 {
        let (wo, n) = (self.wo, self.n);
        let (cos_o, cos_i, cos_h) = (wo.dot(n), wi.dot(n), h.dot(n));
        if cos_i <= 0.0 || cos_h <= 0.0 || wi.dot(self.ng) <= 0.0 {
            return Vec3::ZERO;
        }
        let voh = wo.dot(h).clamp(0.0, 1.0);
        let g = smith_g1(self.alpha, cos_o) * smith_g1(self.alpha, cos_i);
        self.glossy_fresnel(voh) * (g * voh / (cos_o * cos_h).max(1e-8))
    }

    /// The BSDF's value for incident direction `wi` (unit, away from the surface).
    pub fn eval(&self, wi: Vec3) -> Vec3 {
        let (wo, n, m) = (self.wo, self.n, &self.m);
        let cos_i = wi.dot(n);
        let reflect = cos_i > 0.0;
        if reflect != (wi.dot(self.ng) > 0.0) {
            return Vec3::ZERO;
        }
        let cos_o = wo.dot(n);
        let (metal, tr) = (m.metallic, m.transmission);
        if reflect {
            let h = (wo + wi).normalize_or_zero();
            if h == Vec3::ZERO {
                return Vec3::ZERO;
            }
            self.lambert(wo.dot(h)) + self.eval_glossy(wi)
        } else if m.thin_walled && !self.delta && tr > 0.0 && metal < 1.0 {
            // The microfacet reflection mirrored through the wall's plane.
            let wr = wi - n * (2.0 * cos_i);
            let h = (wo + wr).normalize_or_zero();
            if h == Vec3::ZERO {
                return Vec3::ZERO;
            }
            let voh = wo.dot(h).clamp(0.0, 1.0);
            let fd = fresnel_dielectric(voh, self.eta);
            let d = ggx_d(self.alpha, h.dot(n));
            let g = smith_g1(self.alpha, cos_o) * smith_g1(self.alpha, -cos_i);
            m.base * ((1.0 - metal) * tr * (1.0 - fd) * d * g / (4.0 * cos_o * -cos_i).max(1e-8))
        } else if !self.delta && tr > 0.0 && metal < 1.0 {
            let eta = self.eta;
            let mut h = (wo + wi * eta).normalize_or_zero();
            if h == Vec3::ZERO {
                return Vec3::ZERO;
            }
            if h.dot(n) < 0.0 {
                h = -h;
            }
            let (woh, wih) = (wo.dot(h), wi.dot(h));
            if woh * wih >= 0.0 {
                return Vec3::ZERO;
            }
            let denom = (wih + woh / eta).powi(2);
            let fd = fresnel_dielectric(woh.abs(), eta);
            let d = ggx_d(self.alpha, h.dot(n));
            let g = smith_g1(self.alpha, cos_o) * smith_g1(self.alpha, cos_i);
            let ft = d * (1.0 - fd) * g * (wih * woh / (cos_i * cos_o * denom)).abs() / (eta * eta);
            m.base * ((1.0 - metal) * tr * ft)
        } else {
            Vec3::ZERO
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The mean of `glossy_weight` over half-vectors drawn from `D(h)(n·h)` is the lobe's
    /// directional albedo `∫ f_glossy cos θ_i dω_i`, integrated here on a fine grid: the
    /// weights estimate the lobe without bias.
    #[test]
    fn glossy_weights_average_to_the_lobes_albedo() {
        for (metallic, roughness, cos_o) in
            [(1.0f32, 0.3f32, 0.7f32), (0.0, 0.2, 0.9), (1.0, 0.5, 0.3)]
        {
            let m = SurfaceMaterial {
                base: Vec3::new(0.9, 0.7, 0.5),
                metallic,
                roughness,
                transmission: 0.0,
                ior: 1.5,
                thin_walled: false,
            };
            let wo = Vec3::new((1.0 - cos_o * cos_o).sqrt(), cos_o, 0.0);
            let bsdf = Bsdf::new(m, Vec3::Y, Vec3::Y, wo, true);
            let alpha = roughness * roughness;
            // Importance-sampled: a 256 × 256 stratified grid of half-vectors.
            let k = 256;
            let mut sampled = Vec3::ZERO;
            for i in 0..k {
                for j in 0..k {
                    let u1 = (i as f32 + 0.5) / k as f32;
                    let u2 = (j as f32 + 0.5) / k as f32;
                    let tan2 = alpha * alpha * u1 / (1.0 - u1);
                    let cos_h = 1.0 / (1.0 + tan2).sqrt();
                    let sin_h = (1.0 - cos_h * cos_h).sqrt();
                    let phi = std::f32::consts::TAU * u2;
                    let h = Vec3::new(sin_h * phi.cos(), cos_h, sin_h * phi.sin());
                    let wi = h * (2.0 * wo.dot(h)) - wo;
                    sampled += bsdf.glossy_weight(h, wi);
                }
            }
            sampled /= (k * k) as f32;
            // Integrated: f · cos over the hemisphere, uniform in cos θ and φ.
            let n = 1024;
            let mut integral = Vec3::ZERO;
            for i in 0..n {
                for j in 0..n {
                    let cos_t = (i as f32 + 0.5) / n as f32;
                    let sin_t = (1.0 - cos_t * cos_t).sqrt();
                    let phi = std::f32::consts::TAU * (j as f32 + 0.5) / n as f32;
                    let wi = Vec3::new(sin_t * phi.cos(), cos_t, sin_t * phi.sin());
                    integral += bsdf.eval_glossy(wi) * cos_t;
                }
            }
            integral *= std::f32::consts::TAU / (n * n) as f32;
            let rel = ((sampled - integral) / integral).abs().max_element();
            assert!(
                rel < 0.02,
                "metal {metallic}, roughness {roughness}, cos {cos_o}: {sampled} against {integral}"
            );
        }
    }
}
