//! Denoising of the baked lighting before quantisation (docs/architecture.md, "Pack v2:
//! lighting from the pack, detail from the geometry": the diffuse lighting per texel,
//! "denoised in the bake (edge-aware, guided by id, normal and distance, continuous across
//! cube seams)"; thesis ch. 8, separating illumination quality from image quality).
//!
//! # What is filtered
//!
//! A range-image texel's radiance is split by the multi-stage renderer
//! ([`plenoptic_trace::RadianceSample::diffuse`], [`plenoptic_trace::RadianceSample::albedo`])
//! into a [`LightingCube`]:
//!
//! `radiance = albedo ⊙ lighting + residual + direct + emission`
//!
//! - `lighting`: the first hit's diffuse lighting, diffuse radiance / diffuse albedo per
//!   channel (demodulated: textures are divided out, so filtering it does not blur them). This
//!   is the only part filtered.
//! - `albedo`: `(1 − metallic)(1 − transmission) · base colour`, mean over the texel's samples.
//! - `residual`: the specular/view-dependent part (glossy and mirror reflections,
//!   refraction, the environment seen directly) and the diffuse radiance of channels whose
//!   albedo is below [`MIN_ALBEDO`]. Not filtered: a reflection's detail is geometry seen in
//!   another direction, not noise, and guides of the first hit cannot tell its edges.
//!
//! - `direct`: the first hit's direct light left to the runtime (shadow rays against the
//!   proxies at screen resolution): the scene's sun's through all lobes (pack 3) and the
//!   lamps' through the Lambertian lobe (pack 5's runtime lamps). It is taken out of the
//!   lighting and the residual before anything else, so the filter never sees sun-shadow
//!   edges, and added back only into the radiance (image and volume modes warp that).
//! - `emission`: what the first hit emits towards the ray, which pack 4 leaves to the runtime
//!   (the material's emissive factor × texture at each pixel's UV, at screen resolution
//!   instead of the cube's). Taken out with the sun, added back only into the radiance.
//!
//! This record is pack v2's "lighting apart from reflectance": the pack can store `lighting`
//! (and `residual` as the view-dependent part) and the runtime multiply by `albedo(uv)`.
//!
//! # The filter
//!
//! Edge-avoiding à-trous wavelet transform: H. Dammertz, D. Sewtz, J. Hanika, H. P. A. Lensch,
//! "Edge-Avoiding À-Trous Wavelet Transform for fast Global Illumination Filtering", HPG 2010
//! ([`atrous`]). Passes of a 5 × 5 B3-spline kernel with holes (step 1, 2, 4, …), each tap
//! weighted by edge-stopping functions of the guides. Variant, and why:
//!
//! - Guides: the object id (taps on another object have weight 0), the normal
//!   (`max(0, n_p·n_q)^σ_n`) and the distance, as the distance of the tap's surface point from
//!   the tangent plane at the centre texel relative to the centre's distance (a plane seen at
//!   a grazing angle keeps its weights; a depth step on one object is cut). Dammertz et al.
//!   used world position and normal; the plane distance is the cube's equivalent that does not
//!   depend on how far the surface is.
//! - Luminance: instead of Dammertz et al.'s colour weight with a σ halved every pass, the
//!   luminance weight of SVGF (Schied et al., "Spatiotemporal Variance-Guided Filtering", HPG
//!   2017): `exp(−|ℓ_p − ℓ_q| / (σ_ℓ √var_p))`, with the variance of the texel's samples from
//!   the renderer ([`RadianceSample::lighting_variance`]) smoothed over its 3 × 3 surface
//!   neighbourhood, and carried through the passes (`var' = Σ w² var / (Σ w)²`). It keeps
//!   shadow edges that are well above the noise: a sun shadow's edge is sharp and noise-free
//!   in every sample, so it is not averaged away. With one sample per pixel the variance is
//!   estimated from the lighting's spread over 5 × 5 texels instead, which counts such edges
//!   as noise (measured: it blurs the sunlit floor's shadow edges). `σ_ℓ = ∞` turns the
//!   weight off, and then every weight depends on the guides alone.
//! - Seams: taps are addressed through their direction ([`cube::CubeGrid::offset`]), so the
//!   footprint crosses face edges as if the cube were one surface.
//! - Time keys: for static geometry the guides (id, normal, distance of the pixel-centre ray)
//!   are identical at every key of a base view, so the geometric weights are too, and the
//!   independent noise of two keys is averaged over the same footprints: their difference
//!   shrinks with their noise (flicker). A temporal term across keys is not part of this:
//!   range images are rendered as independent work items (resumable, shardable), and the
//!   spatial filter already gives the consistency above.
//!
//! Each pass runs in parallel over texels (rayon) and is deterministic whatever the thread
//! count. Cost: `25 · passes` taps per texel; see `benches/bake.rs` (`denoise`).

