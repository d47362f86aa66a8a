//! `--results DIR`: the tour's end-to-end figures, as the README shows them.
//!
//! 1. Reference frames: `plenoptic_trace`'s path tracer at N frames spread over the tour, as
//!    two independent halves (`reference` and `reference_seed2`, another seed each), whose
//!    mean is the reference and whose difference is its noise (docs/architecture.md,
//!    "Measuring against a noisy reference").
//! 2. The same frames reconstructed from the pack by `plenoptic_recon` in each mode
//!    (geometry-assisted, image, volume), timed.
//! 3. Per frame and mode (`tour_error.csv`): variance-corrected and uncorrected relative
//!    LRMS, PSNR, SSIM of the displayed frames and the mean-luminance ratio against the mean
//!    of the halves, with the reference's noise floor and the SSIM of one half against the
//!    other; the error-along-the-tour plot (`tour_error.svg`/`.png`, thesis figures 6.29
//!    and 6.31, with the noise floor).
//! 4. `montage.png`: three frames, one per row; columns reference, geometry-assisted, image,
//!    volume. Beside them, `geometry_radiance`: geometry-assisted mode showing the pack's
//!    radiance as version-1 packs were shown, from the same bake (equal bake time).
//! 5. `crop.png`: texture detail at full resolution. The centre 320 × 180 pixels of a
//!    1280 × 720 frame (rendered as a camera with the field of view of that crop, which
//!    gives the same pixels): reference | geometry-assisted | `geometry_radiance`, measured
//!    like the frames.
//! 6. `figures.md`: bake time per phase, pack size and its ratio to the raw range images,
//!    the errors per mode, CPU reconstruction time per frame at the path's own 640 × 360,
//!    the streaming working set along the whole tour (with the `bevy` feature; `--streaming`
//!    prints it alone), and the walk-through speed-up over path tracing every frame — beside
//!    the thesis's figures.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use image::{Rgb, RgbImage};
use plenoptic_bake::progress::Progress;
use plenoptic_eval::tools::{
    CandidateMetrics, Comparison, compare_with, frame_name, write_frame_files,
};
use plenoptic_pack::PackReader;
use plenoptic_recon::{Camera, CameraPath, Mode, PathSample, Reconstructor, Shading};
use plenoptic_scene::Scene;

use crate::BoxError;

/// The compared reconstructions: name, mode, how geometry-assisted mode shades. The first
/// three are the montage's columns (after the reference); the last is geometry-assisted mode
/// showing the baked radiance, as version-1 packs were shown, from the same bake (so at equal
/// bake time).
const CANDIDATES: [(&str, Mode, Shading); 4] = [
    ("geometry", Mode::GeometryAssisted, Shading::Materials),
    ("image", Mode::Image, Shading::Materials),
    ("volume", Mode::Volume, Shading::Materials),
    (
        "geometry_radiance",
        Mode::GeometryAssisted,
        Shading::Radiance,
    ),
];
/// Samples per pixel along each axis of the compared reconstructions by default
/// (`--supersampling`): a box filter over each pixel, as the references' pixels are. The
/// timings at the path's own size are taken at one sample per pixel, as a game would run.
pub const SUPERSAMPLING: u32 = 4;
/// How many of [`CANDIDATES`] the montage shows.
const MONTAGE_COLUMNS: usize = 3;
/// The full resolution the crop is cut from, and the crop's size (its centre).
const CROP_FULL: (u32, u32) = (1280, 720);
/// The crop's size in pixels.
const CROP: (u32, u32) = (320, 180);

/// What `--results` renders.
#[derive(Debug, Clone)]
pub struct ResultsOptions {
    /// Frames spread evenly over the tour.
    pub frames: usize,
    /// Reference samples per pixel, per half.
    pub spp: u32,
    /// Frame size of the compared frames.
    pub width: u32,
    /// Frame height.
    pub height: u32,
    /// Which of the frames the full-resolution crop is taken from.
    pub crop_frame: usize,
    /// Reference samples per pixel of the crop, per half.
    pub crop_spp: u32,
    /// Samples per pixel along each axis of the compared reconstructions
    /// ([`plenoptic_recon::ReconSettings::supersampling`]).
    pub supersampling: u32,
    /// Progress bars.
    pub progress: bool,
}

