//! Lights at one time: emissive triangles in world space with a distribution by area ×
//! luminance, the punctual lights placed (directional lights with a disc, such as the sun,
//! sampled over it for soft shadows), the environment ([`crate::environment`]), and
//! next-event estimation with multiple importance sampling (power heuristic).

use glam::{Vec2, Vec3};
use plenoptic_scene::{AlphaMode, Light, LightKind, ObjectId, PlacedLight, Scene};
use std::collections::HashMap;

use crate::accel::{Hit, Instance, PlacedScene, Ray};
use crate::alpha::coverage;
use crate::environment::EnvLight;
use crate::image::luminance;
use crate::material::{Bsdf, Lobes};
use crate::sampling::{Distribution1d, Frame, Sampler, power_heuristic, uniform_triangle};
use crate::texture::sample_ref;

/// An emissive triangle placed in the world.
#[derive(Debug, Clone, Copy)]
pub struct EmissiveTriangle {
    /// The object it belongs to.
    pub object: ObjectId,
    /// Triangle index in the object's mesh.
    pub triangle: u32,
    /// First vertex.
    pub p0: Vec3,
    /// Second minus first vertex.
    pub e1: Vec3,
    /// Third minus first vertex.
    pub e2: Vec3,
    /// Unit normal by winding (the emitting side unless double-sided).
    pub normal: Vec3,
    /// Area in m².
    pub area: f32,
    uv: [Vec2; 3],
    material: usize,
}

/// A light sample seen from a shading point.
#[derive(Debug, Clone, Copy)]
pub struct LightSample {
    /// Unit direction from the shading point to the light.
    pub wi: Vec3,
    /// Distance to the light point.
    pub distance: f32,
    /// Incident radiance (area lights) or normal irradiance (punctual lights).
    pub value: Vec3,
    /// Solid-angle density (area lights); infinite for punctual lights.
    pub pdf: f32,
    /// Point on the light.
    pub position: Vec3,
}

/// The lights of a [`PlacedScene`].
#[derive(Debug, Clone, Default)]
pub struct LightSet {
    emissive: Vec<EmissiveTriangle>,
    distribution: Distribution1d,
    index: HashMap<(ObjectId, u32), usize>,
    punctual: Vec<(Light, PlacedLight)>,
    /// Index into `punctual` of the scene's sun.
    sun: Option<usize>,
    env: EnvLight,
}

impl LightSet {
    pub(crate) fn new(scene: &Scene, t: f32, instances: &[Instance], env: EnvLight) -> Self {
        let mut emissive = Vec::new();
        let mut weights = Vec::new();
        for inst in instances {
            let object = &scene.objects[inst.object as usize];
            let material = &scene.materials[object.material];
            let lum = luminance(material.emissive);
            if lum <= 0.0 {
                continue;
            }
            let mesh = &scene.meshes[inst.mesh];
            let has_uv = mesh.uvs.len() == mesh.positions.len();
            for (ti, tri) in mesh.triangles.iter().enumerate() {
                let [a, b, c] =
                    tri.map(|i| inst.to_world.transform_point3(mesh.positions[i as usize]));
                let cross = (b - a).cross(c - a);
                let area = 0.5 * cross.length();
                if area <= 0.0 {
                    continue;
                }
                let uv = if has_uv {
                    tri.map(|i| mesh.uvs[i as usize])
                } else {
                    [Vec2::ZERO; 3]
                };
                weights.push(area * lum);
                emissive.push(EmissiveTriangle {
                    object: inst.object,
                    triangle: ti as u32,
                    p0: a,
                    e1: b - a,
                    e2: c - a,
                    normal: cross / (2.0 * area),
                    area,
                    uv,
                    material: object.material,
                });
            }
        }
        let index = emissive
            .iter()
            .enumerate()
            .map(|(i, e)| ((e.object, e.triangle), i))
            .collect();
        let punctual = (0..scene.lights.len())
            .map(|i| (scene.lights[i].clone(), scene.placed_light(i, t)))
            .collect();
        Self {
            emissive,
            distribution: Distribution1d::new(weights),
            index,
            punctual,
            sun: scene.sun.as_ref().map(|s| s.light),
            env,
        }
    }

    /// The environment at this time.
    pub fn environment(&self) -> &EnvLight {
        &self.env
    }

    /// Emissive triangles.
    pub fn emissive(&self) -> &[EmissiveTriangle] {
        &self.emissive
    }

    /// Whether there are emissive triangles to sample.
    pub fn has_emissive(&self) -> bool {
        !self.distribution.is_empty()
    }

    /// Number of punctual lights.
    pub fn punctual_count(&self) -> usize {
        self.punctual.len()
    }

