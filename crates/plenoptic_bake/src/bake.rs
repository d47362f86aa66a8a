//! The whole bake: plan, ambient field, range images, temporal volumes, pack; with resume,
//! shards and merge (see [`crate::work`]).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use plenoptic_pack::Manifest;
use plenoptic_scene::Scene;
use plenoptic_scene::recipe::BakeRecipe;
use plenoptic_trace::SceneAccel;

use crate::error::{BakeError, Result};
use crate::groups::Layer;
use crate::plan::{self, Plan};
use crate::progress::Progress;
use crate::render::BakeRenderer;
use crate::work::{ItemChunk, Shard, WorkDir, WorkItem, work_items};
use crate::write::{AssembleOptions, assemble, range_image_chunks, volume_chunks, write_timings};

/// How to run a bake.
#[derive(Debug, Clone)]
pub struct BakeOptions {
    /// Continue from the work directory's finished items instead of starting over.
    pub resume: bool,
    /// Render only this shard's items into the work directory (implies resuming; no pack is
    /// written: `plenoptic merge` assembles it).
    pub shard: Option<Shard>,
    /// Keep the work directory after the pack is written.
    pub keep_work: bool,
    /// Put wall-clock timings into the manifest (else only in `<output>.timings.json`).
    pub timings_in_manifest: bool,
    /// Stop with [`BakeError::Interrupted`] after rendering this many items (tests resuming).
    pub stop_after: Option<usize>,
    /// Progress bars.
    pub progress: Progress,
    /// Write here instead of the recipe's `output`.
    pub output: Option<PathBuf>,
    /// Also store the (x, y, t) Delaunay complex of every volume block.
    pub volume_complex: bool,
}

impl Default for BakeOptions {
    fn default() -> Self {
        Self {
            resume: false,
            shard: None,
            keep_work: false,
            timings_in_manifest: false,
            stop_after: None,
            progress: Progress::hidden(),
            output: None,
            volume_complex: false,
        }
    }
}

/// What a bake did.
#[derive(Debug, Clone)]
pub struct BakeReport {
    /// The pack written (none for a shard).
    pub output: Option<PathBuf>,
    /// The plan.
    pub plan: Plan,
    /// Work items in the plan.
    pub items_total: usize,
    /// Items rendered by this run.
    pub items_rendered: usize,
    /// Items found finished in the work directory.
    pub items_skipped: usize,
    /// Wall-clock seconds per phase.
    pub timings: BTreeMap<String, f64>,
    /// The manifest written (none for a shard).
    pub manifest: Option<Manifest>,
}

/// Renders one work item into its chunks.
pub fn render_item(r: &BakeRenderer<'_>, item: &WorkItem) -> Result<Vec<ItemChunk>> {
    match *item {
        WorkItem::RangeImage { base_view, key } => {
            let image = r.range_image(base_view as usize, key as usize)?;
            range_image_chunks(base_view, key, &image)
        }
        WorkItem::Volume { base_view } => {
            let volume = r.volume(base_view as usize);
            volume_chunks(r.plan, base_view, &volume)
        }
    }
}

/// The output path of a bake.
pub fn output_path(recipe: &BakeRecipe, options: &BakeOptions) -> PathBuf {
    options
        .output
        .clone()
        .unwrap_or_else(|| recipe.output.clone())
}

