//! The `plenoptic` command: plan, bake, merge, inspect and reference-render radiance packs.
//!
//! ```text
//! plenoptic plan RECIPE [--out PLAN.json]          print the plan and its cost, write the plan
//! plenoptic bake RECIPE [--resume] [--shard i/N] [--keep-work] [--timings-in-manifest] [-q]
//! plenoptic merge RECIPE [--keep-work]              join shards into the pack
//! plenoptic inspect PACK [--chunks] [--extract N OUT]
//! plenoptic reference RECIPE --path PATH.json --out DIR [--spp N] [--seed S] [--halves]
//!                    [--exposure E] [--light NAME=I]... [--frames N]
//! plenoptic render PACK --path PATH.json [--mode image|volume|geometry]
//!     [--shading materials|radiance] [--reflections shaded|marched] [--supersampling N]
//!     [--frames N] [--exposure E] [--light NAME=I]... --out DIR
//! plenoptic compare --reference DIR [--reference-b DIR_B] [LABEL=]DIR... [--csv OUT.csv]
//!                   [--plot OUT.svg] [--maps DIR]
//! ```
//!
//! Variance-corrected comparison: `plenoptic reference … --out ref --halves` renders two
//! independent halves (`ref` and `ref_b`, half the samples each, different seeds); then
//! `plenoptic compare --reference ref --reference-b ref_b …` compares against their mean and
//! subtracts the reference's estimated variance (`plenoptic_eval::metrics`).

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use clap::{Parser, Subcommand};
use plenoptic_bake::progress::Progress;
use plenoptic_bake::{BakeError, BakeOptions, Result, Shard, plan};
use plenoptic_pack::PackReader;
use plenoptic_trace::SceneAccel;

/// `println!` that ends the program quietly when standard output is closed (`plenoptic
/// inspect pack --chunks | head`), where `println!` would panic.
macro_rules! out {
    ($($t:tt)*) => {{
        use std::io::Write as _;
        if let Err(e) = writeln!(std::io::stdout(), $($t)*)
            && e.kind() == std::io::ErrorKind::BrokenPipe
        {
            std::process::exit(0);
        }
    }};
}