    /// Whether punctual light `i` is a lamp: a point or spot light (not a directional one).
    pub fn is_lamp(&self, i: usize) -> bool {
        self.punctual
            .get(i)
            .is_some_and(|(l, _)| matches!(l.kind, LightKind::Point | LightKind::Spot { .. }))
    }

    /// Samples a point on the emissive triangles (by area × luminance) as seen from `p`. The
    /// radiance is weighted by the surface's coverage there (0 where a MASK cuts it, alpha for
    /// BLEND), matching what rays that hit emitters see.
    pub fn sample_emissive(
        &self,
        scene: &Scene,
        p: Vec3,
        u_pick: f32,
        u: Vec2,
    ) -> Option<LightSample> {
        if self.distribution.is_empty() {
            return None;
        }
        let (i, pmf) = self.distribution.sample(u_pick);
        let e = &self.emissive[i];
        let b = uniform_triangle(u);
        let q = e.p0 + e.e1 * b.x + e.e2 * b.y;
        let d = q - p;
        let dist2 = d.length_squared();
        if dist2 <= 0.0 {
            return None;
        }
        let dist = dist2.sqrt();
        let wi = d / dist;
        let cos_l = -wi.dot(e.normal);
        let material = &scene.materials[e.material];
        if cos_l.abs() < 1e-6 || (cos_l < 0.0 && !material.double_sided) {
            return None;
        }
        let mut value = material.emissive;
        if let Some(tex) = material.emissive_texture {
            let uv = e.uv[0] * (1.0 - b.x - b.y) + e.uv[1] * b.x + e.uv[2] * b.y;
            value *= sample_ref(scene, &tex, uv).truncate();
        }
        if material.alpha_mode != AlphaMode::Opaque {
            // A cut-out emits nothing; a BLEND emitter is met by a fraction alpha of the rays.
            let mesh = &scene.meshes[scene.objects[e.object as usize].mesh];
            value *= coverage(scene, material, mesh, e.triangle, b);
        }
        Some(LightSample {
            wi,
            distance: dist,
            value,
            pdf: pmf * dist2 / (e.area * cos_l.abs()),
            position: q,
        })
    }

    /// Solid-angle density with which [`LightSet::sample_emissive`] from `from` picks the point
    /// of `hit` (0 when the hit triangle is not emissive).
    pub fn emissive_pdf(&self, from: Vec3, hit: &Hit) -> f32 {
        let Some(&i) = self.index.get(&(hit.object, hit.triangle)) else {
            return 0.0;
        };
        let e = &self.emissive[i];
        let d = hit.position - from;
        let dist2 = d.length_squared();
        let cos_l = (d.dot(e.normal) / dist2.sqrt()).abs();
        if cos_l < 1e-6 {
            return 0.0;
        }
        self.distribution.pmf(i) * dist2 / (e.area * cos_l)
    }

    /// Punctual light `i` seen from `p`: direction, distance and normal irradiance
    /// (I·colour/r² for point and spot lights with the glTF cone falloff, E·colour for
    /// directional ones); `None` outside a spot cone or beyond the range. A directional light
    /// with a disc (`angular_radius` > 0) gives a direction drawn uniformly over the disc's
    /// cone with `u`, carrying the whole disc's irradiance: averaged over draws, the soft
    /// shadow of a sun of that size.
    pub fn punctual_at(&self, i: usize, p: Vec3, u: Vec2) -> Option<LightSample> {
        let (light, placed) = &self.punctual[i];
        let radiant = placed.emitted;
        match light.kind {
            LightKind::Directional => {
                let mut wi = -placed.direction;
                if light.angular_radius > 0.0 {
                    let cos_max = light.angular_radius.min(0.5).cos();
                    let cos_t = 1.0 - u.x * (1.0 - cos_max);
                    let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
                    let phi = 2.0 * std::f32::consts::PI * u.y;
                    let local = Vec3::new(sin_t * phi.cos(), sin_t * phi.sin(), cos_t);
                    wi = Frame::from_normal(wi).to_world(local).normalize();
                }
                Some(LightSample {
                    wi,
                    distance: f32::INFINITY,
                    value: radiant,
                    pdf: f32::INFINITY,
                    position: p + wi * 1e9,
                })
            }
            LightKind::Point | LightKind::Spot { .. } => {
                let d = placed.position - p;
                let dist2 = d.length_squared();
                let dist = dist2.sqrt();
                if dist <= 0.0 || light.range.is_some_and(|r| dist > r) {
                    return None;
                }
                let wi = d / dist;
                let mut value = radiant / dist2;
                if let LightKind::Spot {
                    inner_cone_angle,
                    outer_cone_angle,
                } = light.kind
                {
                    let cd = placed.direction.dot(-wi);
                    let (ci, co) = (inner_cone_angle.cos(), outer_cone_angle.cos());
                    let scale = 1.0 / (ci - co).max(1e-3);
                    let att = ((cd - co) * scale).clamp(0.0, 1.0);
                    value *= att * att;
                }
                (value != Vec3::ZERO).then_some(LightSample {
                    wi,
                    distance: dist,
                    value,
                    pdf: f32::INFINITY,
                    position: placed.position,
                })
            }
        }
    }
}