/// Per-candidate timing.
struct ModeTiming {
    name: &'static str,
    /// Mean CPU ms per frame at the compared size.
    ms_small: f64,
    /// Mean CPU ms per frame at the path's own size.
    ms_full: f64,
}

/// Each candidate's frame directory (label, directory), and its timing.
type Reconstructed = (Vec<(String, PathBuf)>, Vec<ModeTiming>);

/// Renders `samples` with every candidate in `names` into `<dir>/<name>`; returns the
/// directories and the timings (the path's own size `full` is timed, not written).
fn reconstruct(
    pack: &Path,
    names: &[&str],
    samples: &[PathSample],
    full: &[PathSample],
    dir: &Path,
    exposure: f32,
    supersampling: u32,
) -> Result<Reconstructed, BoxError> {
    let mut dirs = Vec::new();
    let mut timings = Vec::new();
    for (name, mode, shading) in CANDIDATES.into_iter().filter(|c| names.contains(&c.0)) {
        let mut rec = Reconstructor::open(pack)?;
        rec.settings.shading = shading;
        rec.settings.supersampling = supersampling;
        let out = dir.join(name);
        std::fs::create_dir_all(&out)?;
        // Untimed: decodes every cube these frames need into the reconstructor's cache, so
        // that the times below are reconstruction only.
        for s in samples {
            rec.render(&s.camera, s.scene_time, mode)?;
        }
        let mut ms = 0.0;
        for s in samples {
            let clock = Instant::now();
            let (frame, _) = rec.render(&s.camera, s.scene_time, mode)?;
            ms += clock.elapsed().as_secs_f64() * 1e3;
            write_frame_files(
                &out,
                s.index,
                frame.width,
                frame.height,
                &frame.radiance,
                Some(&frame.depth),
                exposure,
            )?;
        }
        rec.settings.supersampling = 1;
        let clock = Instant::now();
        for s in full {
            rec.render(&s.camera, s.scene_time, mode)?;
        }
        let ms_full = clock.elapsed().as_secs_f64() * 1e3 / full.len().max(1) as f64;
        dirs.push((name.to_owned(), out));
        timings.push(ModeTiming {
            name,
            ms_small: ms / samples.len().max(1) as f64,
            ms_full,
        });
    }
    Ok((dirs, timings))
}

/// The reference of `samples` as two halves in `<dir>/reference` and
/// `<dir>/reference_seed2`.
fn reference_halves(
    scene: &Scene,
    samples: &[PathSample],
    spp: u32,
    dir: &Path,
    progress: &Progress,
) -> Result<
    (
        plenoptic_bake::reference::ReferenceSummary,
        PathBuf,
        PathBuf,
    ),
    BoxError,
> {
    let (a, b) = (dir.join("reference"), dir.join("reference_seed2"));
    let summary =
        plenoptic_bake::reference::render_reference(scene, samples, spp, None, &a, None, progress)?;
    plenoptic_bake::reference::render_reference(
        scene,
        samples,
        spp,
        Some(0x5eed_0002),
        &b,
        Some(summary.exposure),
        progress,
    )?;
    Ok((summary, a, b))
}

/// The centre `CROP` of the `CROP_FULL` frame of `camera`: the same pixels, as a camera of
/// the crop's size whose field of view the crop spans.
fn crop_camera(camera: &Camera) -> Camera {
    let scale = CROP.1 as f32 / CROP_FULL.1 as f32;
    Camera {
        vfov: 2.0 * ((camera.vfov * 0.5).tan() * scale).atan(),
        width: CROP.0,
        height: CROP.1,
        ..*camera
    }
}