#[derive(Parser)]
#[command(name = "plenoptic", version, about = "Bake and inspect radiance packs")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Compute the bake plan (base views, time keys, ambient keys) and print its cost.
    Plan {
        /// The bake recipe (TOML).
        recipe: PathBuf,
        /// Where to write the plan JSON (default: `<output>.plan.json`).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Print the plan JSON instead of the summary.
        #[arg(long)]
        json: bool,
    },
    /// Bake the recipe into its pack.
    Bake {
        /// The bake recipe (TOML).
        recipe: PathBuf,
        /// Continue an interrupted bake from `<output>.work/`.
        #[arg(long)]
        resume: bool,
        /// Bake only shard i of N into `<output>.work/` (then run `plenoptic merge`).
        #[arg(long)]
        shard: Option<Shard>,
        /// Keep `<output>.work/` after writing the pack.
        #[arg(long)]
        keep_work: bool,
        /// Store wall-clock timings in the manifest too (the pack is then not byte-identical
        /// between runs).
        #[arg(long)]
        timings_in_manifest: bool,
        /// Write the pack here instead of the recipe's output.
        #[arg(long)]
        output: Option<PathBuf>,
        /// Also store the (x, y, t) Delaunay complex of every temporal-volume block.
        #[arg(long)]
        volume_complex: bool,
        /// No progress bars.
        #[arg(short, long)]
        quiet: bool,
        /// Stop after rendering N work items (for testing --resume).
        #[arg(long, hide = true)]
        stop_after: Option<usize>,
    },
    /// Join the shards in `<output>.work/` into the pack.
    Merge {
        /// The bake recipe (TOML).
        recipe: PathBuf,
        /// Write the pack here instead of the recipe's output.
        #[arg(long)]
        output: Option<PathBuf>,
        /// Keep `<output>.work/` after writing the pack.
        #[arg(long)]
        keep_work: bool,
    },
    /// Summarise a pack.
    Inspect {
        /// The pack.
        pack: PathBuf,
        /// List every chunk.
        #[arg(long)]
        chunks: bool,
        /// Write chunk N's bytes (a KTX2 file for cube chunks) to OUT.
        #[arg(long, num_args = 2, value_names = ["N", "OUT"])]
        extract: Option<Vec<String>>,
    },
    /// Reconstruct frames along a camera path from a pack (plenoptic_recon): EXR + PNG per
    /// frame and report.csv.
    Render {
        /// The pack.
        pack: PathBuf,
        /// The camera path (JSON).
        #[arg(long)]
        path: PathBuf,
        /// Reconstruction mode: image, volume or geometry (geometry-assisted, the default).
        #[arg(long, default_value = "geometry")]
        mode: String,
        /// How geometry-assisted mode shows objects with a material: materials (albedo from
        /// their textures × the baked lighting, the default) or radiance (the baked radiance,
        /// as version-1 packs were shown).
        #[arg(long, default_value = "materials")]
        shading: String,
        /// What a mirror shows: shaded (the surface its ray meets shaded as a pixel is, the
        /// default) or marched (every reflected ray marched through the base views' distance
        /// cubes and shown in their radiance, as the plugin's GPU path does).
        #[arg(long, default_value = "shaded")]
        reflections: String,
        /// Samples per pixel along each axis, box-filtered (1: the pixel centre; a path-traced
        /// reference's pixels are box-filtered, so compare with 2–4).
        #[arg(long, default_value_t = 1)]
        supersampling: u32,
        /// Render N frames spread evenly over the whole path (first and last keyframe
        /// included, as the tour's `--results` frames are) instead of every frame.
        #[arg(long)]
        frames: Option<usize>,
        /// Exposure of the PNGs (default: automatic from the first frame; printed, so that a
        /// reference can be shown at the same one).
        #[arg(long)]
        exposure: Option<f32>,
        /// A light group's colour × intensity, NAME=I or NAME=R,G,B (repeatable; `default`
        /// names the emitters no group names; unset groups are 1).
        #[arg(long = "light", value_name = "NAME=I")]
        lights: Vec<String>,
        /// Output directory.
        #[arg(long, default_value = "frames")]
        out: PathBuf,
    },
    /// Compare frame directories with a reference directory: relative LRMS, PSNR and the
    /// mean-luminance ratio per frame (CSV), a table of the means, and an error-along-path
    /// plot (SVG and PNG).
    ///
    /// With --reference-b the reference is the mean of two independent halves A and B, and the
    /// error is variance-corrected: the reference's per-pixel variance, estimated as
    /// |A − B|²/4, is subtracted from the mean squared luminance error (clamped at 0) before
    /// the relative LRMS is taken. The table then shows corrected and uncorrected errors and
    /// the reference's noise floor (relative LRMS of (A − B)/2).
    Compare {
        /// The reference frames (from `plenoptic reference`; the first half with --halves).
        #[arg(long)]
        reference: PathBuf,
        /// The second, independent half of the reference (same frame names), e.g. the `DIR_b`
        /// that `plenoptic reference --halves` writes.
        #[arg(long)]
        reference_b: Option<PathBuf>,
        /// Candidate frame directories, as DIR or LABEL=DIR.
        #[arg(required = true)]
        candidates: Vec<String>,
        /// The CSV to write.
        #[arg(long, default_value = "compare.csv")]
        csv: PathBuf,
        /// The plot to write: `<stem>.svg` (with text) and `<stem>.png` (curves only).
        #[arg(long, default_value = "compare.svg")]
        plot: PathBuf,
        /// Also write each candidate frame's low-frequency difference from the reference as
        /// `DIR/<label>_frame_NNNNN.png`: red where the candidate is brighter, blue where it
        /// is darker, full colour at 20 % of the frame's mean (blotches, halos, dim patches);
        /// and where its corrected squared error lies as `DIR/<label>_error_frame_NNNNN.png`
        /// (red at the frame's mean luminance squared), printing each frame's share of it in
        /// its worst 8 × 8 pixels.
        #[arg(long, value_name = "DIR")]
        maps: Option<PathBuf>,
    },
    /// Render reference frames along a camera path with the path tracer (EXR + PNG).
    Reference {
        /// The bake recipe (TOML): scene and quality.
        recipe: PathBuf,
        /// The camera path (JSON, plenoptic_recon's format).
        #[arg(long)]
        path: PathBuf,
        /// Output directory.
        #[arg(long, default_value = "reference")]
        out: PathBuf,
        /// Samples per pixel (default: the recipe's reference_samples_per_pixel); with
        /// --halves, the total over both halves.
        #[arg(long)]
        spp: Option<u32>,
        /// Seed of the random sequence (default 0). References with different seeds are
        /// independent.
        #[arg(long)]
        seed: Option<u64>,
        /// Render two independent halves for `plenoptic compare --reference-b`: OUT with seed S
        /// and OUT_b with seed S + 1, each with half the samples.
        #[arg(long)]
        halves: bool,
        /// Exposure of the PNGs (default: automatic from the first frame).
        #[arg(long)]
        exposure: Option<f32>,
        /// A light group's colour × intensity, as `plenoptic render --light` takes it.
        #[arg(long = "light", value_name = "NAME=I")]
        lights: Vec<String>,
        /// Render N frames spread evenly over the whole path, the frames `plenoptic render
        /// --frames N` renders, instead of every frame.
        #[arg(long)]
        frames: Option<usize>,
        /// Render the bake's lighting model at each camera instead of the path tracer: the
        /// multi-stage renderer over the bake's ambient field, as the range images are
        /// rendered, at the camera's own pixels (docs/fidelity.md, "Where the error is made").
        #[arg(long)]
        bake_lighting: bool,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match run(cli.command) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("plenoptic: error: {e}");
            ExitCode::FAILURE
        }
    }
}

