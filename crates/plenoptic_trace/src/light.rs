//! Lights at one time: emissive triangles in world space with a distribution by area ×
//! luminance, the punctual lights placed, and next-event estimation with multiple importance
//! sampling (power heuristic).

use glam::{Vec2, Vec3};
use plenoptic_scene::{AlphaMode, Light, LightKind, ObjectId, PlacedLight, Scene};
use std::collections::HashMap;

use crate::accel::{Hit, Instance, PlacedScene};
use crate::alpha::coverage;
use crate::image::luminance;
use crate::material::{Bsdf, Lobes};
use crate::sampling::{Distribution1d, Sampler, power_heuristic, uniform_triangle};
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
}

impl LightSet {
    pub(crate) fn new(scene: &Scene, t: f32, instances: &[Instance]) -> Self {
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
        }
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
    /// directional ones); `None` outside a spot cone or beyond the range.
    pub fn punctual_at(&self, i: usize, p: Vec3) -> Option<LightSample> {
        let (light, placed) = &self.punctual[i];
        let radiant = light.color * light.intensity;
        match light.kind {
            LightKind::Directional => Some(LightSample {
                wi: -placed.direction,
                distance: f32::INFINITY,
                value: radiant,
                pdf: f32::INFINITY,
                position: p - placed.direction * 1e9,
            }),
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

/// Direct light reflected by `bsdf` at `hit` towards its `wo`: every punctual light once plus
/// `emissive_samples` samples of the emissive triangles, each shadow-tested.
///
/// `lobes` selects the part of the BSDF evaluated. `mis_lobes` (a subset of `lobes`) names the lobes whose BSDF sampling also finds emitters (the caller adds the
/// emission it hits with [`power_heuristic`]`(bsdf_pdf, light_pdf)`): the part of the BSDF in
/// those lobes is weighted by the power heuristic, the rest counts fully. `None`: no lobe
/// competes.
pub fn estimate_direct(
    placed: &PlacedScene<'_>,
    hit: &Hit,
    bsdf: &Bsdf,
    lobes: Lobes,
    mis_lobes: Option<Lobes>,
    emissive_samples: u32,
    sampler: &mut Sampler,
) -> Vec3 {
    let scene = placed.scene();
    let lights = placed.lights();
    let n = bsdf.normal();
    let mut total = Vec3::ZERO;
    for i in 0..lights.punctual_count() {
        let Some(ls) = lights.punctual_at(i, hit.position) else {
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
        total += f * ls.value * ls.wi.dot(n).abs();
    }
    if emissive_samples > 0 && lights.has_emissive() {
        let mut sum = Vec3::ZERO;
        for _ in 0..emissive_samples {
            let u_pick = sampler.next_f32();
            let u = sampler.next_2d();
            let Some(ls) = lights.sample_emissive(scene, hit.position, u_pick, u) else {
                continue;
            };
            let (f_all, _) = bsdf.eval(ls.wi, lobes);
            if f_all == Vec3::ZERO || ls.value == Vec3::ZERO {
                continue;
            }
            let f = match mis_lobes {
                None => f_all,
                Some(l) => {
                    let (f_c, p_c) = bsdf.eval(ls.wi, l);
                    (f_all - f_c) + f_c * power_heuristic(ls.pdf, p_c)
                }
            };
            let origin = hit.offset_origin(ls.wi);
            if placed.segment_occluded(origin, ls.position) {
                continue;
            }
            sum += f * ls.value * (ls.wi.dot(n).abs() / ls.pdf);
        }
        total += sum / emissive_samples as f32;
    }
    total
}
