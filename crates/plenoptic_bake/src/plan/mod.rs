//! The bake plan: the thesis's "recipe" (Nimeroff 1997, ch. 6): where the base views are
//! ([`space`], then moved out of the objects a lattice point falls in by [`clearance`]),
//! which times each one stores ([`time`]), when the ambient field is gathered
//! ([`ambient`]), and how many temporal-volume samples each base view gets. Computed from
//! id-images, first hits (clearance) and, for the ambient keys, irradiance only: no radiance
//! of the range images.
//!
//! A [`Plan`] is plain data (serde JSON). It is a pure function of the recipe and the scene,
//! so every process of a sharded bake computes the same plan, and the work directory keeps a
//! copy to check that a resumed bake or a merge still has the same inputs.

pub mod ambient;
pub mod clearance;
pub mod ids;
pub mod space;
pub mod sunlit;
pub mod time;
pub mod view_keys;

use glam::Vec3;
use plenoptic_scene::Scene;
use plenoptic_scene::recipe::{BakeRecipe, Quality, ViewSpace};
use plenoptic_trace::{AmbientField, SceneAccel};
use serde::{Deserialize, Serialize};

use crate::error::{BakeError, Result};
use crate::input::scene_is_animated;

/// Version of the plan's JSON layout.
pub const PLAN_VERSION: u32 = 1;

/// Default seed of every random stream of a bake.
pub const DEFAULT_SEED: u64 = 0x706c_656e_6f70_7469;

/// The view space as stored in a plan.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum PlanViewSpace {
    /// A segment from `a` to `b`.
    Segment {
        /// One end.
        a: Vec3,
        /// The other end.
        b: Vec3,
    },
    /// A rectangle in x-z at height `y`: `min`/`max` are (x, z).
    Rectangle {
        /// Smallest (x, z).
        min: [f32; 2],
        /// Largest (x, z).
        max: [f32; 2],
        /// Eye height.
        y: f32,
    },
    /// An axis-aligned box.
    Box {
        /// Smallest corner.
        min: Vec3,
        /// Largest corner.
        max: Vec3,
    },
}

impl From<ViewSpace> for PlanViewSpace {
    fn from(v: ViewSpace) -> Self {
        match v {
            ViewSpace::Segment { a, b } => Self::Segment { a, b },
            ViewSpace::Rectangle { min, max, y } => Self::Rectangle {
                min: min.to_array(),
                max: max.to_array(),
                y,
            },
            ViewSpace::Box { min, max } => Self::Box { min, max },
        }
    }
}

/// One base view of the plan.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PlannedView {
    /// Index in the plan (and the pack's base-view index and id).
    pub id: u32,
    /// Lattice coordinates in the view-space subdivision (unused axes 0).
    pub lattice: [u32; 3],
    /// Position, metres.
    pub position: Vec3,
    /// This view's time keys, ascending.
    pub time_keys: Vec<f32>,
    /// Temporal-volume sample budget: the recipe's `temporal_volume_samples` on average over
    /// the base views, in proportion to this view's number of time intervals.
    pub volume_samples: u32,
}

/// Counters of the planning work (deterministic).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct PlanCounters {
    /// View-space cells tested.
    pub space_cells_tested: u64,
    /// View-space cells split.
    pub space_cells_split: u64,
    /// Time intervals tested (lights and views).
    pub time_intervals_tested: u64,
    /// Ambient intervals tested.
    pub ambient_intervals_tested: u64,
    /// Base views moved off their lattice point, out of or away from an object
    /// ([`clearance`]).
    #[serde(default)]
    pub views_moved: u64,
    /// Base views left where they were, crowded, with no clear point around them.
    #[serde(default)]
    pub views_crowded: u64,
}