/// Runs the whole comparison into `dir`.
pub fn run(
    pack: &Path,
    recipe: &Path,
    path: &CameraPath,
    dir: &Path,
    o: &ResultsOptions,
) -> Result<(), BoxError> {
    let frames_dir = dir.join("frames");
    std::fs::create_dir_all(&frames_dir)?;
    let full = path.spread(o.frames);
    let mut small = full.clone();
    for s in &mut small {
        s.camera.width = o.width;
        s.camera.height = o.height;
    }
    let progress = Progress::new(o.progress);

    // 1. Reference, as two halves.
    let (_, scene) = plenoptic_bake::input::load_recipe(recipe)?;
    println!(
        "reference: {} frames of {}×{} at 2 × {} spp",
        small.len(),
        o.width,
        o.height,
        o.spp
    );
    let (reference, ref_a, ref_b) =
        reference_halves(&scene, &small, o.spp, &frames_dir, &progress)?;

    // 2. Each candidate, at the compared size (files) and at the path's size (time only).
    let names = CANDIDATES.map(|c| c.0);
    let (candidates, timings) = reconstruct(
        pack,
        &names,
        &small,
        &full,
        &frames_dir,
        reference.exposure,
        o.supersampling,
    )?;
    for t in &timings {
        println!(
            "{:>17}: {:.1} ms per frame at {}×{}, {:.1} ms at {}×{}",
            t.name, t.ms_small, o.width, o.height, t.ms_full, path.width, path.height
        );
    }

    // 3. Errors and the plot, against the mean of the halves.
    let comparison = compare(&ref_a, &ref_b, &candidates, dir, "tour_error")?;

    // 4. The montage.
    montage(
        &ref_a,
        &candidates[..MONTAGE_COLUMNS],
        &small,
        &dir.join("montage.png"),
    )?;

    // 5. The crop at full resolution.
    let frame = full
        .get(o.crop_frame)
        .ok_or_else(|| format!("--crop-frame {} of {} frames", o.crop_frame, full.len()))?;
    let crop_sample = PathSample {
        camera: crop_camera(&Camera {
            width: CROP_FULL.0,
            height: CROP_FULL.1,
            ..frame.camera
        }),
        ..*frame
    };
    let crop_dir = frames_dir.join("crop");
    println!(
        "crop: the centre {}×{} of frame {} at {}×{}, reference at 2 × {} spp",
        CROP.0, CROP.1, o.crop_frame, CROP_FULL.0, CROP_FULL.1, o.crop_spp
    );
    let samples = std::slice::from_ref(&crop_sample);
    let (crop_ref, crop_a, crop_b) =
        reference_halves(&scene, samples, o.crop_spp, &crop_dir, &progress)?;
    let (crop_candidates, _) = reconstruct(
        pack,
        &["geometry", "geometry_radiance"],
        samples,
        &[],
        &crop_dir,
        crop_ref.exposure,
        o.supersampling,
    )?;
    let crop = compare(&crop_a, &crop_b, &crop_candidates, &crop_dir, "crop_error")?;
    montage(&crop_a, &crop_candidates, samples, &dir.join("crop.png"))?;

    // 6. Figures.
    let text = figures(
        pack,
        path,
        &small,
        o,
        &reference,
        &timings,
        &comparison,
        &crop,
    )?;
    std::fs::write(dir.join("figures.md"), &text)?;
    println!("{text}");
    println!("results in {}", dir.display());
    Ok(())
}

/// Three frames (first, middle, last), one per row: the reference then each mode.
fn montage(
    ref_dir: &Path,
    candidates: &[(String, PathBuf)],
    samples: &[PathSample],
    out: &Path,
) -> Result<(), BoxError> {
    const GAP: u32 = 4;
    let n = samples.len();
    let mut rows: Vec<usize> = vec![0, n / 2, n.saturating_sub(1)];
    rows.dedup();
    let mut columns = vec![ref_dir.to_path_buf()];
    columns.extend(candidates.iter().map(|(_, d)| d.clone()));
    let load = |dir: &Path, index: usize| -> Result<RgbImage, BoxError> {
        let p = dir.join(frame_name(index, "png"));
        Ok(image::open(&p)
            .map_err(|e| format!("{}: {e}", p.display()))?
            .to_rgb8())
    };
    let first = load(ref_dir, samples[rows[0]].index)?;
    let (w, h) = first.dimensions();
    let cols = columns.len() as u32;
    let mut canvas = RgbImage::from_pixel(
        cols * w + (cols - 1) * GAP,
        rows.len() as u32 * h + (rows.len() as u32 - 1) * GAP,
        Rgb([255, 255, 255]),
    );
    for (r, &row) in rows.iter().enumerate() {
        for (c, dir) in columns.iter().enumerate() {
            let tile = load(dir, samples[row].index)?;
            image::imageops::replace(
                &mut canvas,
                &tile,
                i64::from(c as u32 * (w + GAP)),
                i64::from(r as u32 * (h + GAP)),
            );
        }
    }
    canvas.save(out)?;
    Ok(())
}

