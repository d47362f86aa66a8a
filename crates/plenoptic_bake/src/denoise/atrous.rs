//! The edge-avoiding à-trous wavelet filter of the denoiser (Dammertz, Sewtz, Hanika,
//! Lensch, HPG 2010; variant and guides: [`super`]'s module doc) over a [`LightingCube`].
//!
//! Pass `k` convolves the lighting with the 5 × 5 B3-spline kernel `h = (1, 4, 6, 4, 1)/16`
//! whose taps are `2^k` texels apart, each tap `q` of centre `p` weighted by
//!
//! `h(dx) h(dy) · [id_q = id_p] · max(0, n_p·n_q)^σ_n · exp(−(|n_p·(x_q − x_p)| / (σ_z d_p))²)
//!  · exp(−|ℓ_q − ℓ_p| / (σ_ℓ √var_p + ε))`
//!
//! with `x` the texel's surface point (direction × distance from the base view), `ℓ` the
//! lighting's luminance and `var` its variance: before the first pass the renderer's per-texel
//! variance smoothed over 3 × 3 texels (or, without it, the lighting's spread over 5 × 5),
//! then propagated (`var'_p = Σ w² var_q / (Σ w)²`). Weights are
//! normalised per texel, so a constant lighting stays constant wherever the guides cut.
//! Texels without lighting (misses, black albedo) are left as they are and are never taps.

use glam::Vec3;
use plenoptic_trace::image::luminance;
use rayon::prelude::*;

use super::cube::CubeGrid;
use super::{DenoiseSettings, LightingCube};

/// The B3-spline kernel's 1D weights.
const H: [f32; 5] = [1.0 / 16.0, 1.0 / 4.0, 3.0 / 8.0, 1.0 / 4.0, 1.0 / 16.0];

/// Filters `cube.lighting` in place with `settings` (see the module doc); residual, albedo
/// and guides are not touched.
pub fn denoise(cube: &mut LightingCube, settings: &DenoiseSettings) {
    let grid = CubeGrid::new(cube.face_size);
    denoise_on(cube, &grid, settings);
}

/// [`denoise`] on a precomputed grid of the cube's face size (the grid depends on the size
/// only, so a bake or a benchmark can build it once).
///
/// # Panics
///
/// If the grid's size is not the cube's.
pub fn denoise_on(cube: &mut LightingCube, grid: &CubeGrid, settings: &DenoiseSettings) {
    assert_eq!(grid.len(), cube.len(), "grid and cube sizes differ");
    if settings.passes == 0 || cube.is_empty() {
        return;
    }
    let mut lighting = std::mem::take(&mut cube.lighting);
    let guides = Guides::new(cube, grid, settings);
    let samples = settings.sample_variance.then_some(cube.variance.as_slice());
    let mut var = guides.initial_variance(&lighting, samples);
    for pass in 0..settings.passes.min(16) {
        let step = 1i32 << pass;
        let (l, v): (Vec<Vec3>, Vec<f32>) = (0..lighting.len())
            .into_par_iter()
            .map(|p| guides.filter_texel(p, step, &lighting, &var))
            .unzip();
        lighting = l;
        var = v;
    }
    drop(guides);
    cube.lighting = lighting;
}

/// The guides of one cube, ready for the weights.
struct Guides<'a> {
    grid: &'a CubeGrid,
    object: &'a [u32],
    normal: &'a [Vec3],
    distance: &'a [f32],
    /// Surface point of each filterable texel relative to the base view.
    point: Vec<Vec3>,
    filterable: Vec<bool>,
    sigma_normal: f32,
    sigma_normal_int: Option<i32>,
    inv_sigma_plane: f32,
    sigma_luminance: f32,
}

impl<'a> Guides<'a> {
    fn new(cube: &'a LightingCube, grid: &'a CubeGrid, s: &DenoiseSettings) -> Self {
        // `cube.lighting` is taken out while filtering: count the guides.
        let len = cube.object.len();
        let filterable: Vec<bool> = (0..len).map(|i| cube.filterable(i)).collect();
        let point = (0..len)
            .map(|i| {
                if filterable[i] && cube.distance[i].is_finite() {
                    grid.direction(i) * cube.distance[i]
                } else {
                    Vec3::ZERO
                }
            })
            .collect();
        Self {
            grid,
            object: &cube.object,
            normal: &cube.normal,
            distance: &cube.distance,
            point,
            filterable,
            sigma_normal: s.sigma_normal.max(0.0),
            sigma_normal_int: (s.sigma_normal.fract() == 0.0
                && (0.0..=1024.0).contains(&s.sigma_normal))
            .then_some(s.sigma_normal as i32),
            inv_sigma_plane: 1.0 / s.sigma_plane.max(1e-6),
            sigma_luminance: s.sigma_luminance,
        }
    }