/// The bake plan. See the module doc.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Plan {
    /// [`PLAN_VERSION`].
    pub version: u32,
    /// The recipe's name.
    pub recipe: String,
    /// The view space.
    pub view_space: PlanViewSpace,
    /// Time range start, seconds.
    pub start: f32,
    /// Time range end, seconds.
    pub end: f32,
    /// Frames per second.
    pub frame_rate: f32,
    /// The quality settings.
    pub quality: Quality,
    /// Whether anything in the scene moves.
    pub animated: bool,
    /// Seed of every random stream.
    pub seed: u64,
    /// View-space lattice steps per axis.
    pub space_lattice: u32,
    /// Time lattice steps.
    pub time_lattice: u32,
    /// Keys from the light pass (shared by every base view).
    pub light_keys: Vec<f32>,
    /// The base views.
    pub base_views: Vec<PlannedView>,
    /// Ambient-field key times.
    pub ambient_keys: Vec<f32>,
    /// Temporal-volume bucket length, seconds.
    pub bucket_span: f32,
    /// Whether each volume block also gets its (x, y, t) Delaunay complex
    /// ([`crate::delaunay3`]); set by the bake's options, not by the recipe.
    #[serde(default)]
    pub volume_complex: bool,
    /// Planning counters.
    pub counters: PlanCounters,
}

/// What a plan will cost to bake.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PlanCost {
    /// Range images (base view × time key).
    pub range_images: u64,
    /// Range-image texels (6·n² per image).
    pub range_image_texels: u64,
    /// Camera samples (texels × samples per pixel).
    pub camera_samples: u64,
    /// Temporal-volume samples.
    pub volume_samples: u64,
    /// Ambient fields gathered.
    pub ambient_fields: u64,
    /// Upper bound of the pack's size before zstd: 16 bytes per texel, 24 per volume sample.
    pub estimated_bytes: u64,
    /// Estimated seconds on this machine: camera and volume samples at about 8 rays each, at
    /// the ray rate measured while planning.
    pub estimated_seconds: f64,
}

impl Plan {
    /// The plan as pretty JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("a plan always serialises")
    }

    /// Parses a plan; `path` names it in errors.
    pub fn from_json(text: &str, path: &std::path::Path) -> Result<Self> {
        serde_json::from_str(text).map_err(|e| BakeError::Json {
            path: path.to_owned(),
            message: e.to_string(),
        })
    }

    /// Total time keys over all base views.
    pub fn time_key_count(&self) -> usize {
        self.base_views.iter().map(|v| v.time_keys.len()).sum()
    }

    /// The expected cost; `rays_per_second` is the tracer's measured rate (0: no time estimate).
    pub fn cost(&self, rays_per_second: f64) -> PlanCost {
        let n = u64::from(self.quality.range_image_size);
        let range_images = self.time_key_count() as u64;
        let texels = range_images * 6 * n * n;
        let camera = texels * u64::from(self.quality.samples_per_pixel.max(1));
        let volume: u64 = self
            .base_views
            .iter()
            .map(|v| u64::from(v.volume_samples))
            .sum();
        let seconds = if rays_per_second > 0.0 {
            (camera + volume) as f64 * 8.0 / rays_per_second
        } else {
            0.0
        };
        PlanCost {
            range_images,
            range_image_texels: texels,
            camera_samples: camera,
            volume_samples: volume,
            ambient_fields: self.ambient_keys.len() as u64,
            estimated_bytes: texels * 16 + volume * 24,
            estimated_seconds: seconds,
        }
    }
}

/// A plan and the ambient fields at its ambient key times (needed by rendering; not stored).
pub struct Planned {
    /// The plan.
    pub plan: Plan,
    /// `fields[i]` is the ambient field at `plan.ambient_keys[i]`.
    pub fields: Vec<AmbientField>,
    /// Rays traced for id-images while planning.
    pub id_rays: u64,
}

/// Bucket length of the temporal volumes: about a sixteenth of the time range, at least one
/// frame; 1 s for an empty range.
pub fn bucket_span(start: f32, end: f32, frame_rate: f32) -> f32 {
    let d = end - start;
    if d <= 0.0 {
        return 1.0;
    }
    let frame = if frame_rate > 0.0 {
        1.0 / frame_rate
    } else {
        d
    };
    (d / 16.0).max(frame).min(d)
}

