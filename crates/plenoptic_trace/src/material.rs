//! Materials at a hit and the BSDF the renderers share.
//!
//! The glTF metallic-roughness model: `mix(dielectric, metal, metallic)` where the dielectric
//! is `mix(base, specular, F)` and the base is `mix(Lambert, BTDF, transmission)`
//! (KHR_materials_transmission). Specular reflection is GGX with height-correlated-free
//! separable Smith masking; the dielectric Fresnel is the exact one for the material's IOR
//! (so IOR 1 gives a pure Lambertian surface, F0 = ((ior−1)/(ior+1))² = 0.04 at IOR 1.5),
//! the metal Fresnel is Schlick's with F0 = base colour. Roughness below [`DELTA_ROUGHNESS`]
//! gives delta (mirror / ideal refraction) lobes.
//!
//! Transmission follows glTF's two cases:
//! - **thin-walled** (the default: no `KHR_materials_volume`, or thickness 0): the surface is
//!   an infinitely thin wall between air and air. The transmitted ray leaves without bending,
//!   along the microfacet reflection mirrored through the surface's plane (the straight line
//!   when smooth), weighted by (1 − F)·transmission·base colour, and both faces see the IOR
//!   from outside. A pane modelled as one quad, or as a box, shows what is behind it in place.
//! - **thick** (`KHR_materials_volume` thickness above 0): the mesh bounds a solid dielectric;
//!   rays refract into it and out again at its other faces (Walter et al. 2007 rough BTDF),
//!   so a slab shows inter-reflections and a block bends what is seen through it.

use glam::{Vec2, Vec3};
use plenoptic_scene::Scene;
use std::f32::consts::PI;

use crate::accel::Hit;
use crate::image::luminance;
use crate::sampling::Frame;
use crate::texture::{mesh_color, sample_opt};

pub use plenoptic_math::optics::{DELTA_ROUGHNESS, fresnel_dielectric};
use plenoptic_math::optics::{fresnel_schlick, ggx_d, smith_g1};

pub use crate::texture::sample_texture;

/// The material evaluated at a surface point (textures applied).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceProps {
    /// Linear base colour.
    pub base_color: Vec3,
    /// Metalness.
    pub metallic: f32,
    /// Perceptual roughness.
    pub roughness: f32,
    /// Emitted radiance (front side, or both sides when double-sided).
    pub emissive: Vec3,
    /// Transmission factor.
    pub transmission: f32,
    /// Index of refraction.
    pub ior: f32,
    /// Whether transmission crosses a thin wall (no bending) rather than entering a solid.
    pub thin_walled: bool,
    /// Whether back faces emit.
    pub double_sided: bool,
}

impl SurfaceProps {
    /// The material of the object at `hit`, with its textures sampled at the hit's uv (each
    /// through its reference's transform and wrap modes) and the base colour multiplied by
    /// the `COLOR_0` vertex colour. Alpha is not part of the result: MASK and BLEND act in the
    /// traversal ([`crate::alpha`]), so a hit that reaches shading is opaque.
    pub fn at(scene: &Scene, hit: &Hit) -> Self {
        let object = &scene.objects[hit.object as usize];
        let m = &scene.materials[object.material];
        let tex = |r: Option<plenoptic_scene::TextureRef>| sample_opt(scene, r.as_ref(), hit.uv);
        let mut base = m.base_color * tex(m.base_color_texture);
        if let Some(mesh) = scene.meshes.get(object.mesh)
            && !mesh.colors.is_empty()
        {
            base *= mesh_color(mesh, hit.triangle, hit.barycentrics);
        }
        let mr = tex(m.metallic_roughness_texture);
        let emissive = m.emissive * tex(m.emissive_texture).truncate();
        Self {
            base_color: base.truncate(),
            metallic: (m.metallic * mr.z).clamp(0.0, 1.0),
            roughness: (m.roughness * mr.y).clamp(0.0, 1.0),
            emissive,
            transmission: m.transmission.clamp(0.0, 1.0),
            ior: if m.ior > 0.0 { m.ior } else { 1.5 },
            thin_walled: m.thickness <= 0.0,
            double_sided: m.double_sided,
        }
    }