    /// The weight of tap `q` for centre `p` from the guides alone (id, normal, plane
    /// distance); 0 where `q` is not on `p`'s surface.
    fn geometric(&self, p: usize, q: usize) -> f32 {
        if q == p {
            return 1.0;
        }
        if !self.filterable[q] || self.object[q] != self.object[p] {
            return 0.0;
        }
        let np = self.normal[p];
        let cos = np.dot(self.normal[q]).max(0.0);
        if cos <= 0.0 {
            return 0.0;
        }
        // powi (a few multiplications) for the usual integral exponents; powf is ~10× dearer.
        let w_n = match self.sigma_normal_int {
            Some(k) => cos.powi(k),
            None => cos.powf(self.sigma_normal),
        };
        let dp = self.distance[p].max(1e-6);
        let plane = np.dot(self.point[q] - self.point[p]).abs() * self.inv_sigma_plane / dp;
        w_n * (-plane * plane).exp()
    }

    /// The noise estimate of the luminance weight before the first pass: the renderer's
    /// variance smoothed over the 3 × 3 surface neighbourhood (taps weighted by
    /// [`Self::geometric`]) when `samples` is given, else the spread of the lighting's
    /// luminance over the 5 × 5 surface neighbourhood.
    fn initial_variance(&self, lighting: &[Vec3], samples: Option<&[f32]>) -> Vec<f32> {
        if !self.sigma_luminance.is_finite() {
            return vec![0.0; lighting.len()];
        }
        if let Some(var) = samples {
            return (0..lighting.len())
                .into_par_iter()
                .map(|p| {
                    if !self.filterable[p] {
                        return 0.0;
                    }
                    let (face, i, j) = self.grid.coords(p);
                    let (mut sw, mut sv) = (0.0f32, 0.0f32);
                    for (ky, hy) in [0.25f32, 0.5, 0.25].iter().enumerate() {
                        for (kx, hx) in [0.25f32, 0.5, 0.25].iter().enumerate() {
                            let q = self.grid.offset(face, i, j, kx as i32 - 1, ky as i32 - 1);
                            let w = hx * hy * self.geometric(p, q);
                            if w > 0.0 {
                                sw += w;
                                sv += w * var[q];
                            }
                        }
                    }
                    sv / sw
                })
                .collect();
        }
        (0..lighting.len())
            .into_par_iter()
            .map(|p| {
                if !self.filterable[p] {
                    return 0.0;
                }
                let (face, i, j) = self.grid.coords(p);
                let (mut sw, mut s1, mut s2) = (0.0f32, 0.0f32, 0.0f32);
                for dy in -2..=2 {
                    for dx in -2..=2 {
                        let q = self.grid.offset(face, i, j, dx, dy);
                        let w = self.geometric(p, q);
                        if w > 0.0 {
                            let l = luminance(lighting[q]);
                            sw += w;
                            s1 += w * l;
                            s2 += w * l * l;
                        }
                    }
                }
                let mean = s1 / sw;
                (s2 / sw - mean * mean).max(0.0)
            })
            .collect()
    }

    /// One texel of one pass with holes of `step` texels: `(lighting, variance)`.
    fn filter_texel(&self, p: usize, step: i32, lighting: &[Vec3], var: &[f32]) -> (Vec3, f32) {
        if !self.filterable[p] {
            return (lighting[p], var[p]);
        }
        let (face, i, j) = self.grid.coords(p);
        let lp = luminance(lighting[p]);
        let lum_scale = if self.sigma_luminance.is_finite() {
            1.0 / (self.sigma_luminance * var[p].sqrt() + 1e-3 * lp.abs() + 1e-12)
        } else {
            0.0
        };
        let (mut sum, mut sw, mut sv) = (Vec3::ZERO, 0.0f32, 0.0f32);
        for (ky, hy) in H.iter().enumerate() {
            for (kx, hx) in H.iter().enumerate() {
                let (dx, dy) = ((kx as i32 - 2) * step, (ky as i32 - 2) * step);
                let q = self.grid.offset(face, i, j, dx, dy);
                let g = self.geometric(p, q);
                if g <= 0.0 {
                    continue;
                }
                let w_l = if lum_scale > 0.0 {
                    (-(luminance(lighting[q]) - lp).abs() * lum_scale).exp()
                } else {
                    1.0
                };
                let w = hx * hy * g * w_l;
                sum += w * lighting[q];
                sw += w;
                sv += w * w * var[q];
            }
        }
        (sum / sw, sv / (sw * sw))
    }
}