fn run(command: Command) -> Result<()> {
    match command {
        Command::Plan { recipe, out, json } => cmd_plan(&recipe, out, json),
        Command::Bake {
            recipe,
            resume,
            shard,
            keep_work,
            timings_in_manifest,
            output,
            volume_complex,
            quiet,
            stop_after,
        } => {
            let options = BakeOptions {
                resume,
                shard,
                keep_work,
                timings_in_manifest,
                stop_after,
                progress: Progress::new(!quiet),
                output,
                volume_complex,
            };
            cmd_bake(&recipe, &options)
        }
        Command::Merge {
            recipe,
            output,
            keep_work,
        } => {
            let options = BakeOptions {
                keep_work,
                output,
                ..Default::default()
            };
            let report = plenoptic_bake::merge_recipe(&recipe, &options)?;
            if let Some(out) = report.output {
                out!("merged {} items into {}", report.items_total, out.display());
            }
            Ok(())
        }
        Command::Inspect {
            pack,
            chunks,
            extract,
        } => cmd_inspect(&pack, chunks, extract),
        Command::Render {
            pack,
            path,
            mode,
            shading,
            reflections,
            supersampling,
            frames,
            exposure,
            lights,
            out,
        } => {
            let mode = plenoptic_recon::Mode::parse(&mode).ok_or_else(|| {
                BakeError::Invalid(format!("mode '{mode}': expected image, volume or geometry"))
            })?;
            let look = Look {
                shading: parse_shading(&shading)?,
                shaded_reflections: parse_reflections(&reflections)?,
                supersampling,
                exposure,
                lights,
            };
            cmd_render(&pack, &path, (mode, frames), look, &out)
        }
        Command::Compare {
            reference,
            reference_b,
            candidates,
            csv,
            plot,
            maps,
        } => cmd_compare(
            &reference,
            reference_b.as_deref(),
            &candidates,
            (&csv, &plot),
            maps.as_deref(),
        ),
        Command::Reference {
            recipe,
            path,
            out,
            spp,
            seed,
            halves,
            exposure,
            lights,
            frames,
            bake_lighting,
        } => {
            let samples = plenoptic_bake::reference::path_frames(&path, frames)?;
            cmd_reference(
                &recipe,
                &samples,
                &out,
                (spp, seed, halves, bake_lighting),
                exposure,
                &lights,
            )
        }
    }
}

/// Bakes the recipe (or one shard of it) and prints what was written and the time per phase.
fn cmd_bake(recipe_path: &Path, options: &BakeOptions) -> Result<()> {
    // What the import could not take over (an unsupported feature, a value out of range),
    // before the bake's minutes start: the author can stop and fix it.
    let (recipe, scene) = plenoptic_bake::input::load_recipe(recipe_path)?;
    for w in &scene.warnings {
        eprintln!("plenoptic: warning: {w}");
    }
    let report = plenoptic_bake::bake(&recipe, &scene, options)?;
    match (&report.output, options.shard) {
        (Some(out), _) => out!(
            "wrote {} ({} items rendered, {} resumed)",
            out.display(),
            report.items_rendered,
            report.items_skipped
        ),
        (None, Some(s)) => out!(
            "shard {s}: {} items rendered, {} already done, of {} in the plan",
            report.items_rendered,
            report.items_skipped,
            report.items_total
        ),
        (None, None) => {}
    }
    for (phase, secs) in &report.timings {
        out!("  {phase:>14}: {secs:.3} s");
    }
    Ok(())
}