    /// Radiance emitted towards the ray that made `hit`.
    pub fn emission(&self, hit: &Hit) -> Vec3 {
        if hit.front_face || self.double_sided {
            self.emissive
        } else {
            Vec3::ZERO
        }
    }
}

/// Refracts `wo` (pointing away, `wo·n > 0`) through the interface with normal `n`; `eta` =
/// n_t / n_i. `None` under total internal reflection.
pub fn refract(wo: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    let cos_i = wo.dot(n);
    let sin2_t = (1.0 - cos_i * cos_i).max(0.0) / (eta * eta);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some((-wo / eta + n * (cos_i / eta - cos_t)).normalize())
}

/// Samples a GGX microfacet normal in local space with density D(h)·cosθ_h.
fn ggx_sample_h(alpha: f32, u: Vec2) -> Vec3 {
    let a2 = alpha * alpha;
    let cos2 = (1.0 - u.x) / (1.0 + (a2 - 1.0) * u.x);
    let cos = cos2.sqrt();
    let sin = (1.0 - cos2).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(sin * phi.cos(), sin * phi.sin(), cos)
}

/// Which lobes a query concerns.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Lobes {
    /// All lobes.
    All,
    /// The Lambertian lobe only.
    Diffuse,
    /// Specular/glossy reflection and transmission (delta or GGX).
    Specular,
}

/// A sampled direction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BsdfSample {
    /// Incident direction (pointing away from the surface).
    pub wi: Vec3,
    /// f·|cos|/pdf.
    pub weight: Vec3,
    /// Solid-angle density of the non-delta mixture (0 for delta samples).
    pub pdf: f32,
    /// Whether the sample came from a delta lobe.
    pub delta: bool,
}

/// The BSDF at one hit for one outgoing direction.
#[derive(Debug, Clone, Copy)]
pub struct Bsdf {
    frame: Frame,
    /// Geometric normal on the side of `wo`.
    ng: Vec3,
    wo_local: Vec3,
    base: Vec3,
    metallic: f32,
    alpha: f32,
    transmission: f32,
    /// n_other / n_wo-side (the IOR on both faces of a thin wall).
    eta: f32,
    /// Thin-walled transmission: mirrored reflection instead of refraction.
    thin: bool,
    delta: bool,
    /// Lobe selection weights: diffuse, specular reflection, transmission.
    p: [f32; 3],
}

impl Bsdf {
    /// The BSDF of `props` at `hit` seen from direction `wo` (unit, pointing away).
    pub fn new(props: &SurfaceProps, hit: &Hit, wo: Vec3) -> Self {
        let side = if wo.dot(hit.geometric_normal) >= 0.0 {
            1.0
        } else {
            -1.0
        };
        let ng = hit.geometric_normal * side;
        let mut n = hit.shading_normal * side;
        // Keep wo above the shading hemisphere (bent normals from normal maps).
        if n.dot(wo) < 1e-4 {
            n = (n - wo * (n.dot(wo) - 1e-4)).normalize_or(ng);
        }
        let frame = Frame::from_normal(n);
        let wo_local = frame.to_local(wo);
        let eta = if hit.front_face || props.thin_walled {
            props.ior
        } else {
            1.0 / props.ior
        };
        let delta = props.roughness < DELTA_ROUGHNESS;
        let alpha = (props.roughness * props.roughness).max(1e-4);
        let m = props.metallic;
        let tr = props.transmission;
        let cos_o = wo_local.z.clamp(1e-4, 1.0);
        let fd = fresnel_dielectric(cos_o, eta);
        let fm = luminance(fresnel_schlick(props.base_color, cos_o));
        let lb = luminance(props.base_color).max(0.0);
        let p = [
            (1.0 - m) * (1.0 - tr) * (1.0 - fd) * lb,
            ((1.0 - m) * fd + m * fm).max(if m > 0.0 || fd > 0.0 { 0.05 } else { 0.0 }),
            (1.0 - m) * tr * (1.0 - fd) * lb,
        ];
        Self {
            frame,
            ng,
            wo_local,
            base: props.base_color,
            metallic: m,
            alpha,
            transmission: tr,
            eta,
            thin: props.thin_walled,
            delta,
            p,
        }
    }

