//! # The architectural tour
//!
//! A walk through a small building — two rooms on either side of a tall atrium — while its
//! animation plays: the sun moves across the sky and its light travels over the floors
//! through the windows and the skylight, a sliding door opens and closes, a sculpture
//! revolves on its pedestal, a ceiling fan turns, and a cart crosses a room and comes back.
//! The building has a mirror, a glass vitrine, columns, stairs and furniture, so the
//! reconstruction meets reflections, refractions, occlusion and moving shadows. The scene is
//! generated in code (`scene.rs`); see that module for the layout.
//!
//! What the example does:
//!
//! 1. Writes `assets/tour.glb` from the generator if the file is missing (the committed
//!    file is checked against the generator by `tests/tour_scene.rs`).
//! 2. Bakes the radiance pack from `assets/tour.toml` if it is missing, with progress bars
//!    (`target/architectural_tour/tour.pack`; the recipe's `output`). Measured on two
//!    cores: 4.5 min in a release build (`plenoptic bake`); the pack is 40.6 MiB (25 base
//!    views, 225 range images of 6 × 64², 25 volumes; the sun study and the sky).
//! 3. Flies the camera path `assets/tour_path.json` (room B, atrium, room A, for the 14 s
//!    of the animation) and renders every frame with the CPU reconstruction of
//!    `plenoptic_recon` in geometry-assisted mode, into PNG frames plus an animated GIF
//!    preview (`tour.gif`) in the output folder (default, under `$CARGO_TARGET_DIR` if set,
//!    `target/architectural_tour/frames`), with a progress bar.
//!
//! With a display (`DISPLAY` or `WAYLAND_DISPLAY` set), step 3 instead opens a window: the
//! Bevy plugin (`bevy_plenoptic`) streams the pack and reconstructs the tour on the GPU while
//! the camera flies the path; `Tab` switches to free-fly controls (see `windowed.rs`). The
//! windowed mode needs the default `window` feature; `--headless` renders to files anyway.
//!
//! Run it (release recommended for the bake):
//!
//! ```text
//! cargo run --release --example architectural_tour
//! # headless without building Bevy
//! cargo run --release --no-default-features --example architectural_tour -- --headless
//! # a short run: 4 frames spread over the tour, small frames
//! cargo run --no-default-features --example architectural_tour -- --frames 4 --width 160 --height 90
//! ```
//!
//! Options:
//!
//! - `--headless`: render to files even when a display is present.
//! - `--cpu`: in the window, reconstruct with the CPU backend instead of the GPU.
//! - `--frames N`: render N frames spread evenly over the whole tour instead of every frame
//!   of the path (24 per second).
//! - `--width W`, `--height H`: frame size (default: the path's 640 × 360).
//! - `--out DIR`: where frames and the preview go.
//! - `--pack FILE`: use (or bake to) this pack instead of the recipe's output.
//! - `--recipe FILE`: bake this recipe instead of `assets/tour.toml` (for example a copy
//!   with cheaper quality settings for a quick check; its `[[scene]]` should name
//!   `tour.glb`).
//! - `--mode geometry|image|volume`: reconstruction mode (default geometry-assisted).
//! - `--plan`: print the bake plan of the recipe (base views, time keys, estimated cost) and
//!   stop.
//! - `--quiet`: no progress bars.
//! - `--screenshot FILE`, `--screenshot-at S`: in the window, hold the tour at S seconds
//!   (default 4), save the window to FILE once the frame's data is resident, and quit.
//! - `--streaming`: print the plugin's streaming working set along the whole tour (bytes
//!   resident per frame with its default settings) and stop; needs the `bevy` feature.
//! - `--results DIR`: instead of the tour, the README's results (`results.rs`): path-traced
//!   reference frames (`--spp N`, default 128) at `--frames` (default 8) frames spread over
//!   the tour, each mode's reconstruction of them, errors, plot, montage and figures, at
//!   `--width`/`--height` (default 320 × 180); and a crop at full resolution of frame
//!   `--crop-frame K` (default [`CROP_FRAME`]) against a reference of `--crop-spp N`
//!   (default 256) samples per pixel and half. The reconstructions are supersampled
//!   `--supersampling N` × N per pixel (default [`results::SUPERSAMPLING`]), a box filter over
//!   the pixel as the references have.

