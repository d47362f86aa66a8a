//! The environment as a light: radiance for rays that leave the scene, and importance
//! sampling for next-event estimation towards it (docs/architecture.md, "Daylight").
//!
//! The radiance itself is the exact one of [`PlacedEnvironment::radiance`] (the sky's formula
//! or the image's bilinear lookup). Sampling uses a piecewise-constant table over the
//! equirectangular square (`TABLE_WIDTH` × `TABLE_HEIGHT` cells), each cell weighted by the
//! largest luminance at its centre and corners times sin θ, so that no cell where the
//! environment shines has zero density (an estimator without a competing BSDF strategy stays
//! unbiased). A direction's solid-angle density is p(u, v) / (2π² sin θ). The table is built
//! on first use: id-images and placements that never sample the sky do not pay for it.

use std::f32::consts::PI;
use std::sync::OnceLock;

use glam::{Vec2, Vec3};
use plenoptic_scene::PlacedEnvironment;
use plenoptic_sky::{equirect_direction, equirect_uv};

use crate::image::luminance;
use crate::sampling::Distribution1d;

/// Cells of the sampling table across 360°.
pub const TABLE_WIDTH: usize = 256;
/// Cells of the sampling table across 180°.
pub const TABLE_HEIGHT: usize = 128;

/// A sampled direction towards the environment.
#[derive(Debug, Clone, Copy)]
pub struct EnvSample {
    /// Unit direction towards the environment.
    pub wi: Vec3,
    /// Radiance arriving from there.
    pub radiance: Vec3,
    /// Solid-angle density.
    pub pdf: f32,
}

#[derive(Debug)]
struct Table {
    rows: Distribution1d,
    columns: Vec<Distribution1d>,
}

/// The environment at one time, with its sampling table.
#[derive(Debug, Default)]
pub struct EnvLight {
    env: PlacedEnvironment,
    table: OnceLock<Option<Table>>,
}

impl Clone for EnvLight {
    fn clone(&self) -> Self {
        Self::new(self.env.clone())
    }
}

impl EnvLight {
    /// The light of `env`.
    pub fn new(env: PlacedEnvironment) -> Self {
        Self {
            env,
            table: OnceLock::new(),
        }
    }

    /// Whether rays that miss see nothing.
    pub fn is_none(&self) -> bool {
        self.env.is_none()
    }

    /// The environment.
    pub fn environment(&self) -> &PlacedEnvironment {
        &self.env
    }

    /// Radiance arriving from unit direction `dir`.
    pub fn radiance(&self, dir: Vec3) -> Vec3 {
        self.env.radiance(dir)
    }

    fn table(&self) -> Option<&Table> {
        self.table
            .get_or_init(|| {
                if self.env.is_none() {
                    return None;
                }
                let (w, h) = (TABLE_WIDTH, TABLE_HEIGHT);
                let mut columns = Vec::with_capacity(h);
                let mut row_weights = Vec::with_capacity(h);
                for y in 0..h {
                    let v0 = y as f32 / h as f32;
                    let v1 = (y + 1) as f32 / h as f32;
                    // ∫ sin θ dθ over the row, per unit v: the row's share of the sphere.
                    let band = ((v0 * PI).cos() - (v1 * PI).cos()) / (PI * (v1 - v0));
                    let weights: Vec<f32> = (0..w)
                        .map(|x| {
                            let u0 = x as f32 / w as f32;
                            let u1 = (x + 1) as f32 / w as f32;
                            let probes = [
                                Vec2::new(0.5 * (u0 + u1), 0.5 * (v0 + v1)),
                                Vec2::new(u0, v0),
                                Vec2::new(u1, v0),
                                Vec2::new(u0, v1),
                                Vec2::new(u1, v1),
                            ];
                            let peak = probes
                                .iter()
                                .map(|&uv| luminance(self.env.radiance(equirect_direction(uv))))
                                .fold(0.0f32, f32::max);
                            peak * band
                        })
                        .collect();
                    row_weights.push(weights.iter().sum::<f32>());
                    columns.push(Distribution1d::new(weights));
                }
                let rows = Distribution1d::new(row_weights);
                (!rows.is_empty()).then_some(Table { rows, columns })
            })
            .as_ref()
    }