fn finite(v: &[f64]) -> impl Iterator<Item = f64> + '_ {
    v.iter().copied().filter(|x| x.is_finite())
}

fn mean(v: &[f64]) -> f64 {
    finite(v).sum::<f64>() / finite(v).count().max(1) as f64
}

fn min(v: &[f64]) -> f64 {
    finite(v).fold(f64::INFINITY, f64::min)
}

fn max(v: &[f64]) -> f64 {
    finite(v).fold(f64::NEG_INFINITY, f64::max)
}

/// A markdown row of one candidate's figures: corrected mean (best, worst), uncorrected
/// mean, PSNR, SSIM, mean-luminance ratio range, low-frequency error mean (worst).
fn metrics_row(m: &CandidateMetrics) -> String {
    format!(
        "| {} | {:.3} ({:.3}, {:.3}) | {:.3} | {:.1} | {:.3} | {:.2}–{:.2} | {:.3} ({:.3}) |",
        m.label,
        m.mean_corrected_lrms(),
        min(&m.corrected_lrms),
        max(&m.corrected_lrms),
        m.mean_lrms(),
        m.mean_psnr(),
        m.mean_ssim(),
        min(&m.mean_ratio),
        max(&m.mean_ratio),
        m.mean_low_frequency(),
        max(&m.low_frequency)
    )
}

const METRICS_HEAD: &str = "| candidate | relative LRMS, variance-corrected: mean (best, worst) | \
                            uncorrected mean | PSNR mean, dB | SSIM mean | mean-luminance ratio | \
                            low-frequency error: mean (worst) |\n\
                            |---|---|---|---|---|---|---|";

/// Compares `candidates` with the mean of the reference halves `a` and `b`, writes
/// `<stem>.csv` and the plot `<stem>.png` in `dir`, and prints the table.
fn compare(
    a: &Path,
    b: &Path,
    candidates: &[(String, PathBuf)],
    dir: &Path,
    stem: &str,
) -> Result<Comparison, BoxError> {
    let csv = dir.join(format!("{stem}.csv"));
    let comparison = compare_with(
        a,
        Some(b),
        candidates,
        &csv,
        &dir.join(format!("{stem}.png")),
    )?;
    print!("{}", comparison.table());
    Ok(comparison)
}

/// The figures table (markdown).
#[allow(
    clippy::too_many_arguments,
    reason = "one call site, each argument a figure's source"
)]
fn figures(
    pack: &Path,
    path: &CameraPath,
    samples: &[PathSample],
    o: &ResultsOptions,
    reference: &plenoptic_bake::reference::ReferenceSummary,
    timings: &[ModeTiming],
    comparison: &Comparison,
    crop: &Comparison,
) -> Result<String, BoxError> {
    let reader = PackReader::open(pack)?;
    let manifest = reader.manifest();
    let range_images: usize = manifest.base_views.iter().map(|v| v.time_keys.len()).sum();
    let mut s = String::new();
    writeln!(
        s,
        "Architectural tour: {} base views, {range_images} range images of 6 × {}², \
         {} frames compared at {}×{} against a path-traced reference of two halves of {} spp \
         each.\n",
        manifest.base_views.len(),
        f64::from(manifest.bake.cube_face_size),
        samples.len(),
        o.width,
        o.height,
        o.spp
    )?;
    let bake_total = bake_phases(&mut s, pack)?;
    pack_size(&mut s, &reader, range_images)?;
    errors(&mut s, path, o, timings, comparison, crop)?;
    let speed_up = walkthrough(&mut s, path, o, reference, timings, bake_total)?;
    if let Some(line) = crate::streaming_figures(pack, path)? {
        writeln!(s, "\n{line}")?;
    }
    thesis_table(&mut s, comparison, speed_up)?;
    Ok(s)
}