mod results;
#[allow(dead_code, reason = "some items are for tests/tour_scene.rs")]
mod scene;
#[cfg(feature = "window")]
mod windowed;

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use image::codecs::gif::{GifEncoder, Repeat};
use image::{Delay, Frame as GifFrame, RgbaImage};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use plenoptic_bake::BakeOptions;
use plenoptic_bake::progress::Progress;
use plenoptic_eval::frame_io::{auto_exposure, tonemap, write_png};
use plenoptic_eval::tools::frame_name;
use plenoptic_recon::{CameraPath, Mode, PathSample, Reconstructor};
use plenoptic_scene::recipe::Recipe;

type BoxError = Box<dyn std::error::Error>;

/// Command-line options.
#[derive(Debug)]
struct Options {
    headless: bool,
    cpu: bool,
    frames: Option<usize>,
    width: Option<u32>,
    height: Option<u32>,
    out: Option<PathBuf>,
    pack: Option<PathBuf>,
    recipe: Option<PathBuf>,
    mode: Mode,
    quiet: bool,
    plan: bool,
    results: Option<PathBuf>,
    spp: u32,
    crop_frame: Option<usize>,
    crop_spp: u32,
    supersampling: u32,
    screenshot: Option<PathBuf>,
    screenshot_at: f32,
    streaming: bool,
}

/// The frame of `--results` whose centre the full-resolution crop shows.
const CROP_FRAME: usize = 4;

const USAGE: &str = "usage: architectural_tour [--headless] [--cpu] [--frames N] [--width W] \
                     [--height H] [--out DIR] [--pack FILE] [--recipe FILE] [--mode geometry|image|volume] \
                     [--plan] [--streaming] [--quiet] [--results DIR [--spp N] [--crop-frame K] [--crop-spp N] [--supersampling N]] [--screenshot FILE [--screenshot-at S]]";

fn parse_args() -> Result<Options, String> {
    let mut o = Options {
        headless: false,
        cpu: false,
        frames: None,
        width: None,
        height: None,
        out: None,
        pack: None,
        recipe: None,
        mode: Mode::GeometryAssisted,
        quiet: false,
        plan: false,
        results: None,
        spp: 128,
        crop_frame: None,
        crop_spp: 256,
        supersampling: results::SUPERSAMPLING,
        screenshot: None,
        screenshot_at: 4.0,
        streaming: false,
    };
    let mut args = std::env::args().skip(1);
    while let Some(arg) = args.next() {
        let mut value = |name: &str| args.next().ok_or(format!("{name} needs a value\n{USAGE}"));
        let number = |name: &str, v: String| {
            v.parse::<u32>()
                .ok()
                .filter(|&n| n > 0)
                .ok_or(format!("{name}: `{v}` is not a positive whole number"))
        };
        match arg.as_str() {
            "--headless" => o.headless = true,
            "--cpu" => o.cpu = true,
            "--quiet" => o.quiet = true,
            "--plan" => o.plan = true,
            "--streaming" => o.streaming = true,
            "--frames" => o.frames = Some(number("--frames", value("--frames")?)? as usize),
            "--width" => o.width = Some(number("--width", value("--width")?)?),
            "--height" => o.height = Some(number("--height", value("--height")?)?),
            "--out" => o.out = Some(value("--out")?.into()),
            "--pack" => o.pack = Some(value("--pack")?.into()),
            "--recipe" => o.recipe = Some(value("--recipe")?.into()),
            "--results" => o.results = Some(value("--results")?.into()),
            "--spp" => o.spp = number("--spp", value("--spp")?)?,
            "--crop-frame" => {
                let v = value("--crop-frame")?;
                o.crop_frame = Some(
                    v.parse()
                        .map_err(|_| format!("--crop-frame: `{v}` is not a frame number"))?,
                );
            }
            "--crop-spp" => o.crop_spp = number("--crop-spp", value("--crop-spp")?)?,
            "--supersampling" => {
                o.supersampling = number("--supersampling", value("--supersampling")?)?
            }
            "--screenshot" => o.screenshot = Some(value("--screenshot")?.into()),
            "--screenshot-at" => {
                let v = value("--screenshot-at")?;
                o.screenshot_at = v
                    .parse()
                    .ok()
                    .filter(|s: &f32| s.is_finite() && *s >= 0.0)
                    .ok_or(format!("--screenshot-at: `{v}` is not a time in seconds"))?;
            }
            "--mode" => {
                let v = value("--mode")?;
                o.mode = Mode::parse(&v).ok_or(format!("--mode: unknown mode `{v}`"))?;
            }
            "-h" | "--help" => return Err(USAGE.to_owned()),
            other => return Err(format!("unknown argument `{other}`\n{USAGE}")),
        }
    }
    Ok(o)
}

