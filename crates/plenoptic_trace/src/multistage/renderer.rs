//! The per-sample stage of multi-stage rendering (thesis §5.3.5, where *Radiance* computed
//! direct and specular light and read indirect diffuse light from the ambient file).
//!
//! Radiance leaving a hit towards the viewer =
//! emission
//! + direct light from punctual lights (one shadow ray each; the sun's disc sampled for soft
//!   shadows) and emissive triangles (`shadow_samples` shadow rays), through the full BSDF
//! + the environment's reflection in the specular lobes (`shadow_samples` samples)
//! + diffuse directional albedo × ambient-field irradiance / π, where the field holds the
//!   environment's direct light too: a sky seen through a window is a large, smooth source,
//!   gathered once per field point instead of sampled per pixel (which in a room lit through
//!   a small window needs hundreds of shadow rays to converge). With
//!   [`MultiStageSettings::final_gather`] the first hit's irradiance is a final gather over
//!   the field ([`AmbientField::irradiance_gathered`]: one bounce traced from the hit, the
//!   field read where its rays end) instead of the field interpolated at the hit, whose grid
//!   is too coarse for the falloff of light into corners (thesis §5.3.4 augments its
//!   ambient field with irradiance gradients for the same shortcoming of interpolation;
//!   tracing one bounce resolves it where gradients only extrapolate)
//! + specular reflection and refraction traced recursively up to `max_specular_depth`
//!   (one ray for ideal lobes, `glossy_samples` GGX samples for rough ones at the first hit).
//!
//! The first hit's Lambertian share (its direct light through the diffuse lobe plus the
//! ambient term) is returned apart as [`RadianceSample::diffuse`], with the hit's diffuse
//! albedo, for the bake's denoiser (pack v2: lighting apart from reflectance), and its direct
//! light from the scene's sun as [`RadianceSample::sun`] (pack 3 leaves that to the runtime,
//! thesis ch. 5's split of direct and indirect light at different accuracies). Splitting
//! draws no extra random numbers: the radiance is the same with or without it.
//!
//! Emitters and the environment found by glossy rays and by light sampling are combined with
//! the power heuristic; the diffuse lobe sees emitters through light sampling only. A ray that
//! leaves the scene returns the environment's radiance (the sky behind windows).

use glam::Vec3;
use std::f32::consts::PI;

use super::AmbientField;
use crate::accel::{PlacedScene, Ray};
use crate::camera::{Camera, CubeCamera};
use crate::image::Image;
use crate::light::{Competing, LightSamples, estimate_direct_split};
use crate::material::{Bsdf, Lobes, SurfaceProps};
use crate::render::{PixelFilter, RadianceSample, render_camera, render_camera_filtered};
use crate::sampling::{Sampler, power_heuristic};

/// Settings of the [`MultiStageRenderer`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MultiStageSettings {
    /// Samples per pixel (anti-aliasing and the noise of soft shadows and glossy rays).
    pub samples_per_pixel: u32,
    /// Shadow rays towards emissive triangles per hit; soft-shadow noise falls as 1/√n.
    pub shadow_samples: u32,
    /// GGX rays for a rough specular lobe at the first hit (deeper hits use one).
    pub glossy_samples: u32,
    /// Largest number of specular bounces traced.
    pub max_specular_depth: u32,
    /// Seed of the random streams.
    pub seed: u64,
    /// Final-gather rays at the first hit (0: the first hit reads the ambient field
    /// directly). See [`AmbientField::irradiance_gathered`].
    pub final_gather: u32,
}

impl Default for MultiStageSettings {
    fn default() -> Self {
        Self {
            samples_per_pixel: 8,
            shadow_samples: 4,
            glossy_samples: 2,
            max_specular_depth: 4,
            seed: 0,
            final_gather: 0,
        }
    }
}

/// The multi-stage renderer over one ambient field.
#[derive(Debug, Clone, Copy)]
pub struct MultiStageRenderer<'f> {
    /// Settings.
    pub settings: MultiStageSettings,
    field: &'f AmbientField,
}

impl<'f> MultiStageRenderer<'f> {
    /// A renderer reading indirect light from `field` (which should have been gathered for the
    /// same time, or interpolated to it with [`AmbientField::lerp`]).
    pub fn new(settings: MultiStageSettings, field: &'f AmbientField) -> Self {
        Self { settings, field }
    }

    /// Radiance along one ray with the first hit's auxiliary data; the function the baker
    /// calls per temporal-volume sample.
    pub fn sample(
        &self,
        placed: &PlacedScene<'_>,
        ray: &Ray,
        sampler: &mut Sampler,
    ) -> RadianceSample {
        let mut out = RadianceSample::MISS;
        let radiance = self.shade(placed, ray, sampler, 0, None, Some(&mut out));
        out.radiance = radiance;
        out
    }