pub mod atrous;
pub mod cube;
#[cfg(test)]
mod tests;

use glam::Vec3;
use plenoptic_pack::{CubeImage, RangeImage};
use plenoptic_trace::{Image, RadianceSample};
use serde::{Deserialize, Serialize};

use crate::render::pack_object_id;
use cube::CubeGrid;

pub use atrous::denoise;

/// Albedo channels below this are not demodulated: their diffuse radiance goes to the
/// residual, unfiltered (dividing by a near-zero albedo would amplify noise without bound).
pub const MIN_ALBEDO: f32 = 1e-3;

/// Settings of the denoiser.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct DenoiseSettings {
    /// À-trous passes; pass `k` uses holes of `2^k` texels, so the footprint's radius is
    /// `2·(2^passes − 1)` texels. Cost is linear in it.
    pub passes: u32,
    /// Exponent of the normal weight `max(0, n_p·n_q)^σ_n`.
    pub sigma_normal: f32,
    /// Scale of the plane-distance weight, relative to the centre texel's distance:
    /// `exp(−(|n_p·(x_q − x_p)| / (σ_z d_p))²)`.
    pub sigma_plane: f32,
    /// Scale of the luminance weight in standard deviations of the noise; infinite turns
    /// the luminance weight off (weights from the guides alone).
    pub sigma_luminance: f32,
    /// Take the noise from the renderer's per-texel variance ([`LightingCube::variance`],
    /// which needs two or more samples per pixel), smoothed over the 3 × 3 surface
    /// neighbourhood; else estimate it from the spread of the lighting over the 5 × 5
    /// neighbourhood (which also counts real edges such as shadow boundaries as noise, and
    /// so blurs them).
    pub sample_variance: bool,
}

impl Default for DenoiseSettings {
    fn default() -> Self {
        Self {
            passes: 5,
            sigma_normal: 128.0,
            sigma_plane: 0.02,
            sigma_luminance: 4.0,
            sample_variance: true,
        }
    }
}

/// A cube of per-texel lighting records with their guides (see the module doc):
/// `radiance = albedo ⊙ lighting + residual`.
#[derive(Debug, Clone, PartialEq)]
pub struct LightingCube {
    /// Texels per face edge.
    pub face_size: u32,
    /// Diffuse lighting (demodulated diffuse radiance); the part the denoiser filters.
    pub lighting: Vec<Vec3>,
    /// The ambient share of `lighting` (indirect light from the ambient field or its final
    /// gather, demodulated like it): what [`Self::smooth_ambient`] filters.
    pub ambient: Vec<Vec3>,
    /// Diffuse albedo.
    pub albedo: Vec<Vec3>,
    /// The specular/view-dependent part and undemodulated diffuse radiance.
    pub residual: Vec<Vec3>,
    /// The first hit's direct light left to the runtime: the sun's, the lamps' diffuse light
    /// (see the module doc).
    pub direct: Vec<Vec3>,
    /// The first hit's emission, left to the runtime (pack 4: the material's emission at
    /// the pixel's own UV).
    pub emission: Vec<Vec3>,
    /// Distance along the texel's centre ray; infinite for a miss.
    pub distance: Vec<f32>,
    /// Pack object id (0: none).
    pub object: Vec<u32>,
    /// Shading normal facing the ray; zero for a miss.
    pub normal: Vec<Vec3>,
    /// The renderer's variance of the lighting's luminance
    /// ([`RadianceSample::lighting_variance`]); zero where unknown.
    pub variance: Vec<f32>,
}

