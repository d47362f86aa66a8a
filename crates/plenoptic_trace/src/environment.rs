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
//!
//! Building a table costs 164k evaluations of the environment (about 5 ms for a sky). A
//! sky that follows a moving sun changes with time, and the bake places the scene once per
//! temporal-volume sample, each at its own time; so placements share a table built at a
//! nearby time ([`EnvTable`], cached by `SceneAccel` per eighth of a second). Radiance is
//! still the exact one at the placement's time, and the density is the shared table's, so
//! the estimate stays unbiased wherever the table's environment shines where the
//! placement's does (a sky shines over the whole upper hemisphere at every sun position);
//! where the shared table is empty the placement builds its own.

use std::collections::HashMap;
use std::f32::consts::PI;
use std::sync::{Arc, Mutex, OnceLock};

use glam::{Vec2, Vec3};
use plenoptic_scene::{PlacedEnvironment, Scene};
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

/// A sampling table and the environment it is built from (on first use), shareable by the
/// placements of nearby times.
#[derive(Debug, Default)]
pub struct EnvTable {
    env: PlacedEnvironment,
    table: OnceLock<Option<Table>>,
}

impl EnvTable {
    /// The table of `env`, built when first asked for.
    pub fn new(env: PlacedEnvironment) -> Self {
        Self {
            env,
            table: OnceLock::new(),
        }
    }

    fn get(&self) -> Option<&Table> {
        self.table.get_or_init(|| build_table(&self.env)).as_ref()
    }
}

/// Tables shared by the placements of one scene: per eighth of a second for an environment
/// that changes with time, one otherwise. At most [`EnvTableCache::CAPACITY`] are kept
/// (about 0.3 MB each); past that the cache starts again.
#[derive(Debug, Default)]
pub(crate) struct EnvTableCache {
    tables: Mutex<HashMap<i64, Arc<EnvTable>>>,
}

impl Clone for EnvTableCache {
    fn clone(&self) -> Self {
        Self::default()
    }
}

impl EnvTableCache {
    /// Tables kept at most.
    pub const CAPACITY: usize = 128;
    /// Times within one step share a table, seconds.
    pub const STEP: f32 = 0.125;

    /// The light of `scene`'s environment at `t`, drawing by a table shared with nearby
    /// times.
    pub fn light(&self, scene: &Scene, t: f32) -> EnvLight {
        let env = scene.environment_at(t);
        if env.is_none() {
            return EnvLight::new(env);
        }
        let (key, table_time) = if scene.environment_is_animated() {
            let k = (t / Self::STEP).round();
            (k as i64, k * Self::STEP)
        } else {
            (0, t)
        };
        let Ok(mut tables) = self.tables.lock() else {
            return EnvLight::new(env);
        };
        if tables.len() >= Self::CAPACITY && !tables.contains_key(&key) {
            tables.clear();
        }
        let table = tables
            .entry(key)
            .or_insert_with(|| Arc::new(EnvTable::new(scene.environment_at(table_time))))
            .clone();
        EnvLight::with_table(env, table)
    }
}

/// The environment at one time, with its sampling table.
#[derive(Debug, Default)]
pub struct EnvLight {
    env: PlacedEnvironment,
    /// The table of this environment or of one at a nearby time.
    shared: Arc<EnvTable>,
    /// This environment's own table, where the shared one is empty.
    own: OnceLock<Option<Table>>,
}

impl Clone for EnvLight {
    fn clone(&self) -> Self {
        Self::with_table(self.env.clone(), self.shared.clone())
    }
}

impl EnvLight {
    /// The light of `env`, with its own table.
    pub fn new(env: PlacedEnvironment) -> Self {
        let shared = Arc::new(EnvTable::new(env.clone()));
        Self::with_table(env, shared)
    }