/// How `plenoptic render` shows the frames (its `--shading`, `--reflections`,
/// `--supersampling`, `--exposure` and `--light`).
#[derive(Clone)]
struct Look {
    shading: plenoptic_recon::Shading,
    shaded_reflections: bool,
    supersampling: u32,
    exposure: Option<f32>,
    lights: Vec<String>,
}

/// `--shading`: materials or radiance.
fn parse_shading(shading: &str) -> Result<plenoptic_recon::Shading> {
    match shading.to_ascii_lowercase().as_str() {
        "materials" => Ok(plenoptic_recon::Shading::Materials),
        "radiance" => Ok(plenoptic_recon::Shading::Radiance),
        other => Err(BakeError::Invalid(format!(
            "shading '{other}': expected materials or radiance"
        ))),
    }
}

/// `--reflections`: shaded (true) or marched (false).
fn parse_reflections(reflections: &str) -> Result<bool> {
    match reflections.to_ascii_lowercase().as_str() {
        "shaded" => Ok(true),
        "marched" => Ok(false),
        other => Err(BakeError::Invalid(format!(
            "reflections '{other}': expected shaded or marched"
        ))),
    }
}

/// Reconstructs the frames along the camera path at `path` from `pack` into `out`.
fn cmd_render(
    pack: &Path,
    path: &Path,
    (mode, frames): (plenoptic_recon::Mode, Option<usize>),
    look: Look,
    out: &Path,
) -> Result<()> {
    let mut rec = plenoptic_recon::Reconstructor::open(pack)
        .map_err(|e| BakeError::Invalid(format!("render: {e}")))?;
    let names = (rec.pack().manifest().light_groups.as_ref()).map_or(&[][..], |g| &g.names[..]);
    rec.set_light_weights(plenoptic_bake::groups::weights(names, &look.lights)?);
    rec.settings.shading = look.shading;
    rec.settings.shaded_reflections = look.shaded_reflections;
    rec.settings.supersampling = look.supersampling;
    let render = || -> std::result::Result<_, plenoptic_eval::EvalError> {
        let camera_path = plenoptic_recon::CameraPath::load(path)?;
        plenoptic_eval::tools::render_path_with(
            &rec,
            &camera_path,
            out,
            &plenoptic_eval::tools::RenderOptions {
                mode,
                progress: true,
                frames,
                exposure: look.exposure,
                ..Default::default()
            },
        )
    };
    let summary = render().map_err(|e| BakeError::Invalid(format!("render: {e}")))?;
    out!(
        "{} frames in {} ({:.1} ms per frame, exposure {}), report {}",
        summary.frames,
        out.display(),
        summary.mean_ms,
        summary.exposure,
        summary.report_csv.display()
    );
    Ok(())
}

/// Compares the candidate directories (`DIR` or `LABEL=DIR`) with the reference.
fn cmd_compare(
    reference: &Path,
    reference_b: Option<&Path>,
    candidates: &[String],
    (csv, plot): (&Path, &Path),
    maps: Option<&Path>,
) -> Result<()> {
    let candidates: Vec<(String, PathBuf)> = candidates
        .iter()
        .map(|c| match c.split_once('=') {
            Some((label, dir)) => (label.to_owned(), PathBuf::from(dir)),
            None => {
                let dir = PathBuf::from(c);
                let label = dir
                    .file_name()
                    .map_or_else(|| c.clone(), |n| n.to_string_lossy().into_owned());
                (label, dir)
            }
        })
        .collect();
    let comparison =
        plenoptic_eval::tools::compare_with(reference, reference_b, &candidates, csv, plot)
            .map_err(|e| BakeError::Invalid(format!("compare: {e}")))?;
    print!("{}", comparison.table());
    let plots: Vec<String> = comparison
        .plots
        .iter()
        .map(|p| p.display().to_string())
        .collect();
    out!("wrote {} and {}", csv.display(), plots.join(", "));
    if let Some(dir) = maps {
        let n = plenoptic_eval::maps::write_low_frequency_maps(
            reference,
            reference_b,
            &candidates,
            dir,
        )
        .map_err(|e| BakeError::Invalid(format!("compare: {e}")))?;
        out!("wrote {n} low-frequency maps into {}", dir.display());
        let errors =
            plenoptic_eval::maps::write_error_maps(reference, reference_b, &candidates, dir)
                .map_err(|e| BakeError::Invalid(format!("compare: {e}")))?;
        for (label, frame, c) in &errors {
            out!(
                "{label} frame {frame}: {:.0} % of the corrected squared error in the 8 × 8 \
                 pixels at ({}, {})",
                100.0 * c.share,
                c.x,
                c.y
            );
        }
        out!("wrote {} error maps into {}", errors.len(), dir.display());
    }
    Ok(())
}