    fn shade(
        &self,
        placed: &PlacedScene<'_>,
        ray: &Ray,
        s: &mut Sampler,
        depth: u32,
        prev_pdf: Option<f32>,
        // At the first hit: receives the hit's auxiliary data, albedo and diffuse part.
        mut first: Option<&mut RadianceSample>,
    ) -> Vec3 {
        let Some(hit) = placed.intersect(ray) else {
            // The environment: seen directly, through delta bounces, or weighted against
            // light sampling after a glossy one.
            let env = placed.lights().environment();
            if env.is_none() {
                return Vec3::ZERO;
            }
            let w = match prev_pdf {
                None => 1.0,
                Some(p) => power_heuristic(p, env.pdf(ray.direction)),
            };
            return env.radiance(ray.direction) * w;
        };
        let scene = placed.scene();
        let props = SurfaceProps::at(scene, &hit);
        if let Some(out) = first.as_deref_mut() {
            *out = RadianceSample::first_hit(&hit, ray);
            out.albedo = props.base_color * ((1.0 - props.metallic) * (1.0 - props.transmission));
        }
        let mut diffuse = Vec3::ZERO;
        let mut l = Vec3::ZERO;
        let le = props.emission(&hit);
        if le != Vec3::ZERO {
            let w = match prev_pdf {
                None => 1.0,
                Some(p) => power_heuristic(p, placed.lights().emissive_pdf(ray.origin, &hit)),
            };
            l += le * w;
            if let Some(out) = first.as_deref_mut() {
                out.emission = le * w;
            }
        }
        let wo = -ray.direction;
        let bsdf = Bsdf::new(&props, &hit, wo);
        if !bsdf.is_delta(Lobes::All) {
            let n = self.settings.shadow_samples.max(1);
            // Emitters and the environment compete with the glossy rays below. The diffuse
            // lobe's share of the environment is in the ambient field, like indirect light.
            let competing = Competing {
                emissive: &[Lobes::Specular],
                environment: Some((Lobes::Specular, &[Lobes::Specular])),
            };
            let light = LightSamples {
                lobes: Lobes::All,
                competing,
                count: n,
            };
            let direct = estimate_direct_split(placed, &hit, &bsdf, light, s);
            l += direct.total;
            diffuse += direct.diffuse;
            if let Some(out) = first.as_deref_mut() {
                out.sun = direct.sun;
                out.sun_diffuse = direct.sun_diffuse;
                out.lamp_diffuse = direct.lamp_diffuse;
            }
        }
        if bsdf.has(Lobes::Diffuse) {
            // One-sample estimate of the Lambertian lobe's directional albedo (its Fresnel
            // factor depends on the incident direction).
            let u_lobe = s.next_f32();
            let albedo = bsdf
                .sample(u_lobe, s.next_2d(), Lobes::Diffuse)
                .map_or(Vec3::ZERO, |b| b.weight);
            let e = if depth == 0 && self.settings.final_gather > 0 {
                self.field
                    .irradiance_gathered(placed, &hit, wo, self.settings.final_gather, s)
            } else {
                self.field.irradiance_seen(placed, &hit, wo)
            };
            let ambient = albedo * e / PI;
            l += ambient;
            diffuse += ambient;
            if let Some(out) = first.as_deref_mut() {
                out.ambient = ambient;
            }
        }
        if let Some(out) = first {
            out.diffuse = diffuse;
        }
        if depth < self.settings.max_specular_depth && bsdf.has(Lobes::Specular) {
            let rough = !bsdf.is_delta(Lobes::Specular);
            let count = if rough && depth == 0 {
                self.settings.glossy_samples.max(1)
            } else {
                1
            };
            let mut sum = Vec3::ZERO;
            for _ in 0..count {
                let u_lobe = s.next_f32();
                let u = s.next_2d();
                let Some(bs) = bsdf.sample(u_lobe, u, Lobes::Specular) else {
                    continue;
                };
                let next = Ray::new(hit.offset_origin(bs.wi), bs.wi);
                let pdf = (!bs.delta).then_some(bs.pdf);
                sum += bs.weight * self.shade(placed, &next, s, depth + 1, pdf, None);
            }
            l += sum / count as f32;
        }
        l
    }

    /// Renders a pinhole (or any) camera.
    pub fn render(
        &self,
        placed: &PlacedScene<'_>,
        camera: &(impl Camera + ?Sized),
    ) -> Image<RadianceSample> {
        render_camera(
            camera,
            self.settings.samples_per_pixel,
            self.settings.seed,
            |ray, s, _| self.sample(placed, ray, s),
        )
    }

    /// Renders the six faces of a cube camera in KTX2 layer order (+X, −X, +Y, −Y, +Z, −Z);
    /// each texel's means take only the samples that hit the centre ray's object
    /// ([`PixelFilter::SameObject`]), as the range image's lookups read a texel.
    pub fn render_cube(
        &self,
        placed: &PlacedScene<'_>,
        cube: &CubeCamera,
    ) -> [Image<RadianceSample>; 6] {
        cube.faces().map(|face| {
            let seed =
                self.settings.seed ^ (0x51ed_270b_u64.wrapping_mul(face.face.index() as u64 + 1));
            render_camera_filtered(
                &face,
                self.settings.samples_per_pixel,
                seed,
                PixelFilter::SameObject,
                |ray, s, _| self.sample(placed, ray, s),
            )
        })
    }
}