impl LightingCube {
    /// Splits six rendered faces (KTX2 layer order, `n`² pixels each) into records.
    pub fn from_faces(n: u32, faces: &[Image<RadianceSample>; 6]) -> Self {
        let nn = (n * n) as usize;
        let samples = || (0..6 * nn).map(|i| &faces[i / nn].pixels[i % nn]);
        Self::from_samples(n, samples())
    }

    /// Splits `6·n²` samples in cube order into records.
    pub fn from_samples<'s>(n: u32, samples: impl Iterator<Item = &'s RadianceSample>) -> Self {
        let mut c = Self {
            face_size: n,
            lighting: Vec::new(),
            ambient: Vec::new(),
            albedo: Vec::new(),
            residual: Vec::new(),
            direct: Vec::new(),
            emission: Vec::new(),
            distance: Vec::new(),
            object: Vec::new(),
            normal: Vec::new(),
            variance: Vec::new(),
        };
        for s in samples {
            let Split {
                lighting,
                ambient,
                albedo,
                residual,
                direct,
                emission,
            } = split(s);
            c.lighting.push(lighting);
            c.ambient.push(ambient);
            c.albedo.push(albedo);
            c.residual.push(residual);
            c.direct.push(direct);
            c.emission.push(emission);
            c.distance.push(s.distance);
            c.object.push(pack_object_id(s.object));
            c.normal.push(s.normal);
            c.variance.push(s.lighting_variance);
        }
        c
    }

    /// Number of texels.
    pub fn len(&self) -> usize {
        self.lighting.len()
    }

    /// Whether there are no texels.
    pub fn is_empty(&self) -> bool {
        self.lighting.is_empty()
    }

    /// Whether texel `i` has lighting to filter: a hit with some albedo.
    pub fn filterable(&self, i: usize) -> bool {
        self.object[i] != 0 && self.albedo[i].max_element() > MIN_ALBEDO
    }

    /// Radiance of texel `i`: `albedo ⊙ lighting + residual + direct + emission`, never
    /// negative.
    pub fn radiance(&self, i: usize) -> Vec3 {
        (self.albedo[i] * self.lighting[i] + self.residual[i] + self.direct[i] + self.emission[i])
            .max(Vec3::ZERO)
    }

    /// The range image of the records (pack v2): radiance re-modulated, the lighting with
    /// [`Self::filled_lighting`] applied, the residual as the non-diffuse part, the guides as
    /// they are.
    pub fn to_range_image(&self) -> RangeImage {
        let n = self.face_size;
        let lighting = self.filled_lighting();
        RangeImage {
            radiance: CubeImage::from_fn(n, |i, _| self.radiance(i)),
            lighting: CubeImage {
                face_size: n,
                texels: lighting,
            },
            non_diffuse: CubeImage {
                face_size: n,
                texels: self.clamped_residual(),
            },
            distance: CubeImage::from_fn(n, |i, _| self.distance[i]),
            object_id: CubeImage::from_fn(n, |i, _| self.object[i]),
            normal: CubeImage::from_fn(n, |i, _| self.normal[i]),
        }
    }

    /// The lighting, where texels of an object without diffuse albedo (black, metal, clear
    /// glass) take the mean lighting of their filterable 8-neighbours on the same object,
    /// grown ring by ring ([`FILL_RINGS`] at most; then zero). The runtime filters the lighting
    /// bilinearly and multiplies it by the albedo at the pixel, which may be bright where the
    /// texel centre was dark (a grout line, a dark fleck in a texture); a zero there would
    /// darken its neighbours.
    pub fn filled_lighting(&self) -> Vec<Vec3> {
        let grid = CubeGrid::new(self.face_size);
        let mut lighting = self.lighting.clone();
        let mut known: Vec<bool> = (0..self.len()).map(|i| self.filterable(i)).collect();
        for _ in 0..FILL_RINGS {
            let mut grown = Vec::new();
            for i in 0..self.len() {
                if known[i] || self.object[i] == 0 {
                    continue;
                }
                let (face, x, y) = grid.coords(i);
                let (mut sum, mut count) = (Vec3::ZERO, 0u32);
                for dj in -1..=1 {
                    for di in -1..=1 {
                        let q = grid.offset(face, x, y, di, dj);
                        if q != i && known[q] && self.object[q] == self.object[i] {
                            sum += lighting[q];
                            count += 1;
                        }
                    }
                }
                if count > 0 {
                    grown.push((i, sum / count as f32));
                }
            }
            if grown.is_empty() {
                break;
            }
            for (i, l) in grown {
                lighting[i] = l;
                known[i] = true;
            }
        }
        lighting
    }
}

