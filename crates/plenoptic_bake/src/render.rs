//! Rendering the plan (docs/architecture.md Baking steps 6–7): range images at every base view and time
//! key (thesis ch. 6) and temporal volumes per base view (thesis ch. 7), with the multi-stage
//! renderer and the ambient field interpolated linearly in time between its key times.
//!
//! Determinism: every random stream is seeded from the plan's seed, the base view and the
//! time key (range images; the tracer then seeds per texel and sample) or the volume cell
//! (volumes), and results are collected in a fixed order, so the output does not depend on
//! the number of threads.
//!
//! Denoising: with `quality.denoise` the diffuse lighting of every range image is filtered
//! before it is quantised into the pack ([`crate::denoise`]); volume samples are not.
//!
//! Object ids: the pack reserves 0 for "no object", so a scene object `i` is stored as `i + 1`
//! ([`pack_object_id`]). Misses have infinite distance and a zero normal.

use std::collections::HashMap;
use std::sync::{Arc, Mutex};

use glam::Vec3;
use plenoptic_pack::{CubeImage, RangeImage, face_uv_to_direction};
use plenoptic_scene::recipe::Quality;
use plenoptic_scene::{NO_OBJECT, ObjectId, Scene};
use plenoptic_trace::image::luminance;
use plenoptic_trace::sampling::Sampler;
use plenoptic_trace::{
    AmbientField, CubeCamera, MultiStageRenderer, MultiStageSettings, PlacedScene, RadianceSample,
    Ray, SceneAccel,
};
use rayon::prelude::*;

use crate::denoise::{DenoiseSettings, LightingCube, ambient_passes};
use crate::error::Result;
use crate::groups::{Layer, LayeredImage};
use crate::plan::{Plan, ambient::field_at};
use crate::volume::LayeredVolume;

/// The pack's object id of scene object `id` (0 for [`NO_OBJECT`]).
pub fn pack_object_id(id: ObjectId) -> u32 {
    if id == NO_OBJECT { 0 } else { id + 1 }
}