/// Which lights [`estimate_direct`] samples and which BSDF sampling strategies of the caller
/// compete with it. Each strategy is a set of lobes the caller samples on its own and whose
/// rays add what they find (emission, or the environment when they leave the scene) with
/// `power_heuristic(bsdf_pdf, light_pdf)`. The part of the BSDF in a strategy is weighted by
/// the power heuristic against that strategy's density; the part in none counts fully.
#[derive(Debug, Clone, Copy)]
pub struct Competing<'a> {
    /// Strategies that find emissive triangles.
    pub emissive: &'a [Lobes],
    /// `None`: the environment is not sampled (the caller gets it elsewhere). Else the lobes
    /// whose reflection of it is estimated, and the strategies that also find it.
    pub environment: Option<(Lobes, &'a [Lobes])>,
}

impl Competing<'static> {
    /// Light sampling alone, the environment included through every lobe.
    pub const NONE: Self = Self {
        emissive: &[],
        environment: Some((Lobes::All, &[])),
    };
}

/// `f` with the parts in `strategies` weighted by the power heuristic against `light_pdf`.
fn weighted(bsdf: &Bsdf, wi: Vec3, f_all: Vec3, light_pdf: f32, strategies: &[Lobes]) -> Vec3 {
    let mut f = f_all;
    for &l in strategies {
        let (f_c, p_c) = bsdf.eval(wi, l);
        f += f_c * (power_heuristic(light_pdf, p_c) - 1.0);
    }
    f
}

/// How [`estimate_direct`] samples direct light.
#[derive(Debug, Clone, Copy)]
pub struct LightSamples<'a> {
    /// The part of the BSDF evaluated.
    pub lobes: Lobes,
    /// Which of the caller's BSDF strategies also find emitters and the environment.
    pub competing: Competing<'a>,
    /// Samples of the emissive triangles, and as many of the environment.
    pub count: u32,
}

/// Direct light reflected by `bsdf` at `hit` towards its `wo`: every punctual light once plus
/// `light.count` samples of the emissive triangles and as many of the environment, each
/// shadow-tested.
pub fn estimate_direct(
    placed: &PlacedScene<'_>,
    hit: &Hit,
    bsdf: &Bsdf,
    light: LightSamples<'_>,
    sampler: &mut Sampler,
) -> Vec3 {
    direct(placed, hit, bsdf, light, sampler, false).total
}

/// What [`estimate_direct_split`] returns: direct light and its Lambertian part.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DirectLight {
    /// All of it: what [`estimate_direct`] returns for the same random numbers.
    pub total: Vec3,
    /// The part reflected by the Lambertian lobe, with its share of the MIS weights;
    /// `total − diffuse` is the specular/glossy part.
    pub diffuse: Vec3,
    /// The part of `total` from the scene's sun ([`plenoptic_scene::Scene::sun`]).
    pub sun: Vec3,
    /// The Lambertian lobe's share of `sun`.
    pub sun_diffuse: Vec3,
    /// The part of `diffuse` from the scene's point and spot lights (the lamps): what a pack
    /// whose lamps are lit at runtime leaves out of the stored lighting.
    pub lamp_diffuse: Vec3,
}

/// [`estimate_direct`] with the Lambertian lobe's share kept apart (the bake's denoiser
/// filters diffuse lighting only). Draws the same random numbers and returns the same total;
/// the split costs a few more BSDF evaluations per light sample.
pub fn estimate_direct_split(
    placed: &PlacedScene<'_>,
    hit: &Hit,
    bsdf: &Bsdf,
    light: LightSamples<'_>,
    sampler: &mut Sampler,
) -> DirectLight {
    direct(placed, hit, bsdf, light, sampler, true)
}