/// À-trous passes of [`LightingCube::smooth_ambient`] in the bake for faces of `n` texels:
/// 3 at 256 (a footprint of 14 texels' radius, about 5°), one more per doubling (2 to 5
/// passes), so that the footprint covers about the same angle at large faces; at 128 px and
/// below 2 passes, where the bake traces more gather rays per sample
/// (`crate::render::final_gather_rays`).
pub fn ambient_passes(n: u32) -> u32 {
    let octaves = n.max(1).ilog2() as i32 - 8;
    (3 + octaves).clamp(2, 5) as u32
}

impl LightingCube {
    /// Smooths the ambient share of the lighting with the à-trous filter guided by id,
    /// normal and distance alone (no luminance weight), and puts it back into the lighting.
    ///
    /// A final gather (`plenoptic_trace::AmbientField::irradiance_gathered`) traces one ray
    /// per sample from each texel: unbiased where the field's interpolation is not (corners,
    /// the floor under an object), but noisy. Indirect light varies slowly along a surface,
    /// and the guides stop the filter at creases and depth steps, where it does change.
    /// Without a luminance weight the filter is linear in the lighting, so it does not move
    /// the mean: a luminance weight rejects the rare bright samples of a skewed noise and
    /// darkens it (measured on the tour with the default settings: 0.93–0.95 of the mean).
    /// Direct light is not touched, so lamp shadows keep their edges.
    pub fn smooth_ambient(&mut self, passes: u32) {
        let before = self.ambient.clone();
        std::mem::swap(&mut self.lighting, &mut self.ambient);
        let settings = DenoiseSettings {
            passes,
            sigma_luminance: f32::INFINITY,
            sample_variance: false,
            ..DenoiseSettings::default()
        };
        denoise(self, &settings);
        std::mem::swap(&mut self.lighting, &mut self.ambient);
        for ((l, a), b) in self.lighting.iter_mut().zip(&self.ambient).zip(&before) {
            *l = (*l - *b + *a).max(Vec3::ZERO);
        }
    }
}

/// Most rings [`LightingCube::filled_lighting`] grows the known lighting by.
pub const FILL_RINGS: usize = 8;

/// How far above the brightest of its same-object 3 × 3 neighbours a texel's non-diffuse
/// luminance may be before [`LightingCube::clamped_residual`] scales it down.
pub const FIREFLY_RATIO: f32 = 4.0;