fn main() -> ExitCode {
    let options = match parse_args() {
        Ok(o) => o,
        Err(message) => {
            eprintln!("{message}");
            return ExitCode::FAILURE;
        }
    };
    match run(&options) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("architectural_tour: {e}");
            ExitCode::FAILURE
        }
    }
}

/// The example's asset folder.
fn assets() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/architectural_tour/assets")
}

/// Where the example writes by default: `$CARGO_TARGET_DIR/architectural_tour` or
/// `target/architectural_tour` of the workspace.
fn target_dir() -> PathBuf {
    std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("target"))
        .join("architectural_tour")
}

fn run(options: &Options) -> Result<(), BoxError> {
    let assets = assets();

    // 1. The scene file.
    let glb = assets.join("tour.glb");
    if !glb.exists() {
        println!("writing {} from the scene generator", glb.display());
        scene::build().write_glb(&glb)?;
    }

    // 2. The pack.
    let recipe_path = options
        .recipe
        .clone()
        .unwrap_or_else(|| assets.join("tour.toml"));
    let recipe = Recipe::from_path(&recipe_path)?;
    if options.plan {
        return print_plan(&recipe_path);
    }
    let mut pack = options.pack.clone().unwrap_or(recipe.output.clone());
    // A pack of an older format is baked again (version 1 cannot be read; version 2 keeps
    // the sun in its lighting, which version 3 evaluates at runtime; 4.0 does not place its
    // lamps, so its glossy surfaces keep their baked highlights); the new pack replaces it
    // only once it is complete.
    let outdated = pack.exists() && plenoptic_pack::is_outdated(&pack);
    if outdated {
        println!(
            "{} is a pack of an older format: baking it again",
            pack.display()
        );
    }
    if !pack.exists() || outdated {
        if let Some(dir) = pack.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir)?;
            if let (Ok(dir), Some(name)) = (dir.canonicalize(), pack.file_name()) {
                pack = dir.join(name);
            }
        }
        println!(
            "baking {} → {} (q = {}, {} px range images)",
            recipe_path.display(),
            pack.display(),
            recipe.quality.q,
            recipe.quality.range_image_size
        );
        if cfg!(debug_assertions) {
            println!("  (a dev build bakes about 1.5× slower than `--release`: 10+ minutes)");
        }
        let start = Instant::now();
        let report = plenoptic_bake::bake_recipe(
            &recipe_path,
            &BakeOptions {
                // An interrupted bake continues where it stopped.
                resume: true,
                progress: Progress::new(!options.quiet),
                output: Some(pack.clone()),
                ..BakeOptions::default()
            },
        )?;
        let size = std::fs::metadata(&pack).map(|m| m.len()).unwrap_or(0);
        println!(
            "baked {} base views, {} work items in {:.1} s: {} ({:.1} MiB)",
            report.plan.base_views.len(),
            report.items_total,
            start.elapsed().as_secs_f64(),
            pack.display(),
            size as f64 / (1024.0 * 1024.0)
        );
    }

    // 3. The tour, or the results.
    if options.streaming {
        let path = CameraPath::load(assets.join("tour_path.json"))?;
        let line = streaming_figures(&pack, &path)?
            .ok_or("--streaming needs the `bevy` feature (leave out --no-default-features)")?;
        println!("{line}");
        return Ok(());
    }
    if let Some(dir) = &options.results {
        let path = CameraPath::load(assets.join("tour_path.json"))?;
        return results::run(
            &pack,
            &recipe_path,
            &path,
            dir,
            &results::ResultsOptions {
                frames: options.frames.unwrap_or(8).max(2),
                spp: options.spp,
                width: options.width.unwrap_or(320),
                height: options.height.unwrap_or(180),
                crop_frame: options.crop_frame.unwrap_or(CROP_FRAME),
                crop_spp: options.crop_spp,
                supersampling: options.supersampling,
                progress: !options.quiet,
            },
        );
    }
    let display = std::env::var_os("DISPLAY").is_some_and(|v| !v.is_empty())
        || std::env::var_os("WAYLAND_DISPLAY").is_some_and(|v| !v.is_empty());
    if display && !options.headless {
        return windowed(options, &pack);
    }
    render_headless(options, &pack)
}