/// The bake's seconds per phase (from `<pack>.timings.json`) as a table; returns their total.
fn bake_phases(s: &mut String, pack: &Path) -> Result<f64, BoxError> {
    writeln!(s, "| bake phase | seconds |\n|---|---|")?;
    let mut bake_total = 0.0;
    let timings_file = PathBuf::from(format!("{}.timings.json", pack.display()));
    match std::fs::read_to_string(&timings_file)
        .ok()
        .and_then(|t| serde_json::from_str::<serde_json::Map<String, serde_json::Value>>(&t).ok())
    {
        Some(map) => {
            for (phase, v) in &map {
                let secs = v.as_f64().unwrap_or(0.0);
                bake_total += secs;
                writeln!(s, "| {phase} | {secs:.1} |")?;
            }
            writeln!(s, "| total | {bake_total:.1} |\n")?;
        }
        None => writeln!(s, "| (no {} ) | |\n", timings_file.display())?,
    }
    Ok(bake_total)
}

/// The pack's size: the file, its range-image chunks stored and as texels, and the range
/// images as rendered.
fn pack_size(s: &mut String, reader: &PackReader, range_images: usize) -> std::fmt::Result {
    const MIB: f64 = 1024.0 * 1024.0;
    let face = f64::from(reader.manifest().bake.cube_face_size);
    // Every range-image cube: radiance, lighting and non-diffuse (pack 2.0), distance, id,
    // normal.
    let (stored, texel_bytes) = reader
        .entries()
        .iter()
        .filter(|e| e.kind.is_cube())
        .fold((0u64, 0u64), |(s, t), e| {
            (s + e.length, t + e.uncompressed_length)
        });
    // A range image as rendered: RGB f32 radiance, lighting and non-diffuse + f32 distance +
    // u32 id + RGB f32 normal.
    let raw = range_images as f64 * 6.0 * face * face * 56.0;
    let file = reader.file_length() as f64;
    writeln!(
        s,
        "Pack: {:.1} MiB; range-image chunks {:.1} MiB stored, {:.1} MiB as texels \
         (RGB9E5 ×3 / R32F / R32Uint / RG16Snorm, {:.2} : 1 by zstd), {:.1} MiB as rendered \
         (f32 radiance, lighting, non-diffuse, distance, id, normal: {:.1} : 1 overall).\n",
        file / MIB,
        stored as f64 / MIB,
        texel_bytes as f64 / MIB,
        texel_bytes as f64 / stored.max(1) as f64,
        raw / MIB,
        raw / stored.max(1) as f64
    )
}

