//! What both renderers return per sample, and the pixel loop they share.

use glam::{Vec2, Vec3};
use plenoptic_scene::{NO_OBJECT, ObjectId};

use crate::accel::{Hit, Ray};
use crate::camera::Camera;
use crate::image::{Image, luminance};
use crate::sampling::Sampler;

/// Radiance along one ray with what the first hit tells about the surface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RadianceSample {
    /// Linear RGB radiance arriving along the ray.
    pub radiance: Vec3,
    /// Distance to the first hit; infinite for a miss.
    pub distance: f32,
    /// Object of the first hit; [`NO_OBJECT`] for a miss.
    pub object: ObjectId,
    /// Shading normal of the first hit facing the ray; zero for a miss.
    pub normal: Vec3,
    /// The part of `radiance` that the first hit's Lambertian lobe reflects: direct light
    /// through the diffuse lobe plus the ambient field's indirect diffuse light. `radiance −
    /// diffuse` is emission and the specular/view-dependent part. Filled by the multi-stage
    /// renderer (the bake's denoiser filters `diffuse / albedo` and nothing else); zero from
    /// the path tracer, which does not split.
    pub diffuse: Vec3,
    /// Diffuse albedo of the first hit, `(1 − metallic)(1 − transmission) · base colour` with
    /// textures and vertex colours applied (no Fresnel factor: that stays in the lighting).
    /// `diffuse / albedo` is the hit's diffuse lighting, what pack v2 stores apart from
    /// reflectance. Zero for a miss and from the path tracer.
    pub albedo: Vec3,
    /// Variance of the mean over the pixel's samples of the diffuse lighting's luminance
    /// (each sample's `luminance(diffuse) / luminance(albedo)`): the noise the bake's denoiser
    /// weighs luminance differences against. Zero with one sample per pixel (unknown) and
    /// where `diffuse` is zero.
    pub lighting_variance: f32,
    /// The part of `radiance` that is the first hit's direct light from the scene's sun
    /// ([`plenoptic_scene::Scene::sun`]) through all its lobes, shadow rays included: what
    /// pack 3 leaves out of the stored lighting and non-diffuse radiance for the runtime to
    /// evaluate at screen resolution. Zero without a sun and from the path tracer.
    pub sun: Vec3,
    /// The Lambertian lobe's share of `sun` (part of `diffuse`).
    pub sun_diffuse: Vec3,
    /// The part of `diffuse` that is the first hit's direct light from the scene's point and
    /// spot lights, shadow rays included: what a pack whose lamps are lit at runtime leaves
    /// out of the stored lighting. Zero without lamps and from the path tracer.
    pub lamp_diffuse: Vec3,
    /// The ambient share of `diffuse`: the first hit's indirect diffuse light (the ambient
    /// field's, or its final gather's), without direct light. It varies slowly over a
    /// surface, so the bake may smooth it where it would not smooth shadow edges.
    pub ambient: Vec3,
    /// The part of `radiance` that the first hit emits towards the ray: what pack 4 leaves
    /// out of the non-diffuse radiance for the runtime to take from the material at screen
    /// resolution. Zero for a miss and from the path tracer.
    pub emission: Vec3,
}

impl RadianceSample {
    /// Adds the light of `other`, a sample along the same ray of the same scene lit by other
    /// emitters (a light group's: light transport is linear in the emitters), into this one:
    /// every radiance and its parts add, the variances of independent estimates add, and
    /// the geometry and the albedo, which do not depend on the emitters, stay this sample's.
    pub fn add_light(&mut self, other: &RadianceSample) {
        self.radiance += other.radiance;
        self.diffuse += other.diffuse;
        self.lighting_variance += other.lighting_variance;
        self.sun += other.sun;
        self.sun_diffuse += other.sun_diffuse;
        self.lamp_diffuse += other.lamp_diffuse;
        self.ambient += other.ambient;
        self.emission += other.emission;
    }

    /// A miss before the environment is added: no radiance, infinite distance (the renderers
    /// set the environment's radiance for the ray).
    pub const MISS: Self = Self {
        radiance: Vec3::ZERO,
        distance: f32::INFINITY,
        object: NO_OBJECT,
        normal: Vec3::ZERO,
        diffuse: Vec3::ZERO,
        albedo: Vec3::ZERO,
        lighting_variance: 0.0,
        sun: Vec3::ZERO,
        sun_diffuse: Vec3::ZERO,
        lamp_diffuse: Vec3::ZERO,
        ambient: Vec3::ZERO,
        emission: Vec3::ZERO,
    };