/// The tour's camera path, at the frame size the options ask for.
fn tour_path(options: &Options) -> Result<CameraPath, BoxError> {
    let mut path = CameraPath::load(assets().join("tour_path.json"))?;
    if let Some(w) = options.width {
        path.width = w;
    }
    if let Some(h) = options.height {
        path.height = h;
    }
    Ok(path)
}

/// Opens the window (the `window` feature), exposed like the headless frames.
#[cfg(feature = "window")]
fn windowed(options: &Options, pack: &Path) -> Result<(), BoxError> {
    let path = tour_path(options)?;
    // The exposure of the first frame shown, from a small CPU reconstruction.
    let start = path.sample(if options.screenshot.is_some() {
        options.screenshot_at
    } else {
        path.time_range().0
    });
    let mut probe = start.camera;
    (probe.width, probe.height) = (160, 90);
    let (frame, _) = Reconstructor::open(pack)?.render(&probe, start.scene_time, options.mode)?;
    let exposure = auto_exposure(&frame.radiance);
    let backend = if options.cpu {
        bevy_plenoptic::Backend::Cpu
    } else {
        bevy_plenoptic::Backend::Auto
    };
    println!(
        "opening the tour window ({}): Tab free-fly / tour, Space pause, 1-3 mode, Esc quit",
        pack.display()
    );
    let screenshot = options
        .screenshot
        .clone()
        .map(|file| windowed::ScreenshotPlan {
            file,
            at: options.screenshot_at,
        });
    let mode = match options.mode {
        Mode::GeometryAssisted => bevy_plenoptic::ReconMode::GeometryAssisted,
        Mode::Image => bevy_plenoptic::ReconMode::Image,
        Mode::Volume => bevy_plenoptic::ReconMode::Volume,
    };
    windowed::run(pack, path, exposure, backend, mode, screenshot)
}

/// Without the `window` feature the tour renders headless.
#[cfg(not(feature = "window"))]
fn windowed(options: &Options, pack: &Path) -> Result<(), BoxError> {
    println!(
        "built without the `window` feature (--no-default-features): rendering the tour headless"
    );
    render_headless(options, pack)
}

/// Prints the bake plan of the recipe at `recipe_path` and its estimated cost.
fn print_plan(recipe_path: &Path) -> Result<(), BoxError> {
    let (recipe, scene) = plenoptic_bake::input::load_recipe(recipe_path)?;
    println!(
        "scene: {} objects, {} triangles, {} lights, animation {:?} s",
        scene.objects.len(),
        scene.triangle_count(),
        scene.lights.len(),
        scene.animation_range()
    );
    let accel = plenoptic_trace::SceneAccel::new(&scene)?;
    let clock = Instant::now();
    let planned = plenoptic_bake::plan::build(&recipe, &scene, &accel)?;
    let secs = clock.elapsed().as_secs_f64().max(1e-6);
    let p = &planned.plan;
    let cost = p.cost(planned.id_rays as f64 / secs);
    println!(
        "plan (q = {}, {} px range images, {} spp): {} base views, {} time keys, ambient keys {:?}",
        p.quality.q,
        p.quality.range_image_size,
        p.quality.samples_per_pixel,
        p.base_views.len(),
        p.time_key_count(),
        p.ambient_keys
    );
    for v in &p.base_views {
        println!(
            "  view {:>3} at ({:6.2}, {:.2}, {:6.2}): {:>3} keys",
            v.id,
            v.position.x,
            v.position.y,
            v.position.z,
            v.time_keys.len()
        );
    }
    println!(
        "cost: {} range images, {} camera samples, {} volume samples, ≤ {:.1} MiB before \
         compression, about {:.0} s on this machine (planned in {secs:.1} s)",
        cost.range_images,
        cost.camera_samples,
        cost.volume_samples,
        cost.estimated_bytes as f64 / (1024.0 * 1024.0),
        cost.estimated_seconds
    );
    Ok(())
}