    /// The light of `env`, drawing directions by `table` (built from the environment at a
    /// nearby time; see the module docs for why that stays unbiased).
    pub fn with_table(env: PlacedEnvironment, table: Arc<EnvTable>) -> Self {
        Self {
            env,
            shared: table,
            own: OnceLock::new(),
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
        // A black environment has an empty table: building one for every placement to find
        // that out costs 164k evaluations each.
        if self.env.is_black() {
            return None;
        }
        self.shared
            .get()
            .or_else(|| self.own.get_or_init(|| build_table(&self.env)).as_ref())
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

/// The piecewise-constant table of `env` (None when it is black everywhere).
fn build_table(env: &PlacedEnvironment) -> Option<Table> {
    if env.is_none() {
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
                    .map(|&uv| luminance(env.radiance(equirect_direction(uv))))
                    .fold(0.0f32, f32::max);
                peak * band
            })
            .collect();
        row_weights.push(weights.iter().sum::<f32>());
        columns.push(Distribution1d::new(weights));
    }
    let rows = Distribution1d::new(row_weights);
    (!rows.is_empty()).then_some(Table { rows, columns })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Sampler;
    use plenoptic_scene::Environment;
    use plenoptic_sky::SkyParams;

    #[test]
    fn a_black_sky_has_nothing_to_sample_and_builds_no_table() {
        let sky = Environment::Sky(SkyParams::default()).at(Some(Vec3::new(0.3, 0.8, 0.2)));
        assert!(EnvLight::new(sky.clone()).can_sample());
        for black in [
            sky.scaled(Vec3::ZERO),
            PlacedEnvironment::Uniform(Vec3::ZERO),
        ] {
            assert!(black.is_black());
            let light = EnvLight::new(black);
            assert!(!light.can_sample());
            assert!(light.own.get().is_none(), "no table built for a black sky");
            assert_eq!(light.pdf(Vec3::Y), 0.0);
        }
    }

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

    /// A table built for the sun at another position (as `SceneAccel` shares them between
    /// nearby times) still integrates this sky: the density is the table's, the radiance
    /// this environment's own.
    #[test]
    fn a_table_of_a_nearby_time_still_integrates_the_sky() {
        let sun = Vec3::new(0.5, 0.6, -0.3).normalize();
        let elsewhere = Vec3::new(-0.2, 0.3, 0.8).normalize();
        let sky = Environment::Sky(SkyParams::default());
        let table = Arc::new(EnvTable::new(sky.at(Some(elsewhere))));
        let light = EnvLight::with_table(sky.at(Some(sun)), table);
        let reference = f64::from(luminance(light.environment().horizontal_irradiance(300)));
        let mut s = Sampler::new(4, 5, 6);
        let count = 400_000;
        let mut sum = 0.0f64;
        for _ in 0..count {
            if let Some(e) = light.sample(s.next_2d())
                && e.wi.y > 0.0
            {
                sum += f64::from(luminance(e.radiance) * e.wi.y / e.pdf);
            }
        }
        let estimate = sum / count as f64;
        assert!(
            (estimate / reference - 1.0).abs() < 0.02,
            "{estimate} vs {reference}"
        );
    }

    #[test]
    fn a_moving_sky_shares_tables_by_the_step_and_a_still_one_has_one() {
        use plenoptic_scene::builder::{LightDesc, MaterialDesc, NodeDesc, SceneBuilder, shapes};
        use plenoptic_scene::{Sun, Trs};
        use plenoptic_sky::{SunTrack, SunTrackSample};
        let mut b = SceneBuilder::new();
        let m = b.add_material(MaterialDesc::diffuse(Vec3::splat(0.5)));
        b.add_object("floor", shapes::cuboid(Vec3::ONE), m, Trs::default());
        b.add_node(NodeDesc::new("Sun").light(LightDesc::directional(Vec3::ONE, 1.0)));
        let mut scene = b.build_scene().unwrap();
        scene.environment = Environment::Sky(SkyParams::default());
        let still = EnvTableCache::default();
        scene.sun = Some(Sun {
            light: 0,
            track: None,
        });
        let (a, b2) = (still.light(&scene, 0.0), still.light(&scene, 5.0));
        assert!(
            Arc::ptr_eq(&a.shared, &b2.shared),
            "one table for a still sky"
        );
        let sample = |time: f32, x: f32| SunTrackSample {
            time,
            direction: Vec3::new(x, 1.0, 0.2).normalize(),
            illuminance: Vec3::ONE,
        };
        let track = SunTrack::new(vec![sample(0.0, -0.5), sample(10.0, 0.5)]).unwrap();
        scene.sun = Some(Sun {
            light: 0,
            track: Some(track),
        });
        let moving = EnvTableCache::default();
        let (a, b2, c) = (
            moving.light(&scene, 1.0),
            moving.light(&scene, 1.0 + 0.4 * EnvTableCache::STEP),
            moving.light(&scene, 1.0 + 2.0 * EnvTableCache::STEP),
        );
        assert!(
            Arc::ptr_eq(&a.shared, &b2.shared),
            "times within a step share"
        );
        assert!(
            !Arc::ptr_eq(&a.shared, &c.shared),
            "times steps apart do not"
        );
        // Each keeps its own time's radiance.
        let d = Vec3::new(0.3, 0.5, 0.1).normalize();
        assert_ne!(a.radiance(d), c.radiance(d));
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