impl LightingCube {
    /// The residual (emission and the specular part, never negative) with fireflies clamped:
    /// a texel whose luminance is more than [`FIREFLY_RATIO`] times that of the brightest of
    /// its same-object 8-neighbours is scaled down to that, keeping its colour. A few glossy
    /// samples per texel find a bright window or sun patch rarely, and such a texel shows at
    /// runtime as a speck the size of a cube texel; a highlight that spans two neighbouring
    /// texels or more (a mirror's reflection, a lamp) is kept. The radiance keeps the
    /// unclamped value.
    pub fn clamped_residual(&self) -> Vec<Vec3> {
        let grid = CubeGrid::new(self.face_size);
        let lum = |c: Vec3| 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z;
        (0..self.len())
            .map(|i| {
                let r = self.residual[i].max(Vec3::ZERO);
                let l = lum(r);
                if self.object[i] == 0 || l <= 0.0 {
                    return r;
                }
                let (face, x, y) = grid.coords(i);
                let (mut brightest, mut count) = (0.0f32, 0);
                for dj in -1..=1 {
                    for di in -1..=1 {
                        let q = grid.offset(face, x, y, di, dj);
                        if q != i && self.object[q] == self.object[i] {
                            brightest = brightest.max(lum(self.residual[q].max(Vec3::ZERO)));
                            count += 1;
                        }
                    }
                }
                if count < 3 {
                    return r;
                }
                let limit = FIREFLY_RATIO * brightest;
                if l > limit { r * (limit / l) } else { r }
            })
            .collect()
    }
}

/// `(lighting, non-diffuse)` of a volume sample, as a range image's texel stores them: the
/// sun's direct light, the lamps' direct diffuse light and the emission left out (all for the
/// runtime; what the bake keeps is zeroed first, `RuntimeLight::keep_baked`).
pub fn split_sample(s: &RadianceSample) -> (Vec3, Vec3) {
    let split = split(s);
    (split.lighting, split.residual.max(Vec3::ZERO))
}

/// A rendered sample taken apart: `radiance = albedo ⊙ lighting + residual + direct +
/// emission`.
struct Split {
    lighting: Vec3,
    /// The ambient share of `lighting`.
    ambient: Vec3,
    albedo: Vec3,
    residual: Vec3,
    /// The direct light left to the runtime: the sun's and the lamps' diffuse light.
    direct: Vec3,
    emission: Vec3,
}

/// [`Split`] of a rendered sample: the sun's direct light, the lamps' direct diffuse light and
/// the emission are taken out first (clamped so that nothing goes negative), then the rest
/// of the Lambertian part is demodulated by the albedo.
fn split(s: &RadianceSample) -> Split {
    let radiance = s.radiance.max(Vec3::ZERO);
    let sun = s.sun.max(Vec3::ZERO).min(radiance);
    let sun_diffuse = s.sun_diffuse.max(Vec3::ZERO).min(sun);
    let radiance = radiance - sun;
    let lamps = s.lamp_diffuse.max(Vec3::ZERO).min(radiance);
    let radiance = radiance - lamps;
    let emission = s.emission.max(Vec3::ZERO).min(radiance);
    let radiance = radiance - emission;
    let albedo = s.albedo;
    let diffuse = (s.diffuse - sun_diffuse - lamps)
        .max(Vec3::ZERO)
        .min(radiance);
    let mut lighting = Vec3::ZERO;
    let mut ambient = Vec3::ZERO;
    let mut kept = Vec3::ZERO;
    for c in 0..3 {
        if albedo[c] > MIN_ALBEDO {
            lighting[c] = diffuse[c] / albedo[c];
            ambient[c] = (s.ambient[c].max(0.0) / albedo[c]).min(lighting[c]);
            kept[c] = diffuse[c];
        }
    }
    // What is not demodulated stays in the residual, so radiance is exactly recovered.
    let albedo = Vec3::select(albedo.cmpgt(Vec3::splat(MIN_ALBEDO)), albedo, Vec3::ZERO);
    Split {
        lighting,
        ambient,
        albedo,
        residual: radiance - kept,
        direct: sun + lamps,
        emission,
    }
}