fn cmd_plan(recipe_path: &Path, out: Option<PathBuf>, json: bool) -> Result<()> {
    let (recipe, scene) = plenoptic_bake::input::load_recipe(recipe_path)?;
    let accel = SceneAccel::new(&scene)?;
    let clock = Instant::now();
    let (mut planned, id_rays) = plan::decompose(&recipe, &scene, &accel);
    let secs = clock.elapsed().as_secs_f64().max(1e-6);
    // Id rays are about as costly as one shading ray; their rate stands in for both.
    let rate = id_rays as f64 / secs;
    plan::ambient_phase(&mut planned, &scene, &accel)?;
    let p = &planned;
    let cost = p.cost(rate);
    let out = out.unwrap_or_else(|| {
        let mut n = recipe.output.as_os_str().to_owned();
        n.push(".plan.json");
        PathBuf::from(n)
    });
    if let Some(parent) = out.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent).map_err(|e| BakeError::io(parent, e))?;
    }
    std::fs::write(&out, p.to_json()).map_err(|e| BakeError::io(&out, e))?;
    if json {
        out!("{}", p.to_json());
        return Ok(());
    }
    out!("plan of {} (q = {})", p.recipe, p.quality.q);
    out!(
        "  base views: {} (lattice {} per axis, {} cells tested, {} split; {} moved clear of \
         objects, {} crowded with no clear point near)",
        p.base_views.len(),
        p.space_lattice,
        p.counters.space_cells_tested,
        p.counters.space_cells_split,
        p.counters.views_moved,
        p.counters.views_crowded
    );
    out!(
        "  time: {} .. {} s, animated: {}, light keys: {}, time keys: {}",
        p.start,
        p.end,
        p.animated,
        p.light_keys.len(),
        p.time_key_count()
    );
    for v in &p.base_views {
        out!(
            "    view {:>4} at ({:.3}, {:.3}, {:.3}): {} keys, {} volume samples",
            v.id,
            v.position.x,
            v.position.y,
            v.position.z,
            v.time_keys.len(),
            v.volume_samples
        );
    }
    out!("  ambient key times: {:?}", p.ambient_keys);
    out!("cost:");
    out!("  range images:   {}", cost.range_images);
    out!("  camera samples: {}", cost.camera_samples);
    out!("  volume samples: {}", cost.volume_samples);
    out!("  ambient fields: {}", cost.ambient_fields);
    out!(
        "  estimated size: {:.1} MiB before compression",
        cost.estimated_bytes as f64 / (1024.0 * 1024.0)
    );
    out!(
        "  estimated time: {:.0} s (at {:.2} Mrays/s measured while planning in {secs:.2} s)",
        cost.estimated_seconds,
        rate / 1e6
    );
    out!("plan written to {}", out.display());
    Ok(())
}