    /// Whether next-event estimation towards the environment can draw a direction.
    pub fn can_sample(&self) -> bool {
        self.table().is_some()
    }

    /// Draws a direction towards the environment by its table.
    pub fn sample(&self, u: Vec2) -> Option<EnvSample> {
        let table = self.table()?;
        let (y, py, ry) = table.rows.sample_remapped(u.y);
        let (x, px, rx) = table.columns[y].sample_remapped(u.x);
        let uv = Vec2::new(
            (x as f32 + rx) / TABLE_WIDTH as f32,
            (y as f32 + ry) / TABLE_HEIGHT as f32,
        );
        let wi = equirect_direction(uv);
        let sin_theta = (uv.y * PI).sin();
        if sin_theta <= 1e-6 {
            return None;
        }
        let density_uv = py * px * (TABLE_WIDTH * TABLE_HEIGHT) as f32;
        Some(EnvSample {
            wi,
            radiance: self.env.radiance(wi),
            pdf: density_uv / (2.0 * PI * PI * sin_theta),
        })
    }

    /// Solid-angle density with which [`EnvLight::sample`] draws unit direction `dir`.
    pub fn pdf(&self, dir: Vec3) -> f32 {
        let Some(table) = self.table() else {
            return 0.0;
        };
        let uv = equirect_uv(dir);
        let sin_theta = (uv.y * PI).sin();
        if sin_theta <= 1e-6 {
            return 0.0;
        }
        let x = ((uv.x * TABLE_WIDTH as f32) as usize).min(TABLE_WIDTH - 1);
        let y = ((uv.y * TABLE_HEIGHT as f32) as usize).min(TABLE_HEIGHT - 1);
        if table.columns[y].is_empty() {
            return 0.0;
        }
        let density_uv =
            table.rows.pmf(y) * table.columns[y].pmf(x) * (TABLE_WIDTH * TABLE_HEIGHT) as f32;
        density_uv / (2.0 * PI * PI * sin_theta)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Sampler;
    use plenoptic_scene::Environment;
    use plenoptic_sky::SkyParams;

    /// E[L(ω) cos θ / p(ω)] over the upper hemisphere must equal the irradiance integral, and
    /// the density must agree with `pdf`.
    #[test]
    fn sampling_is_consistent_with_its_density_and_integrates_the_sky() {
        let sun = Vec3::new(0.5, 0.6, -0.3).normalize();
        let light = EnvLight::new(Environment::Sky(SkyParams::default()).at(Some(sun)));
        let reference = f64::from(luminance(light.environment().horizontal_irradiance(300)));
        let mut s = Sampler::new(1, 2, 3);
        let count = 200_000;
        let mut sum = 0.0f64;
        let mut close = 0;
        for _ in 0..count {
            let Some(e) = light.sample(s.next_2d()) else {
                continue;
            };
            // A direction on a cell's edge may round into its neighbour, whose density
            // differs by its sin θ and its luminance.
            let p = light.pdf(e.wi);
            assert!((p - e.pdf).abs() <= 0.05 * e.pdf, "{p} vs {}", e.pdf);
            if (p - e.pdf).abs() <= 1e-4 * e.pdf {
                close += 1;
            }
            if e.wi.y > 0.0 {
                sum += f64::from(luminance(e.radiance) * e.wi.y / e.pdf);
            }
        }
        assert!(
            close > count * 99 / 100,
            "{close} of {count} densities agree"
        );
        let estimate = sum / count as f64;
        assert!(
            (estimate / reference - 1.0).abs() < 0.01,
            "{estimate} vs {reference}"
        );
    }

    #[test]
    fn a_uniform_environment_is_sampled_uniformly_and_none_not_at_all() {
        let light = EnvLight::new(Environment::Uniform(Vec3::ONE).at(None));
        let want = 1.0 / (4.0 * PI);
        for d in [Vec3::NEG_Z, Vec3::X, Vec3::new(0.2, -0.6, 0.3).normalize()] {
            assert!(
                (light.pdf(d) - want).abs() < 0.03 * want,
                "{}",
                light.pdf(d)
            );
        }
        let none = EnvLight::new(PlacedEnvironment::None);
        assert!(!none.can_sample() && none.sample(Vec2::splat(0.5)).is_none());
        assert_eq!(none.pdf(Vec3::Y), 0.0);
    }
}