    fn lobe_probs(&self, lobes: Lobes) -> [f32; 3] {
        let mut p = self.p;
        match lobes {
            Lobes::All => {}
            Lobes::Diffuse => {
                p[1] = 0.0;
                p[2] = 0.0;
            }
            Lobes::Specular => p[0] = 0.0,
        }
        let s = p[0] + p[1] + p[2];
        if s > 0.0 { p.map(|x| x / s) } else { [0.0; 3] }
    }

    /// Whether the selected lobes are all delta (or empty): next-event estimation is useless.
    pub fn is_delta(&self, lobes: Lobes) -> bool {
        let p = self.lobe_probs(lobes);
        p[0] == 0.0 && (self.delta || (p[1] == 0.0 && p[2] == 0.0))
    }

    /// Whether any of `lobes` can scatter light.
    pub fn has(&self, lobes: Lobes) -> bool {
        self.lobe_probs(lobes).iter().any(|&p| p > 0.0)
    }

    /// The shading normal on the side of `wo`.
    pub fn normal(&self) -> Vec3 {
        self.frame.n
    }

    /// Directional albedo of the Lambertian lobe towards `wo`, as used with the ambient field:
    /// (1−metallic)(1−transmission)(1−F(n·wo))·base.
    pub fn diffuse_albedo(&self) -> Vec3 {
        let fd = fresnel_dielectric(self.wo_local.z.clamp(1e-4, 1.0), self.eta);
        self.base * ((1.0 - self.metallic) * (1.0 - self.transmission) * (1.0 - fd))
    }

    /// BSDF value (without the cosine) and the solid-angle pdf of sampling `wi` with
    /// [`Bsdf::sample`] restricted to `lobes`; delta lobes contribute nothing.
    pub fn eval(&self, wi: Vec3, lobes: Lobes) -> (Vec3, f32) {
        let wo = self.wo_local;
        let wi_l = self.frame.to_local(wi);
        let geo_reflect = wi.dot(self.ng) > 0.0;
        let reflect = wi_l.z > 0.0;
        if reflect != geo_reflect {
            return (Vec3::ZERO, 0.0);
        }
        let probs = self.lobe_probs(lobes);
        let (m, tr) = (self.metallic, self.transmission);
        let mut f = Vec3::ZERO;
        let mut pdf = 0.0;
        if reflect {
            let h = (wo + wi_l).normalize_or_zero();
            if h == Vec3::ZERO {
                return (Vec3::ZERO, 0.0);
            }
            let voh = wo.dot(h).clamp(0.0, 1.0);
            let fd = fresnel_dielectric(voh, self.eta);
            if lobes != Lobes::Specular {
                f += self.base * ((1.0 - m) * (1.0 - tr) * (1.0 - fd) / PI);
                pdf += probs[0] * wi_l.z / PI;
            }
            if !self.delta && lobes != Lobes::Diffuse {
                let d = ggx_d(self.alpha, h.z);
                let g = smith_g1(self.alpha, wo.z) * smith_g1(self.alpha, wi_l.z);
                let fr = Vec3::splat((1.0 - m) * fd) + fresnel_schlick(self.base, voh) * m;
                f += fr * (d * g / (4.0 * wo.z * wi_l.z).max(1e-8));
                pdf += probs[1] * d * h.z / (4.0 * voh).max(1e-8);
            }
        } else if self.thin && !self.delta && lobes != Lobes::Diffuse && tr > 0.0 && m < 1.0 {
            // The microfacet reflection mirrored through the wall's plane.
            let wr = Vec3::new(wi_l.x, wi_l.y, -wi_l.z);
            let h = (wo + wr).normalize_or_zero();
            if h == Vec3::ZERO {
                return (Vec3::ZERO, 0.0);
            }
            let voh = wo.dot(h).clamp(0.0, 1.0);
            let fd = fresnel_dielectric(voh, self.eta);
            let d = ggx_d(self.alpha, h.z);
            let g = smith_g1(self.alpha, wo.z) * smith_g1(self.alpha, wr.z);
            f += self.base * ((1.0 - m) * tr * (1.0 - fd) * d * g / (4.0 * wo.z * wr.z).max(1e-8));
            pdf += probs[2] * d * h.z / (4.0 * voh).max(1e-8);
        } else if !self.delta && lobes != Lobes::Diffuse && tr > 0.0 && m < 1.0 {
            let eta = self.eta;
            let mut h = (wo + wi_l * eta).normalize_or_zero();
            if h == Vec3::ZERO {
                return (Vec3::ZERO, 0.0);
            }
            if h.z < 0.0 {
                h = -h;
            }
            let (woh, wih) = (wo.dot(h), wi_l.dot(h));
            if woh * wih >= 0.0 {
                return (Vec3::ZERO, 0.0);
            }
            let denom = (wih + woh / eta).powi(2);
            let fd = fresnel_dielectric(woh.abs(), eta);
            let d = ggx_d(self.alpha, h.z);
            let g = smith_g1(self.alpha, wo.z) * smith_g1(self.alpha, wi_l.z);
            let ft = d * (1.0 - fd) * g * (wih * woh / (wi_l.z * wo.z * denom)).abs() / (eta * eta);
            f += self.base * ((1.0 - m) * tr * ft);
            pdf += probs[2] * d * h.z * wih.abs() / denom;
        }
        (f, pdf)
    }