fn cmd_inspect(pack_path: &Path, chunks: bool, extract: Option<Vec<String>>) -> Result<()> {
    let pack = PackReader::open(pack_path)?;
    if let Some(args) = extract {
        let n: usize = args[0]
            .parse()
            .map_err(|_| BakeError::Invalid(format!("chunk index '{}'", args[0])))?;
        if n >= pack.entries().len() {
            return Err(BakeError::Invalid(format!(
                "chunk {n} out of range: the pack has {}",
                pack.entries().len()
            )));
        }
        let bytes = pack.chunk_bytes(n)?;
        let out = Path::new(&args[1]);
        std::fs::write(out, &bytes).map_err(|e| BakeError::io(out, e))?;
        out!(
            "wrote chunk {n} ({} bytes) to {}",
            bytes.len(),
            out.display()
        );
        return Ok(());
    }
    let m = pack.manifest();
    out!("{}: {} bytes", pack_path.display(), pack.file_length());
    out!(
        "  time {} .. {} s, bucket span {} s ({} buckets)",
        m.time_range.start,
        m.time_range.end,
        m.bucket_span,
        m.bucket_count()
    );
    out!("  view space: {:?}", m.view_space);
    out!(
        "  scene bounds: {:?} .. {:?}",
        m.scene_bounds.min,
        m.scene_bounds.max
    );
    out!(
        "  bake: q = {}, face {} px, {} spp, {} volume samples per view",
        m.bake.quality,
        m.bake.cube_face_size,
        m.bake.samples_per_texel,
        m.bake.volume_samples_per_view
    );
    out!("  base views: {}", m.base_views.len());
    for v in &m.base_views {
        out!(
            "    {:>4} at ({:.3}, {:.3}, {:.3}): keys {:?}",
            v.id,
            v.position.x,
            v.position.y,
            v.position.z,
            v.time_keys
        );
    }
    out!("  objects: {}", m.objects.len());
    for o in &m.objects {
        out!("    {:>4} {} ({:?})", o.id, o.name, o.motion);
    }
    out!(
        "  materials: {}, textures: {}",
        m.materials.len(),
        m.textures.len()
    );
    for (i, t) in m.textures.iter().enumerate() {
        out!(
            "    texture {i}: {} x {}, {} levels, {:?}",
            t.width,
            t.height,
            t.levels,
            t.colour_space
        );
    }
    out!("  lights: {}", m.lights.len());
    out!("  chunks: {}", pack.entries().len());
    for (k, v) in &m.stats.bytes {
        out!("    bytes {k}: {v}");
    }
    for (k, v) in &m.stats.sample_counts {
        out!("    count {k}: {v}");
    }
    for (k, v) in &m.stats.phase_seconds {
        out!("    seconds {k}: {v:.3}");
    }
    if chunks {
        out!(
            "  {:>6} {:<20} {:>6} {:>6} {:>12} {:>10} {:>12} {:>18}",
            "index",
            "kind",
            "view",
            "key",
            "offset",
            "length",
            "uncompressed",
            "checksum"
        );
        for (i, e) in pack.entries().iter().enumerate() {
            let view = if e.base_view == plenoptic_pack::NO_BASE_VIEW {
                "-".to_owned()
            } else {
                e.base_view.to_string()
            };
            out!(
                "  {:>6} {:<20} {:>6} {:>6} {:>12} {:>10} {:>12} {:>#18x}",
                i,
                format!("{:?}", e.kind),
                view,
                e.key,
                e.offset,
                e.length,
                e.uncompressed_length,
                e.checksum
            );
        }
    }
    Ok(())
}

fn cmd_reference(
    recipe_path: &Path,
    frames: &[plenoptic_recon::PathSample],
    out: &Path,
    (spp, seed, halves, bake_lighting): (Option<u32>, Option<u64>, bool, bool),
    exposure: Option<f32>,
    lights: &[String],
) -> Result<()> {
    let (recipe, scene) = plenoptic_bake::input::load_recipe(recipe_path)?;
    let scene = plenoptic_bake::groups::relit_scene(&scene, lights)?;
    let spp = spp.unwrap_or(recipe.quality.reference_samples_per_pixel);
    let seed = seed.unwrap_or(0);
    // Two halves: half the samples each, seeds S and S + 1 (independent streams), the same
    // exposure for both PNG sets.
    let runs: Vec<(PathBuf, u32, u64)> = if halves {
        let mut b = out.as_os_str().to_owned();
        b.push("_b");
        let half = spp.div_ceil(2).max(1);
        vec![
            (out.to_path_buf(), half, seed),
            (PathBuf::from(b), half, seed.wrapping_add(1)),
        ]
    } else {
        vec![(out.to_path_buf(), spp, seed)]
    };
    let mut exposure = exposure;
    for (dir, spp, seed) in runs {
        let progress = Progress::new(true);
        let summary = if bake_lighting {
            plenoptic_bake::reference::render_bake_lighting(
                &scene,
                &recipe.quality,
                frames,
                (spp, seed),
                &dir,
                exposure,
                &progress,
            )?
        } else {
            plenoptic_bake::reference::render_reference(
                &scene,
                frames,
                spp,
                Some(seed),
                &dir,
                exposure,
                &progress,
            )?
        };
        exposure = Some(summary.exposure);
        out!(
            "{} reference frames written to {} ({:.1} s per frame at {spp} spp, seed {seed})",
            summary.frames,
            dir.display(),
            summary.seconds_per_frame
        );
    }
    if halves {
        out!(
            "compare with: plenoptic compare --reference {0} --reference-b {0}_b …",
            out.display()
        );
    }
    Ok(())
}
