//! The reference path tracer: unbiased, next-event estimation for emissive triangles and the
//! environment with multiple importance sampling against BSDF sampling (power heuristic),
//! punctual lights by next-event estimation only, Russian roulette. Without environment
//! sampling ([`PathTracerSettings::environment_sampling`] off, for comparisons) the sky is
//! found by BSDF sampling alone. It is the ground truth of every quality
//! figure (docs/architecture.md, "Measuring").

use glam::Vec3;

use crate::accel::{PlacedScene, Ray};
use crate::camera::Camera;
use crate::image::Image;
use crate::light::{Competing, LightSamples, estimate_direct};
use crate::material::{Bsdf, Lobes, SurfaceProps};
use crate::render::{RadianceSample, render_camera};
use crate::sampling::{Sampler, power_heuristic};

/// Settings of the [`PathTracer`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PathTracerSettings {
    /// Samples per pixel; noise falls as 1/√spp, time grows linearly.
    pub samples_per_pixel: u32,
    /// Largest number of bounces; paths are cut there (a bias only for scenes that keep
    /// energy beyond it, such as a furnace with albedo near 1).
    pub max_depth: u32,
    /// Bounce from which Russian roulette may end paths (unbiased; saves time on long paths).
    pub rr_start_depth: u32,
    /// Seed of the random streams.
    pub seed: u64,
    /// Next-event estimation towards the environment (on by default; off only to measure what
    /// it gains).
    pub environment_sampling: bool,
}

impl Default for PathTracerSettings {
    fn default() -> Self {
        Self {
            samples_per_pixel: 64,
            max_depth: 64,
            rr_start_depth: 3,
            seed: 0,
            environment_sampling: true,
        }
    }
}

/// The reference path tracer.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct PathTracer {
    /// Settings.
    pub settings: PathTracerSettings,
}

impl PathTracer {
    /// A path tracer with `settings`.
    pub fn new(settings: PathTracerSettings) -> Self {
        Self { settings }
    }

    /// Radiance arriving along `ray` (one path), with the first hit's auxiliary data.
    pub fn radiance(
        &self,
        placed: &PlacedScene<'_>,
        ray: &Ray,
        sampler: &mut Sampler,
    ) -> RadianceSample {
        let scene = placed.scene();
        let lights = placed.lights();
        let mut out = RadianceSample::MISS;
        let mut l = Vec3::ZERO;
        let mut beta = Vec3::ONE;
        let mut ray = *ray;
        let mut prev_pdf = 0.0f32;
        let mut prev_delta = true;
        for depth in 0..=self.settings.max_depth {
            let Some(hit) = placed.intersect(&ray) else {
                let env = lights.environment();
                if !env.is_none() {
                    let le = env.radiance(ray.direction);
                    let w = if prev_delta || !self.settings.environment_sampling {
                        1.0
                    } else {
                        power_heuristic(prev_pdf, env.pdf(ray.direction))
                    };
                    l += beta * le * w;
                }
                break;
            };
            if depth == 0 {
                out = RadianceSample::first_hit(&hit, &ray);
            }
            let props = SurfaceProps::at(scene, &hit);
            let le = props.emission(&hit);
            if le != Vec3::ZERO {
                let w = if prev_delta {
                    1.0
                } else {
                    power_heuristic(prev_pdf, lights.emissive_pdf(ray.origin, &hit))
                };
                l += beta * le * w;
            }
            if depth == self.settings.max_depth {
                break;
            }
            let wo = -ray.direction;
            let bsdf = Bsdf::new(&props, &hit, wo);
            if !bsdf.is_delta(Lobes::All) {
                l += beta
                    * estimate_direct(
                        placed,
                        &hit,
                        &bsdf,
                        LightSamples {
                            lobes: Lobes::All,
                            competing: Competing {
                                emissive: &[Lobes::All],
                                environment: self
                                    .settings
                                    .environment_sampling
                                    .then_some((Lobes::All, &[Lobes::All][..])),
                            },
                            count: 1,
                        },
                        sampler,
                    );
            }
            let u_lobe = sampler.next_f32();
            let u = sampler.next_2d();
            let Some(bs) = bsdf.sample(u_lobe, u, Lobes::All) else {
                break;
            };
            beta *= bs.weight;
            prev_pdf = bs.pdf;
            prev_delta = bs.delta;
            ray = Ray::new(hit.offset_origin(bs.wi), bs.wi);
            if depth + 1 >= self.settings.rr_start_depth {
                let q = beta.max_element().min(0.95);
                if q <= 0.0 || sampler.next_f32() >= q {
                    break;
                }
                beta /= q;
            }
        }
        out.radiance = l;
        out
    }

    /// Renders `camera`: mean radiance per pixel plus the centre ray's auxiliary data.
    pub fn render(
        &self,
        placed: &PlacedScene<'_>,
        camera: &(impl Camera + ?Sized),
    ) -> Image<RadianceSample> {
        let PathTracerSettings {
            samples_per_pixel,
            seed,
            ..
        } = self.settings;
        render_camera(camera, samples_per_pixel, seed, |ray, s, _| {
            self.radiance(placed, ray, s)
        })
    }
}