/// The Lambertian part of [`weighted`]`(bsdf, wi, f_all, light_pdf, strategies)` where `lobes`
/// were evaluated: the diffuse BSDF value with the weights of the strategies that contain it.
fn diffuse_part(bsdf: &Bsdf, wi: Vec3, lobes: Lobes, light_pdf: f32, strategies: &[Lobes]) -> Vec3 {
    if lobes == Lobes::Specular {
        return Vec3::ZERO;
    }
    let (f_d, _) = bsdf.eval(wi, Lobes::Diffuse);
    if f_d == Vec3::ZERO {
        return f_d;
    }
    let mut w = 1.0;
    for &l in strategies {
        if l != Lobes::Specular {
            w += power_heuristic(light_pdf, bsdf.eval(wi, l).1) - 1.0;
        }
    }
    f_d * w
}

fn direct(
    placed: &PlacedScene<'_>,
    hit: &Hit,
    bsdf: &Bsdf,
    light: LightSamples<'_>,
    sampler: &mut Sampler,
    split: bool,
) -> DirectLight {
    let LightSamples {
        lobes,
        competing,
        count: samples,
    } = light;
    let scene = placed.scene();
    let lights = placed.lights();
    let n = bsdf.normal();
    let mut total = Vec3::ZERO;
    let mut diffuse = Vec3::ZERO;
    let (mut sun, mut sun_diffuse, mut lamp_diffuse) = (Vec3::ZERO, Vec3::ZERO, Vec3::ZERO);
    for i in 0..lights.punctual_count() {
        let u = if lights.punctual[i].0.angular_radius > 0.0 {
            sampler.next_2d()
        } else {
            Vec2::splat(0.5)
        };
        let Some(ls) = lights.punctual_at(i, hit.position, u) else {
            continue;
        };
        let (f, _) = bsdf.eval(ls.wi, lobes);
        if f == Vec3::ZERO {
            continue;
        }
        let origin = hit.offset_origin(ls.wi);
        if placed.segment_occluded(origin, ls.position) {
            continue;
        }
        let value = f * ls.value * ls.wi.dot(n).abs();
        total += value;
        if split {
            let d = diffuse_part(bsdf, ls.wi, lobes, f32::INFINITY, &[])
                * ls.value
                * ls.wi.dot(n).abs();
            diffuse += d;
            if lights.sun == Some(i) {
                sun += value;
                sun_diffuse += d;
            }
            if lights.is_lamp(i) {
                lamp_diffuse += d;
            }
        }
    }
    if samples > 0 && lights.has_emissive() {
        let (mut sum, mut sum_d) = (Vec3::ZERO, Vec3::ZERO);
        for _ in 0..samples {
            let u_pick = sampler.next_f32();
            let u = sampler.next_2d();
            let Some(ls) = lights.sample_emissive(scene, hit.position, u_pick, u) else {
                continue;
            };
            let (f_all, _) = bsdf.eval(ls.wi, lobes);
            if f_all == Vec3::ZERO || ls.value == Vec3::ZERO {
                continue;
            }
            let f = weighted(bsdf, ls.wi, f_all, ls.pdf, competing.emissive);
            let origin = hit.offset_origin(ls.wi);
            if placed.segment_occluded(origin, ls.position) {
                continue;
            }
            sum += f * ls.value * (ls.wi.dot(n).abs() / ls.pdf);
            if split {
                sum_d += diffuse_part(bsdf, ls.wi, lobes, ls.pdf, competing.emissive)
                    * ls.value
                    * (ls.wi.dot(n).abs() / ls.pdf);
            }
        }
        total += sum / samples as f32;
        diffuse += sum_d / samples as f32;
    }
    if let Some((env_lobes, env_competing)) = competing.environment
        && samples > 0
        && lights.env.can_sample()
    {
        let (mut sum, mut sum_d) = (Vec3::ZERO, Vec3::ZERO);
        for _ in 0..samples {
            let Some(es) = lights.env.sample(sampler.next_2d()) else {
                continue;
            };
            if es.radiance == Vec3::ZERO {
                continue;
            }
            let (f_all, _) = bsdf.eval(es.wi, env_lobes);
            if f_all == Vec3::ZERO {
                continue;
            }
            let f = weighted(bsdf, es.wi, f_all, es.pdf, env_competing);
            let origin = hit.offset_origin(es.wi);
            if placed.occluded(&Ray::new(origin, es.wi)) {
                continue;
            }
            sum += f * es.radiance * (es.wi.dot(n).abs() / es.pdf);
            if split {
                sum_d += diffuse_part(bsdf, es.wi, env_lobes, es.pdf, env_competing)
                    * es.radiance
                    * (es.wi.dot(n).abs() / es.pdf);
            }
        }
        total += sum / samples as f32;
        diffuse += sum_d / samples as f32;
    }
    DirectLight {
        total,
        diffuse,
        sun,
        sun_diffuse,
        lamp_diffuse,
    }
}