/// The errors along the tour and in the crop, the reference's noise floor, and the CPU
/// time per frame of each mode.
fn errors(
    s: &mut String,
    path: &CameraPath,
    o: &ResultsOptions,
    timings: &[ModeTiming],
    comparison: &Comparison,
    crop: &Comparison,
) -> std::fmt::Result {
    writeln!(
        s,
        "Along the tour, against the mean of the two halves:\n\n{METRICS_HEAD}"
    )?;
    for m in &comparison.candidates {
        writeln!(s, "{}", metrics_row(m))?;
    }
    let floor = comparison.noise_floor.as_deref().unwrap_or(&[]);
    let halves_ssim = comparison.halves_ssim.as_deref().unwrap_or(&[]);
    writeln!(
        s,
        "\nThe reference's noise floor (relative LRMS of (A − B)/2, what a perfect frame scores \
         uncorrected): mean {:.3} ({:.3}–{:.3}); SSIM of half A against half B: {:.3}.\n",
        mean(floor),
        min(floor),
        max(floor),
        mean(halves_ssim)
    )?;

    writeln!(
        s,
        "The reconstructions compared above are supersampled {n} × {n} per pixel (a box filter \
         over the pixel, as the references' pixels are; `--supersampling`); the CPU times at the \
         path's own size are at one sample per pixel.\n\n\
         | mode | CPU ms/frame {}×{}, {n} × {n} samples | CPU ms/frame {}×{} |\n|---|---|---|",
        o.width,
        o.height,
        path.width,
        path.height,
        n = o.supersampling,
    )?;
    for t in timings {
        writeln!(s, "| {} | {:.1} | {:.1} |", t.name, t.ms_small, t.ms_full)?;
    }

    writeln!(
        s,
        "\nThe crop (`crop.png`): the centre {}×{} of frame {} at {}×{}, reference at 2 × {} spp:\n\n{METRICS_HEAD}",
        CROP.0, CROP.1, o.crop_frame, CROP_FULL.0, CROP_FULL.1, o.crop_spp
    )?;
    for m in &crop.candidates {
        writeln!(s, "{}", metrics_row(m))?;
    }
    writeln!(
        s,
        "\nThe crop's noise floor: {:.3}.",
        crop.mean_noise_floor()
    )
}

/// Walk-through construction vs path tracing every frame of the tour at the path's size
/// (the reference took `seconds_per_frame` per half); returns the speed-up.
fn walkthrough(
    s: &mut String,
    path: &CameraPath,
    o: &ResultsOptions,
    reference: &plenoptic_bake::reference::ReferenceSummary,
    timings: &[ModeTiming],
    bake_total: f64,
) -> Result<f64, std::fmt::Error> {
    let tour_frames = path.frame_count() as f64;
    let scale = f64::from(path.width * path.height) / f64::from(o.width * o.height);
    let path_traced = tour_frames * 2.0 * reference.seconds_per_frame * scale;
    let geometry_ms = timings
        .iter()
        .find(|t| t.name == "geometry")
        .map_or(0.0, |t| t.ms_full);
    let walkthrough = bake_total + tour_frames * geometry_ms / 1e3;
    let speed_up = path_traced / walkthrough.max(1e-9);
    writeln!(
        s,
        "\nWalk-through of the whole tour ({tour_frames:.0} frames of {}×{}): bake {bake_total:.0} s \
         + geometry-assisted reconstruction {:.0} s = {walkthrough:.0} s, against {:.0} s to path-trace \
         every frame at {} spp ({:.1} s per {}×{} frame and half measured, scaled by pixel count): {:.1}× faster.",
        path.width,
        path.height,
        tour_frames * geometry_ms / 1e3,
        path_traced,
        2 * o.spp,
        reference.seconds_per_frame,
        o.width,
        o.height,
        speed_up
    )?;
    Ok(speed_up)
}

/// Our figures beside the thesis's: the best spatial error, the temporal error and the
/// walk-through speed-up.
fn thesis_table(s: &mut String, comparison: &Comparison, speed_up: f64) -> std::fmt::Result {
    let geometry = comparison
        .candidates
        .iter()
        .find(|m| m.label == "geometry")
        .cloned()
        .unwrap_or_default();
    let best = comparison
        .candidates
        .iter()
        .map(|m| min(&m.corrected_lrms))
        .fold(f64::INFINITY, f64::min);
    writeln!(
        s,
        "\n| thesis figure | thesis | ours (variance-corrected; uncorrected) |\n|---|---|---|\n\
         | spatial reconstruction, best relative LRMS (table 6.1) | 0.117 | {best:.3}; {:.3} (best frame of any mode) |\n\
         | temporal reconstruction, relative LRMS (table 6.3) | 0.576 | {:.3}; {:.3} (geometry-assisted, mean along the tour) |\n\
         | walk-through construction vs full rendering (table 6.4) | 8.6–46× | {:.1}× |",
        comparison
            .candidates
            .iter()
            .map(|m| min(&m.relative_lrms))
            .fold(f64::INFINITY, f64::min),
        geometry.mean_corrected_lrms(),
        geometry.mean_lrms(),
        speed_up
    )
}