/// A 64-bit mix of the inputs (splitmix64 finaliser over a running hash).
pub fn seed_of(parts: &[u64]) -> u64 {
    let mut h = 0x9e37_79b9_7f4a_7c15u64;
    for &p in parts {
        h ^= p.wrapping_add(0x9e37_79b9_7f4a_7c15).wrapping_add(h << 6);
        h = (h ^ (h >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        h = (h ^ (h >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        h ^= h >> 31;
    }
    h
}

/// Final-gather rays per sample at the first hit (`MultiStageSettings::final_gather`) for
/// range images of face size `n`: the ambient field's interpolation smooths away the
/// darkening of light into corners and under objects, which one bounce traced from the texel
/// resolves (docs/bake-accuracy.md, cause 6). One ray per sample at 256-px faces and above,
/// twice as many per halving below (16 at most): a texel's solid angle quadruples per
/// halving, and the smoothing afterwards ([`LightingCube::smooth_ambient`], two passes or
/// more) spreads the rest. Measured at 64-px faces (`tests/specular.rs`, diffuse pixels'
/// corrected error under the sun / a lamp): the field alone 0.095 / 0.052; 4 rays and 2
/// passes 0.096 / 0.036; 16 rays and 1 pass 0.087 / 0.032 at four times the gather's cost;
/// 1 ray and 3 passes 0.120 / 0.038.
pub fn final_gather_rays(n: u32) -> u32 {
    let halvings = 8u32.saturating_sub(n.max(1).ilog2()).min(4);
    1 << halvings
}

/// The multi-stage renderer's settings the bake renders with at `quality`: `spp` samples per
/// pixel, `final_gather` rays per sample at the first hit, 2 shadow and 2 glossy samples.
pub fn multi_stage_settings(
    quality: &Quality,
    seed: u64,
    spp: u32,
    final_gather: u32,
) -> MultiStageSettings {
    MultiStageSettings {
        samples_per_pixel: spp.max(1),
        shadow_samples: 2,
        glossy_samples: 2,
        max_specular_depth: quality.max_specular_depth,
        seed,
        final_gather,
    }
}

/// Which direct light the stored lighting leaves to the runtime: the sun's (pack 3,
/// `quality.runtime_sun`) and the lamps' diffuse light (pack 5, `quality.runtime_lamps` where
/// every lamp can be placed, [`crate::lights::lamps_at_runtime`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RuntimeLight {
    /// The sun's direct light, through all its lobes.
    pub sun: bool,
    /// The point and spot lights' direct diffuse light.
    pub lamps: bool,
}

impl RuntimeLight {
    /// What `plan` leaves to the runtime for `scene`.
    pub fn of(plan: &Plan, scene: &Scene) -> Self {
        Self {
            sun: plan.quality.runtime_sun,
            lamps: crate::lights::lamps_at_runtime(scene, &plan.quality),
        }
    }

    /// Keeps in `s`'s stored lighting what the runtime does not evaluate: the split
    /// ([`crate::denoise::split_sample`]) then leaves it where the renderer put it.
    pub fn keep_baked(self, s: &mut RadianceSample) {
        if !self.sun {
            s.sun = Vec3::ZERO;
            s.sun_diffuse = Vec3::ZERO;
        }
        if !self.lamps {
            s.lamp_diffuse = Vec3::ZERO;
        }
    }
}

/// Renders range images and volume samples for a plan.
pub struct BakeRenderer<'a> {
    /// The plan.
    pub plan: &'a Plan,
    /// What the stored lighting leaves to the runtime.
    pub runtime: RuntimeLight,
    /// The scene's acceleration structure.
    pub accel: &'a SceneAccel<'a>,
    /// Ambient fields at `plan.ambient_keys`.
    pub fields: &'a [AmbientField],
    /// The light layers rendered instead of the scene when it has light groups
    /// ([`crate::groups`]); empty without.
    layers: Vec<Layer<'a>>,
    /// Per layer (one entry without layers): the field at each distinct volume-sample time.
    cache: Mutex<HashMap<(usize, u32), Arc<AmbientField>>>,
}

/// A volume sample rendered per layer: the total and each declared group's (lighting,
/// non-diffuse radiance).
pub struct LayeredSample {
    /// The sum of the layers (or the scene's own sample without groups).
    pub total: RadianceSample,
    /// `(declared group, [lighting, non-diffuse])`, in group order.
    pub groups: Vec<(u32, [Vec3; 2])>,
}

impl<'a> BakeRenderer<'a> {
    /// A renderer over a plan, its scene's acceleration structure and its ambient fields (at
    /// least one; none when [`BakeRenderer::with_layers`] gives the light layers' own).
    pub fn new(plan: &'a Plan, accel: &'a SceneAccel<'a>, fields: &'a [AmbientField]) -> Self {
        Self {
            plan,
            runtime: RuntimeLight::of(plan, accel.scene()),
            accel,
            fields,
            layers: Vec::new(),
            cache: Mutex::new(HashMap::new()),
        }
    }

    /// Renders `layers` (one per light group, [`crate::groups::layer_scenes`]) instead of
    /// the scene; no layers keeps the scene.
    pub fn with_layers(mut self, layers: Vec<Layer<'a>>) -> Self {
        self.layers = layers;
        self
    }

    /// What is rendered: `(the group whose layer is stored, scene, its fields)` per layer, or
    /// the scene itself.
    fn sources(&self) -> Vec<(Option<u32>, &'a SceneAccel<'a>, &'a [AmbientField])> {
        if self.layers.is_empty() {
            return vec![(None, self.accel, self.fields)];
        }
        self.layers
            .iter()
            .map(|l| (l.group.filter(|_| l.stored), l.accel, l.fields))
            .collect()
    }

    /// The scene.
    pub fn scene(&self) -> &'a Scene {
        self.accel.scene()
    }

    /// The renderer's settings; `final_gather` rays per sample at the first hit.
    fn settings(&self, seed: u64, spp: u32, final_gather: u32) -> MultiStageSettings {
        multi_stage_settings(&self.plan.quality, seed, spp, final_gather)
    }

    /// The range image of base view `bv` at its time key `key`, per light layer.
    pub fn range_image(&self, bv: usize, key: usize) -> Result<LayeredImage> {
        let view = &self.plan.base_views[bv];
        let t = view.time_keys[key];
        let seed = seed_of(&[self.plan.seed, 1, bv as u64, key as u64]);
        let settings = self.settings(
            seed,
            self.plan.quality.samples_per_pixel,
            final_gather_rays(self.plan.quality.range_image_size),
        );
        let n = self.plan.quality.range_image_size.max(1);
        let denoise = self.plan.quality.denoise.then(DenoiseSettings::default);
        let mut images = Vec::new();
        for (group, accel, fields) in self.sources() {
            let field = field_at(&self.plan.ambient_keys, fields, t);
            let renderer = MultiStageRenderer::new(settings, &field);
            let image = render_range_image(
                &renderer,
                &accel.at_time(t),
                view.position,
                n,
                denoise.as_ref(),
                self.runtime,
            )?;
            images.push((group, image));
        }
        let total = crate::groups::sum_images(&images.iter().map(|(_, i)| i).collect::<Vec<_>>())
            .expect("at least one source");
        let groups = images
            .into_iter()
            .filter_map(|(g, image)| g.map(|g| (g, image)))
            .collect();
        Ok(LayeredImage { total, groups })
    }

    /// The ambient field at time `t`, interpolated once per distinct `t` and cached (volume
    /// samples ask at frame times only).
    fn frame_field(&self, layer: usize, fields: &[AmbientField], t: f32) -> Arc<AmbientField> {
        let key = (layer, if fields.len() == 1 { 0 } else { t.to_bits() });
        if let Some(f) = self.cache.lock().ok().and_then(|c| c.get(&key).cloned()) {
            return f;
        }
        let f = Arc::new(field_at(&self.plan.ambient_keys, fields, t).into_owned());
        if let Ok(mut c) = self.cache.lock() {
            c.entry(key).or_insert_with(|| f.clone());
        }
        f
    }

    /// The temporal-volume samples of base view `bv` (empty for a zero budget).
    pub fn volume(&self, bv: usize) -> LayeredVolume {
        let view = &self.plan.base_views[bv];
        let budget = view.volume_samples as usize;
        if budget == 0 {
            return LayeredVolume::default();
        }
        crate::volume::sample_volume(self, bv, budget)
    }

    /// One volume sample along `dir` at time `t` from base view `bv`, per light layer;
    /// `stream` picks the random stream (the same for every layer).
    pub fn sample(&self, bv: usize, dir: Vec3, t: f32, stream: u64) -> LayeredSample {
        let view = &self.plan.base_views[bv];
        // The ambient field changes slowly: evaluate it at the frame nearest to t.
        let frame = if self.plan.frame_rate > 0.0 {
            ((t - self.plan.start) * self.plan.frame_rate).round() / self.plan.frame_rate
                + self.plan.start
        } else {
            t
        };
        let seed = seed_of(&[self.plan.seed, 2, bv as u64]);
        let mut total: Option<RadianceSample> = None;
        let mut groups = Vec::new();
        for (i, (group, accel, fields)) in self.sources().into_iter().enumerate() {
            let field = self.frame_field(i, fields, frame);
            // No final gather: a volume sample is one sample, which nothing smooths
            // afterwards, so it reads the field at its hit as version 1 did.
            let renderer = MultiStageRenderer::new(self.settings(seed, 1, 0), &field);
            let mut sampler = Sampler::new(seed, stream, 0);
            let placed = accel.at_time(t);
            let mut s = renderer.sample(&placed, &Ray::new(view.position, dir), &mut sampler);
            self.runtime.keep_baked(&mut s);
            if let Some(g) = group {
                let (lighting, non_diffuse) = crate::denoise::split_sample(&s);
                groups.push((g, [lighting, non_diffuse]));
            }
            match &mut total {
                Some(sum) => sum.add_light(&s),
                None => total = Some(s),
            }
        }
        LayeredSample {
            total: total.expect("at least one source"),
            groups,
        }
    }
}

/// The range image of face size `n` seen from `position` with `renderer`, its diffuse
/// lighting denoised with `denoise` when given ([`crate::denoise`]); the direct light
/// `runtime` names left out of the lighting and non-diffuse radiance for the runtime.
/// The ambient light is smoothed when the renderer final-gathers
/// ([`LightingCube::smooth_ambient`]). Without either the result is exactly
/// [`to_range_image`] of the rendered faces.
pub fn render_range_image(
    renderer: &MultiStageRenderer<'_>,
    placed: &PlacedScene<'_>,
    position: Vec3,
    n: u32,
    denoise: Option<&DenoiseSettings>,
    runtime: RuntimeLight,
) -> Result<RangeImage> {
    let cube = CubeCamera::new(position, n)?;
    let mut faces = renderer.render_cube(placed, &cube);
    for face in &mut faces {
        face.pixels.iter_mut().for_each(|s| runtime.keep_baked(s));
    }
    let smooth = renderer.settings.final_gather > 0;
    if denoise.is_none() && !smooth {
        return Ok(to_range_image(n, &faces));
    }
    let mut lighting = LightingCube::from_faces(n, &faces);
    if smooth {
        lighting.smooth_ambient(ambient_passes(n));
    }
    if let Some(settings) = denoise {
        // One sample per pixel reports no variance: estimate it from the image.
        let settings = DenoiseSettings {
            sample_variance: settings.sample_variance && renderer.settings.samples_per_pixel >= 2,
            ..*settings
        };
        crate::denoise::denoise(&mut lighting, &settings);
    }
    Ok(lighting.to_range_image())
}

/// Converts six rendered faces (KTX2 layer order, `n`² pixels each) into a range image: the
/// radiance as rendered, split into lighting and non-diffuse radiance for pack v2
/// ([`LightingCube::to_range_image`]).
pub fn to_range_image(n: u32, faces: &[plenoptic_trace::Image<RadianceSample>; 6]) -> RangeImage {
    let mut image = LightingCube::from_faces(n, faces).to_range_image();
    // The radiance exactly as rendered (the split re-modulates it up to rounding).
    let nn = (n * n) as usize;
    image.radiance = CubeImage::from_fn(n, |i, _| {
        faces[i / nn].pixels[i % nn].radiance.max(Vec3::ZERO)
    });
    image
}

/// Whether two samples disagree: different object, or luminance differing by more than
/// `tolerance` relative to the larger.
pub fn disagree(a: &RadianceSample, b: &RadianceSample, tolerance: f32) -> bool {
    if a.object != b.object {
        return true;
    }
    let (la, lb) = (luminance(a.radiance), luminance(b.radiance));
    (la - lb).abs() > tolerance * la.max(lb).max(1e-4)
}

/// The direction at face coordinates `(u, v)` in [0, 1]² of cube face `face`, unit length.
pub fn face_direction(face: usize, u: f32, v: f32) -> Vec3 {
    face_uv_to_direction(face, u, v).normalize()
}

/// Runs `f` over `items` in parallel, results in input order.
pub fn par_map<T: Sync, U: Send>(items: &[T], f: impl Fn(&T) -> U + Sync + Send) -> Vec<U> {
    items.par_iter().map(f).collect()
}