/// Renders the camera path with the CPU reconstruction into PNG frames and `tour.gif`.
fn render_headless(options: &Options, pack: &Path) -> Result<(), BoxError> {
    let path = tour_path(options)?;
    let (start, end) = path.time_range();
    let samples: Vec<PathSample> = match options.frames {
        None => path.frames().collect(),
        Some(n) => path.spread(n),
    };
    let frame_seconds = (end - start) / samples.len().saturating_sub(1).max(1) as f32;

    let out = options
        .out
        .clone()
        .unwrap_or_else(|| target_dir().join("frames"));
    std::fs::create_dir_all(&out)?;
    let rec = Reconstructor::open(pack)?;
    println!(
        "rendering {} frames of {}×{} ({} mode) into {}",
        samples.len(),
        path.width,
        path.height,
        options.mode.name(),
        out.display()
    );

    let bar = if options.quiet || !std::io::stderr().is_terminal() {
        ProgressBar::hidden()
    } else {
        let bar = ProgressBar::new(samples.len() as u64);
        bar.set_draw_target(ProgressDrawTarget::stderr());
        if let Ok(style) = ProgressStyle::with_template(
            "{prefix:>14} [{bar:32}] {pos}/{len} {elapsed_precise} ETA {eta_precise} {msg}",
        ) {
            bar.set_style(style.progress_chars("=> "));
        }
        bar.set_prefix("tour");
        bar
    };

    // The exposure adapts like an eye going from the bright atrium into a darker room: the
    // log of the auto exposure, smoothed with a time constant of `ADAPTATION` seconds.
    const ADAPTATION: f32 = 0.75;
    let adapt = 1.0 - (-frame_seconds / ADAPTATION).exp();
    let mut log_exposure: Option<f32> = None;
    let mut gif_frames = Vec::with_capacity(samples.len());
    let mut total_ms = 0.0;
    let mut direct = 0.0;
    let mut degraded = 0;
    for s in &samples {
        let clock = Instant::now();
        let (frame, report) = rec.render(&s.camera, s.scene_time, options.mode)?;
        total_ms += clock.elapsed().as_secs_f64() * 1e3;
        direct += report.fallback.direct;
        degraded += usize::from(report.degraded());
        let target = auto_exposure(&frame.radiance).ln();
        let log_e = log_exposure.map_or(target, |prev| prev + (target - prev) * adapt);
        log_exposure = Some(log_e);
        let e = log_e.exp();
        write_png(
            out.join(frame_name(s.index, "png")),
            frame.width,
            frame.height,
            &frame.radiance,
            e,
        )?;
        let rgba: Vec<u8> = frame
            .radiance
            .iter()
            .flat_map(|&c| {
                let [r, g, b] = tonemap(c, e);
                [r, g, b, 255]
            })
            .collect();
        let image = RgbaImage::from_raw(frame.width, frame.height, rgba)
            .ok_or("frame size does not match its pixels")?;
        gif_frames.push(image);
        bar.set_message(format!("t = {:.2} s", s.scene_time));
        bar.inc(1);
    }
    bar.finish_and_clear();

    let gif = out.join("tour.gif");
    write_gif(&gif, gif_frames, frame_seconds)?;
    let n = samples.len().max(1) as f64;
    println!(
        "{} frames, {:.1} ms/frame reconstruction, {:.1}% of pixels direct lookups, {} degraded",
        samples.len(),
        total_ms / n,
        100.0 * f64::from(direct) / n,
        degraded
    );
    println!(
        "frames: {}  preview: {}",
        out.join("frame_*.png").display(),
        gif.display()
    );
    Ok(())
}