/// Space and time decomposition only (no ambient field): the plan with empty
/// `ambient_keys`, and the id rays traced.
pub fn decompose(recipe: &BakeRecipe, scene: &Scene, accel: &SceneAccel<'_>) -> (Plan, u64) {
    let q = recipe.quality;
    let (start, end) = (recipe.time.start, recipe.time.end.max(recipe.time.start));
    let animated = scene_is_animated(scene) && end > start;
    let id_size = q.id_image_size.max(1);
    let cube_rays = 6 * u64::from(id_size) * u64::from(id_size);
    let mut rays = 0u64;

    // Space.
    let placed = accel.at_time(start);
    let mut space = space::decompose(&placed, &recipe.view_space, q.q, id_size, q.max_space_depth);
    rays += space.views.len() as u64 * cube_rays;
    let mut counters = PlanCounters {
        space_cells_tested: space.cells_tested,
        space_cells_split: space.cells_split,
        ..Default::default()
    };
    // Views inside or wedged in objects move to a clear point nearby.
    let scenes: Vec<_> =
        clearance::times(start, if animated { end } else { start }, clearance::TIMES)
            .into_iter()
            .map(|t| accel.at_time(t))
            .collect();
    let lattice_points: Vec<Vec3> = space.views.iter().map(|v| v.1).collect();
    for (_, position) in &mut space.views {
        let reach = clearance::reach(
            &recipe.view_space,
            lattice_points.iter().copied(),
            *position,
        );
        match clearance::clear_position(&scenes, &recipe.view_space, reach, *position) {
            Some(p) if p != *position => {
                *position = p;
                counters.views_moved += 1;
            }
            Some(_) => {}
            None => counters.views_crowded += 1,
        }
    }

    // Time: lights, then each base view.
    let time_lattice = 1u32 << q.max_time_depth.min(16);
    let (light_lattice_keys, view_keys): (Vec<u32>, Vec<Vec<u32>>) = if animated {
        let (mut lo, mut hi) = accel.at_time(start).bounds();
        let (b0, b1) = accel.at_time(end).bounds();
        lo = lo.min(b0);
        hi = hi.max(b1);
        let centre = (lo + hi) * 0.5;
        let radius = ((hi - lo).length() * 0.5).max(1e-3);
        let tt = |k| time::key_time(start, end, time_lattice, k);
        let (lk, tested, lv) = time::subdivide(
            &[0, time_lattice],
            |k| ids::light_ids(&accel.at_time(tt(k)), centre, radius, id_size),
            |a, b| ids::min_fitness(a, b) >= f64::from(q.q),
        );
        rays += lv.values().flatten().map(|v| v.len() as u64).sum::<u64>();
        counters.time_intervals_tested += tested;
        // A moving sun whose direct light is baked: each view also follows where the sun
        // falls (see `sunlit`). A runtime sun's patches are the runtime's.
        let clear =
            (scene.sun_is_animated() && !q.runtime_sun).then(|| sunlit::visibility_scene(scene));
        let patches = clear
            .as_ref()
            .and_then(|c| sunlit::SunPatches::new(scene, c));
        let per_view = space
            .views
            .iter()
            .map(|&(_, pos)| {
                let (keys, tested, values) = time::subdivide(
                    &lk,
                    |k| {
                        let placed = accel.at_time(tt(k));
                        let ids = ids::cube_ids(&placed, pos, id_size);
                        let lit = patches.as_ref().map(|p| p.sunlit(&placed, pos, id_size));
                        (ids, lit)
                    },
                    |a, b| {
                        ids::fitness(&[&a.0, &b.0]) >= f64::from(q.q)
                            && match (&a.1, &b.1) {
                                (Some(x), Some(y)) => sunlit::overlap(x, y) >= f64::from(q.q),
                                _ => true,
                            }
                    },
                );
                let per_key = if patches.is_some() { 3 } else { 1 };
                rays += values.len() as u64 * cube_rays * per_key;
                counters.time_intervals_tested += tested;
                keys
            })
            .collect();
        (lk, per_view)
    } else {
        (vec![0], vec![vec![0]; space.views.len()])
    };
    let to_times = |keys: &[u32]| -> Vec<f32> {
        keys.iter()
            .map(|&k| time::key_time(start, end, time_lattice, k))
            .collect()
    };
    // Volume budgets: `temporal_volume_samples` per base view on average, shared in
    // proportion to each view's number of time intervals (views that see more change get
    // more samples, thesis ch. 7: dense in time where the radiance changes); none for a
    // static scene.
    let intervals: Vec<u64> = view_keys
        .iter()
        .map(|k| (k.len() as u64).saturating_sub(1).max(1))
        .collect();
    let total_intervals: u64 = intervals.iter().sum::<u64>().max(1);
    let total_samples = u64::from(q.temporal_volume_samples) * view_keys.len() as u64;
    let base_views = space
        .views
        .iter()
        .zip(&view_keys)
        .zip(&intervals)
        .enumerate()
        .map(|(i, ((&(lattice, position), keys), &n))| PlannedView {
            id: i as u32,
            lattice,
            position,
            time_keys: to_times(keys),
            volume_samples: if animated {
                (total_samples * n / total_intervals).min(u64::from(u32::MAX)) as u32
            } else {
                0
            },
        })
        .collect();
    let plan = Plan {
        version: PLAN_VERSION,
        recipe: recipe.name.clone(),
        view_space: recipe.view_space.into(),
        start,
        end,
        frame_rate: recipe.time.frame_rate,
        quality: q,
        animated,
        seed: DEFAULT_SEED,
        space_lattice: space.lattice,
        time_lattice,
        light_keys: to_times(&light_lattice_keys),
        base_views,
        ambient_keys: Vec::new(),
        bucket_span: bucket_span(start, end, recipe.time.frame_rate),
        volume_complex: false,
        counters,
    };
    (plan, rays)
}