    pub(crate) fn first_hit(hit: &Hit, ray: &Ray) -> Self {
        let n = if hit.shading_normal.dot(ray.direction) > 0.0 {
            -hit.shading_normal
        } else {
            hit.shading_normal
        };
        Self {
            distance: hit.distance,
            object: hit.object,
            normal: n,
            ..Self::MISS
        }
    }
}

/// Renders `camera` with `spp` jittered samples per pixel: radiance, its diffuse part and the
/// albedo are means over the samples (so `diffuse / albedo` demodulates textures the way the
/// pixel saw them), the other auxiliary fields come from a ray through the pixel centre. Sample k of pixel i draws from
/// `Sampler::new(seed, i, k)`, so the image is the same for any thread count.
pub fn render_camera<C, F>(camera: &C, spp: u32, seed: u64, f: F) -> Image<RadianceSample>
where
    C: Camera + ?Sized,
    F: Fn(&Ray, &mut Sampler, bool) -> RadianceSample + Sync,
{
    render_camera_filtered(camera, spp, seed, PixelFilter::Box, f)
}

/// Which of a pixel's samples its means take.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PixelFilter {
    /// Every sample: the mean over the pixel's area (images to look at, references).
    Box,
    /// Only the samples that hit the object the pixel-centre ray hit (or missed, as it did): a
    /// pixel's colour then belongs to the surface its distance and id describe, as a range
    /// image's lookups take it. Where rays pass a see-through surface (BLEND coverage c), the
    /// pixel is the surface's own radiance where the centre ray stopped at it, and what lies
    /// behind where it passed, instead of the mix c · surface + (1 − c) · behind in both (with
    /// the mix, the tour's glazed window would show the sky through its own pane texels). At
    /// silhouettes, the centre's object alone.
    SameObject,
}

/// [`render_camera`] with the samples `filter` keeps (at least the centre ray's).
pub fn render_camera_filtered<C, F>(
    camera: &C,
    spp: u32,
    seed: u64,
    filter: PixelFilter,
    f: F,
) -> Image<RadianceSample>
where
    C: Camera + ?Sized,
    F: Fn(&Ray, &mut Sampler, bool) -> RadianceSample + Sync,
{
    let (w, h) = camera.resolution();
    let spp = spp.max(1);
    Image::render(w, h, |x, y| {
        let pixel = u64::from(y) * u64::from(w) + u64::from(x);
        // The kept samples' light (`add_light`: every radiance and its parts) and albedo.
        let mut sum = RadianceSample::MISS;
        let mut albedo = Vec3::ZERO;
        let (mut l1, mut l2) = (0.0f64, 0.0f64);
        let mut aux = RadianceSample::MISS;
        let mut any = false;
        let mut kept = 0u32;
        for k in 0..spp {
            let mut s = Sampler::new(seed, pixel, u64::from(k));
            let offset = if k == 0 {
                Vec2::splat(0.5)
            } else {
                s.next_2d()
            };
            let Some(ray) = camera.ray(x, y, offset) else {
                continue;
            };
            let r = f(&ray, &mut s, k == 0);
            if k == 0 {
                aux = r;
            }
            // The centre ray (k = 0) is always kept, so `aux` is set before any comparison.
            if filter == PixelFilter::SameObject && any && r.object != aux.object {
                continue;
            }
            any = true;
            kept += 1;
            sum.add_light(&r);
            albedo += r.albedo;
            let a = luminance(r.albedo);
            // The variance of the lighting the bake stores and filters: without the sun's
            // direct light, which the runtime evaluates.
            let l = if a > 1e-3 {
                f64::from(luminance(r.diffuse - r.sun_diffuse) / a)
            } else {
                0.0
            };
            l1 += l;
            l2 += l * l;
        }
        if !any {
            return RadianceSample::MISS;
        }
        let n = kept as f32;
        RadianceSample {
            radiance: sum.radiance / n,
            diffuse: sum.diffuse / n,
            albedo: albedo / n,
            sun: sum.sun / n,
            sun_diffuse: sum.sun_diffuse / n,
            lamp_diffuse: sum.lamp_diffuse / n,
            ambient: sum.ambient / n,
            emission: sum.emission / n,
            lighting_variance: if kept > 1 {
                // Unbiased sample variance, over n for the variance of the mean.
                let n = f64::from(kept);
                ((l2 - l1 * l1 / n).max(0.0) / (n - 1.0) / n) as f32
            } else {
                0.0
            },
            ..aux
        }
    })
}

impl Image<RadianceSample> {
    /// The radiance channel.
    pub fn radiance(&self) -> Image<Vec3> {
        self.map(|s| s.radiance)
    }

    /// The object-id channel.
    pub fn objects(&self) -> Image<ObjectId> {
        self.map(|s| s.object)
    }
}