    /// Samples an incident direction from the `lobes` with three uniform numbers.
    pub fn sample(&self, u_lobe: f32, u: Vec2, lobes: Lobes) -> Option<BsdfSample> {
        let probs = self.lobe_probs(lobes);
        let wo = self.wo_local;
        let lobe = if u_lobe < probs[0] {
            0
        } else if u_lobe < probs[0] + probs[1] {
            1
        } else if probs[2] > 0.0 {
            2
        } else {
            return None;
        };
        let (m, tr) = (self.metallic, self.transmission);
        if self.delta && lobe > 0 {
            let cos = wo.z.clamp(1e-4, 1.0);
            let fd = fresnel_dielectric(cos, self.eta);
            let (wi_l, weight) = if lobe == 1 {
                let fr = Vec3::splat((1.0 - m) * fd) + fresnel_schlick(self.base, cos) * m;
                (Vec3::new(-wo.x, -wo.y, wo.z), fr / probs[1])
            } else if self.thin {
                let w = self.base * ((1.0 - m) * tr * (1.0 - fd));
                (-wo, w / probs[2])
            } else {
                let wi = refract(wo, Vec3::Z, self.eta)?;
                let w = self.base * ((1.0 - m) * tr * (1.0 - fd) / (self.eta * self.eta));
                (wi, w / probs[2])
            };
            let wi = self.frame.to_world(wi_l);
            if (wi.dot(self.ng) > 0.0) != (wi_l.z > 0.0) {
                return None;
            }
            return Some(BsdfSample {
                wi,
                weight,
                pdf: 0.0,
                delta: true,
            });
        }
        let wi_l = match lobe {
            0 => crate::sampling::cosine_hemisphere(u),
            1 => {
                let h = ggx_sample_h(self.alpha, u);
                let wi = 2.0 * wo.dot(h) * h - wo;
                if wi.z <= 0.0 {
                    return None;
                }
                wi
            }
            _ if self.thin => {
                let h = ggx_sample_h(self.alpha, u);
                let wr = 2.0 * wo.dot(h) * h - wo;
                if wr.z <= 0.0 {
                    return None;
                }
                Vec3::new(wr.x, wr.y, -wr.z)
            }
            _ => {
                let h = ggx_sample_h(self.alpha, u);
                if wo.dot(h) <= 0.0 {
                    return None;
                }
                refract(wo, h, self.eta)?
            }
        };
        let wi = self.frame.to_world(wi_l);
        let (f, pdf) = self.eval(wi, lobes);
        if pdf <= 0.0 || f == Vec3::ZERO {
            return None;
        }
        Some(BsdfSample {
            wi,
            weight: f * (wi_l.z.abs() / pdf),
            pdf,
            delta: false,
        })
    }
}