/// The full plan: [`decompose`], then the ambient key times with their fields.
pub fn build(recipe: &BakeRecipe, scene: &Scene, accel: &SceneAccel<'_>) -> Result<Planned> {
    let (mut plan, id_rays) = decompose(recipe, scene, accel);
    let fields = ambient_phase(&mut plan, scene, accel)?;
    Ok(Planned {
        plan,
        fields,
        id_rays,
    })
}

/// The ambient settings of a plan's fields.
fn ambient_settings(plan: &Plan) -> plenoptic_trace::AmbientSettings {
    ambient::field_settings(&plan.quality, plan.seed)
}

/// The plan's time range and ambient subdivision limits.
fn ambient_range(plan: &Plan) -> ambient::KeyRange {
    ambient::KeyRange {
        start: plan.start,
        end: plan.end,
        max_depth: plan.quality.max_time_depth,
        max_rms: plan.quality.ambient_rms,
        animated: plan.animated,
    }
}

/// Fills `plan.ambient_keys` and returns the fields at them.
pub fn ambient_phase(
    plan: &mut Plan,
    scene: &Scene,
    accel: &SceneAccel<'_>,
) -> Result<Vec<AmbientField>> {
    let keys = ambient::key_times(scene, accel, &ambient_settings(plan), ambient_range(plan))?;
    plan.ambient_keys = keys.times;
    plan.counters.ambient_intervals_tested = keys.tested;
    refine_view_keys(plan, accel, &keys.fields);
    Ok(keys.fields)
}

/// [`ambient_phase`] for a scene baked as light layers ([`crate::groups`]): the key times
/// chosen on the sum of the layers' fields; returns each layer's fields at them.
pub fn layered_ambient_phase(
    plan: &mut Plan,
    layers: &[(&Scene, &SceneAccel<'_>)],
) -> Result<Vec<Vec<AmbientField>>> {
    let keys = ambient::layered_key_times(layers, &ambient_settings(plan), ambient_range(plan))?;
    plan.ambient_keys = keys.times;
    plan.counters.ambient_intervals_tested = keys.tested;
    // The whole scene's field is the sum of the layers' (one layout: the sum cannot fail).
    let sums: Option<Vec<AmbientField>> = keys
        .fields
        .iter()
        .map(|layers| AmbientField::sum(layers).and_then(|s| s.ok()))
        .collect();
    if let (Some(sums), Some((_, accel))) = (sums, layers.first()) {
        refine_view_keys(plan, accel, &sums);
    }
    let mut per_layer: Vec<Vec<AmbientField>> = vec![Vec::new(); layers.len()];
    for at_key in keys.fields {
        for (layer, field) in per_layer.iter_mut().zip(at_key) {
            layer.push(field);
        }
    }
    Ok(per_layer)
}

/// Each base view's keys with the ambient key times added where the view's indirect light is
/// not linear between its keys ([`view_keys`]).
fn refine_view_keys(plan: &mut Plan, accel: &SceneAccel<'_>, fields: &[AmbientField]) {
    if !plan.animated || fields.len() != plan.ambient_keys.len() {
        return;
    }
    let times = plan.ambient_keys.clone();
    for view in &mut plan.base_views {
        view.time_keys = view_keys::refine(accel, view.position, &view.time_keys, &times, fields);
    }
}