/// The plugin's streaming working set along every frame of the tour, with its default
/// settings: the bytes it must hold for each frame (the weighted base views at the
/// bracketing time keys, and the temporal-volume blocks around t) and with prefetch along
/// the camera's motion.
#[cfg(feature = "bevy")]
fn streaming_figures(pack: &Path, path: &CameraPath) -> Result<Option<String>, BoxError> {
    use bevy_plenoptic::PlenopticSettings;
    use bevy_plenoptic::streaming::schedule::{BlockRef, KeyRef, Lookahead, working_set};
    use bevy_plenoptic::streaming::{key_bytes, volume_bytes};

    const MIB: f64 = 1024.0 * 1024.0;
    let reader = plenoptic_pack::PackReader::open(pack)?;
    let settings = PlenopticSettings::default();
    let recon = bevy_plenoptic::ReconSettings::default();
    let look = Lookahead {
        settings: &recon,
        seconds: settings.prefetch_seconds,
    };
    let usable = bevy_plenoptic::asset::usable_views(&reader);
    // The decoded bytes of time keys and volume blocks (those the pack has).
    let bytes = |keys: &[KeyRef], blocks: &[BlockRef]| -> u64 {
        keys.iter().map(|&k| key_bytes(&reader, k)).sum::<u64>()
            + blocks
                .iter()
                .filter_map(|&b| volume_bytes(&reader, b))
                .sum::<u64>()
    };
    let frames: Vec<PathSample> = path.frames().collect();
    let (mut needed_max, mut needed_sum, mut all_max) = (0u64, 0u64, 0u64);
    for (i, s) in frames.iter().enumerate() {
        let next = frames.get(i + 1).unwrap_or(s);
        let dt = (next.path_time - s.path_time).max(1e-6);
        let velocity = (next.camera.position - s.camera.position) / dt;
        let direction = (next.scene_time - s.scene_time) / dt;
        let set = working_set(
            reader.manifest(),
            &usable,
            s.camera.position,
            velocity,
            s.scene_time,
            direction,
            look,
        );
        let needed = bytes(&set.needed, &set.volumes);
        let prefetch = bytes(&set.prefetch, &set.volume_prefetch);
        needed_max = needed_max.max(needed);
        needed_sum += needed;
        all_max = all_max.max(needed + prefetch);
    }
    let keys_decoded: u64 = (0..reader.manifest().base_views.len() as u32)
        .flat_map(|v| {
            let keys = reader.manifest().base_views[v as usize].time_keys.len() as u32;
            (0..keys).map(move |k| (v, k))
        })
        .map(|k| key_bytes(&reader, k))
        .sum();
    let volumes_decoded: u64 = reader
        .entries()
        .iter()
        .filter(|e| e.kind == plenoptic_pack::ChunkKind::VolumeBlock)
        .filter_map(|e| volume_bytes(&reader, (e.base_view, e.key)))
        .sum();
    let decoded = keys_decoded + volumes_decoded;
    Ok(Some(format!(
        "Streaming (bevy_plenoptic's working set with its default settings, {} views, {} s \
         prefetch, along all {} frames of the tour): needed per frame {:.1} MiB mean, {:.1} MiB \
         at most; with prefetch {:.1} MiB at most — of {:.1} MiB for the whole pack decoded \
         ({:.1} % resident at the peak).",
        recon.max_views,
        look.seconds,
        frames.len(),
        needed_sum as f64 / frames.len().max(1) as f64 / MIB,
        needed_max as f64 / MIB,
        all_max as f64 / MIB,
        decoded as f64 / MIB,
        100.0 * all_max as f64 / decoded.max(1) as f64
    )))
}

/// Without the plugin there is no working set to report.
#[cfg(not(feature = "bevy"))]
fn streaming_figures(_pack: &Path, _path: &CameraPath) -> Result<Option<String>, BoxError> {
    Ok(None)
}

/// Writes an endlessly looping GIF, `seconds` per frame.
fn write_gif(path: &Path, frames: Vec<RgbaImage>, seconds: f32) -> Result<(), BoxError> {
    let file = std::io::BufWriter::new(std::fs::File::create(path)?);
    // Speed 10 of 1..=30: good enough colour quantisation at a few ms per frame.
    let mut encoder = GifEncoder::new_with_speed(file, 10);
    encoder.set_repeat(Repeat::Infinite)?;
    let delay = Delay::from_numer_denom_ms((seconds * 1000.0).round().max(20.0) as u32, 1);
    encoder.encode_frames(
        frames
            .into_iter()
            .map(|image| GifFrame::from_parts(image, 0, 0, delay)),
    )?;
    Ok(())
}