/// Bakes `recipe` over `scene`: see the crate doc.
pub fn bake(recipe: &BakeRecipe, scene: &Scene, options: &BakeOptions) -> Result<BakeReport> {
    let output = output_path(recipe, options);
    let work = WorkDir::for_output(&output);
    let accel = SceneAccel::new(scene)?;
    let mut timings = BTreeMap::new();
    let progress = options.progress;

    let clock = Instant::now();
    let bar = progress.phase("plan", 0);
    let (mut plan, _) = plan::decompose(recipe, scene, &accel);
    bar.finish_and_clear();
    timings.insert("plan".to_owned(), clock.elapsed().as_secs_f64());

    let clock = Instant::now();
    let bar = progress.phase("ambient field", 0);
    // Light groups: one scene per layer, sharing the plan (crate::groups); the ambient key
    // times are chosen on the sum of the layers' fields, so the whole scene's are not needed.
    let layer_scenes = crate::groups::layer_scenes(scene);
    let layer_accels = layer_scenes
        .iter()
        .map(|(_, s)| SceneAccel::new(s))
        .collect::<std::result::Result<Vec<_>, _>>()?;
    let (fields, layer_fields) = if layer_scenes.is_empty() {
        (plan::ambient_phase(&mut plan, scene, &accel)?, Vec::new())
    } else {
        let layers: Vec<_> = layer_scenes
            .iter()
            .map(|(_, s)| s)
            .zip(&layer_accels)
            .collect();
        (Vec::new(), plan::layered_ambient_phase(&mut plan, &layers)?)
    };
    plan.volume_complex = options.volume_complex;
    bar.finish_and_clear();
    timings.insert("ambient_field".to_owned(), clock.elapsed().as_secs_f64());

    if !options.resume && options.shard.is_none() {
        work.remove()?;
    }
    work.create()?;
    work.check_or_write_plan(&plan)?;

    let items = work_items(&plan);
    let mine: Vec<(usize, WorkItem)> = items
        .iter()
        .copied()
        .enumerate()
        .filter(|(i, _)| options.shard.is_none_or(|s| s.owns(*i)))
        .collect();
    let layers = layer_scenes
        .iter()
        .zip(&layer_accels)
        .zip(&layer_fields)
        .map(|(((group, _), accel), fields)| Layer {
            group: *group,
            stored: crate::groups::is_stored(scene, *group),
            accel,
            fields,
        })
        .collect();
    let renderer = BakeRenderer::new(&plan, &accel, &fields).with_layers(layers);
    let (mut rendered, mut skipped) = (0usize, 0usize);
    for (phase, is_volume) in [("range_images", false), ("volumes", true)] {
        let clock = Instant::now();
        let todo: Vec<&WorkItem> = mine
            .iter()
            .map(|(_, it)| it)
            .filter(|it| matches!(it, WorkItem::Volume { .. }) == is_volume)
            .collect();
        let bar = progress.phase(phase, todo.len() as u64);
        for item in todo {
            if (options.resume || options.shard.is_some()) && work.is_done(item) {
                skipped += 1;
                bar.inc(1);
                continue;
            }
            if options.stop_after.is_some_and(|n| rendered >= n) {
                return Err(BakeError::Interrupted {
                    completed: rendered,
                });
            }
            bar.set_message(item.name());
            let chunks = render_item(&renderer, item)?;
            work.write_item(item, &chunks)?;
            rendered += 1;
            bar.inc(1);
        }
        bar.finish_and_clear();
        timings.insert(phase.to_owned(), clock.elapsed().as_secs_f64());
    }

    if options.shard.is_some() {
        return Ok(BakeReport {
            output: None,
            items_total: items.len(),
            items_rendered: rendered,
            items_skipped: skipped,
            timings,
            manifest: None,
            plan,
        });
    }
    let clock = Instant::now();
    let bar = progress.phase("write", 0);
    let assemble_options = AssembleOptions {
        timings: timings.clone(),
        timings_in_manifest: options.timings_in_manifest,
    };
    let manifest = assemble(&plan, scene, &accel, &work, &output, &assemble_options)?;
    bar.finish_and_clear();
    timings.insert("write".to_owned(), clock.elapsed().as_secs_f64());
    write_timings(&output, &timings)?;
    if !options.keep_work {
        work.remove()?;
    }
    Ok(BakeReport {
        output: Some(output),
        items_total: items.len(),
        items_rendered: rendered,
        items_skipped: skipped,
        timings,
        manifest: Some(manifest),
        plan,
    })
}

/// Joins the shards in the work directory of `recipe`'s output into the pack a single run
/// would have written. Fails, writing nothing, if an item is missing or the work directory's
/// plan is not this recipe's.
pub fn merge(recipe: &BakeRecipe, scene: &Scene, options: &BakeOptions) -> Result<BakeReport> {
    let output = output_path(recipe, options);
    let work = WorkDir::for_output(&output);
    let plan = work.read_plan()?;
    if plan.recipe != recipe.name || plan.quality != recipe.quality {
        return Err(BakeError::WorkDir {
            path: work.path.clone(),
            problem: format!(
                "its plan was made for recipe '{}' with other settings than '{}'",
                plan.recipe, recipe.name
            ),
        });
    }
    let accel = SceneAccel::new(scene)?;
    let clock = Instant::now();
    let manifest = assemble(
        &plan,
        scene,
        &accel,
        &work,
        &output,
        &AssembleOptions::default(),
    )?;
    let mut timings = BTreeMap::new();
    timings.insert("write".to_owned(), clock.elapsed().as_secs_f64());
    if !options.keep_work {
        work.remove()?;
    }
    Ok(BakeReport {
        output: Some(output),
        items_total: work_items(&plan).len(),
        items_rendered: 0,
        items_skipped: 0,
        timings,
        manifest: Some(manifest),
        plan,
    })
}

/// Loads the recipe at `path` and its scenes, then [`bake`]s.
pub fn bake_recipe(path: &Path, options: &BakeOptions) -> Result<BakeReport> {
    let (recipe, scene) = crate::input::load_recipe(path)?;
    bake(&recipe, &scene, options)
}

/// Loads the recipe at `path` and its scenes, then [`merge`]s.
pub fn merge_recipe(path: &Path, options: &BakeOptions) -> Result<BakeReport> {
    let (recipe, scene) = crate::input::load_recipe(path)?;
    merge(&recipe, &scene, options)
}
