//! `--results DIR`: the tour's end-to-end figures, as the README shows them.
//!
//! 1. Reference frames: `plenoptic_trace`'s path tracer at N frames spread over the tour;
//!    and a second reference with another seed, whose error against the first is the
//!    reference's own noise (the floor under every mode's measured error).
//! 2. The same frames reconstructed from the pack by `plenoptic_recon` in each mode
//!    (geometry-assisted, image, volume), timed.
//! 3. Relative LRMS and PSNR per frame and mode against the reference
//!    (`tour_error.csv`) and the error-along-the-tour plot (`tour_error.png`, thesis
//!    figures 6.29 and 6.31).
//! 4. `montage.png`: three frames, one per row; columns reference, geometry-assisted, image,
//!    volume. Beside them, `geometry_radiance`: geometry-assisted mode showing the pack's
//!    radiance as version-1 packs were shown, from the same bake (equal bake time).
//! 5. `figures.md`: bake time per phase, pack size and its ratio to the raw range images,
//!    error per mode, CPU reconstruction time per frame at the path's own 640 × 360, the
//!    streaming working set along the whole tour (with the `bevy` feature; `--streaming`
//!    prints it alone), and the walk-through speed-up over path tracing every frame — beside
//!    the thesis's figures.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use image::{Rgb, RgbImage};
use plenoptic_bake::progress::Progress;
use plenoptic_eval::tools::{compare, frame_name, write_frame_files};
use plenoptic_pack::PackReader;
use plenoptic_recon::{CameraPath, Mode, PathSample, Reconstructor, Shading};

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
/// How many of [`CANDIDATES`] the montage shows.
const MONTAGE_COLUMNS: usize = 3;

/// What `--results` renders.
#[derive(Debug, Clone)]
pub struct ResultsOptions {
    /// Frames spread evenly over the tour.
    pub frames: usize,
    /// Reference samples per pixel.
    pub spp: u32,
    /// Frame size of the compared frames.
    pub width: u32,
    /// Frame height.
    pub height: u32,
    /// Progress bars.
    pub progress: bool,
}

/// Per-candidate outcome.
struct ModeResult {
    name: &'static str,
    lrms: Vec<f64>,
    psnr: Vec<f64>,
    /// Mean CPU ms per frame at the compared size.
    ms_small: f64,
    /// Mean CPU ms per frame at the path's own size.
    ms_full: f64,
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
    let full = crate::spread_samples(path, o.frames);
    let mut small = full.clone();
    for s in &mut small {
        s.camera.width = o.width;
        s.camera.height = o.height;
    }
    let progress = Progress::new(o.progress);

    // 1. Reference.
    let (_, scene) = plenoptic_bake::input::load_recipe(recipe)?;
    let ref_dir = frames_dir.join("reference");
    println!(
        "reference: {} frames of {}×{} at {} spp",
        small.len(),
        o.width,
        o.height,
        o.spp
    );
    let reference = plenoptic_bake::reference::render_reference(
        &scene, &small, o.spp, None, &ref_dir, None, &progress,
    )?;
    let second = frames_dir.join("reference_seed2");
    plenoptic_bake::reference::render_reference(
        &scene,
        &small,
        o.spp,
        Some(0x5eed_0002),
        &second,
        Some(reference.exposure),
        &progress,
    )?;

    // 2. Each candidate, at the compared size (files) and at the path's size (time only).
    let mut results = Vec::new();
    let mut candidates = Vec::new();
    for (name, mode, shading) in CANDIDATES {
        let mut rec = Reconstructor::open(pack)?;
        rec.settings.shading = shading;
        let out = frames_dir.join(name);
        std::fs::create_dir_all(&out)?;
        // Untimed: decodes every cube these frames need into the reconstructor's cache, so
        // that the times below are reconstruction only.
        for s in &small {
            rec.render(&s.camera, s.scene_time, mode)?;
        }
        let mut ms = 0.0;
        for s in &small {
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
                reference.exposure,
            )?;
        }
        let clock = Instant::now();
        for s in &full {
            rec.render(&s.camera, s.scene_time, mode)?;
        }
        let ms_full = clock.elapsed().as_secs_f64() * 1e3 / full.len().max(1) as f64;
        println!(
            "{name:>17}: {:.1} ms per frame at {}×{}, {ms_full:.1} ms at {}×{}",
            ms / small.len().max(1) as f64,
            o.width,
            o.height,
            path.width,
            path.height
        );
        candidates.push((name.to_owned(), out));
        results.push(ModeResult {
            name,
            lrms: Vec::new(),
            psnr: Vec::new(),
            ms_small: ms / small.len().max(1) as f64,
            ms_full,
        });
    }

    // 3. Errors and the plot; the second reference is the noise floor.
    candidates.push(("reference noise".to_owned(), second));
    let metrics = compare(
        &ref_dir,
        &candidates,
        &dir.join("tour_error.csv"),
        &dir.join("tour_error.png"),
    )?;
    let floor = metrics.last().cloned().unwrap_or_default();
    candidates.pop();
    for (r, m) in results.iter_mut().zip(metrics) {
        r.lrms = m.relative_lrms;
        r.psnr = m.psnr;
    }

    // 4. The montage.
    montage(
        &ref_dir,
        &candidates[..MONTAGE_COLUMNS],
        &small,
        &dir.join("montage.png"),
    )?;

    // 5. Figures.
    let text = figures(pack, path, &small, o, &reference, &results, &floor)?;
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

fn mean(v: &[f64]) -> f64 {
    let f: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    f.iter().sum::<f64>() / f.len().max(1) as f64
}

fn min(v: &[f64]) -> f64 {
    v.iter()
        .copied()
        .filter(|x| x.is_finite())
        .fold(f64::INFINITY, f64::min)
}

/// The figures table (markdown).
fn figures(
    pack: &Path,
    path: &CameraPath,
    samples: &[PathSample],
    o: &ResultsOptions,
    reference: &plenoptic_bake::reference::ReferenceSummary,
    results: &[ModeResult],
    floor: &plenoptic_eval::tools::CandidateMetrics,
) -> Result<String, BoxError> {
    const MIB: f64 = 1024.0 * 1024.0;
    let reader = PackReader::open(pack)?;
    let manifest = reader.manifest();
    let face = f64::from(manifest.bake.cube_face_size);
    let range_images: usize = manifest.base_views.iter().map(|v| v.time_keys.len()).sum();
    // Every range-image cube: radiance, lighting and non-diffuse (pack 2.0), distance, id,
    // normal.
    let cube_chunks = |e: &&plenoptic_pack::ChunkEntry| e.kind.is_cube();
    let stored: u64 = reader
        .entries()
        .iter()
        .filter(cube_chunks)
        .map(|e| e.length)
        .sum();
    let texel_bytes: u64 = reader
        .entries()
        .iter()
        .filter(cube_chunks)
        .map(|e| e.uncompressed_length)
        .sum();
    // A range image as rendered: RGB f32 radiance, lighting and non-diffuse + f32 distance +
    // u32 id + RGB f32 normal.
    let raw = range_images as f64 * 6.0 * face * face * 56.0;
    let file = reader.file_length() as f64;

    let mut s = String::new();
    writeln!(
        s,
        "Architectural tour: {} base views, {range_images} range images of 6 × {face}², \
         {} frames compared at {}×{} against a {} spp path-traced reference.\n",
        manifest.base_views.len(),
        samples.len(),
        o.width,
        o.height,
        o.spp
    )?;

    writeln!(s, "| bake phase | seconds |\n|---|---|")?;
    let mut bake_total = 0.0;
    let timings = PathBuf::from(format!("{}.timings.json", pack.display()));
    match std::fs::read_to_string(&timings)
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
        None => writeln!(s, "| (no {} ) | |\n", timings.display())?,
    }

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
    )?;

    writeln!(
        s,
        "| mode | relative LRMS mean (best frame) | PSNR mean, dB | CPU ms/frame {}×{} | CPU ms/frame {}×{} |\n|---|---|---|---|---|",
        o.width, o.height, path.width, path.height
    )?;
    for r in results {
        writeln!(
            s,
            "| {} | {:.3} ({:.3}) | {:.1} | {:.1} | {:.1} |",
            r.name,
            mean(&r.lrms),
            min(&r.lrms),
            mean(&r.psnr),
            r.ms_small,
            r.ms_full
        )?;
    }
    writeln!(
        s,
        "| reference noise (a second reference, another seed) | {:.3} ({:.3}) | {:.1} | | |",
        mean(&floor.relative_lrms),
        min(&floor.relative_lrms),
        mean(&floor.psnr)
    )?;

    // Walk-through construction vs path tracing every frame of the tour at the path's size.
    let tour_frames = path.frame_count() as f64;
    let scale = f64::from(path.width * path.height) / f64::from(o.width * o.height);
    let path_traced = tour_frames * reference.seconds_per_frame * scale;
    let geometry_ms = results
        .iter()
        .find(|r| r.name == "geometry")
        .map_or(0.0, |r| r.ms_full);
    let walkthrough = bake_total + tour_frames * geometry_ms / 1e3;
    writeln!(
        s,
        "\nWalk-through of the whole tour ({tour_frames:.0} frames of {}×{}): bake {bake_total:.0} s \
         + geometry-assisted reconstruction {:.0} s = {walkthrough:.0} s, against {:.0} s to path-trace \
         every frame at {} spp ({:.1} s per {}×{} frame measured, scaled by pixel count): {:.1}× faster.",
        path.width,
        path.height,
        tour_frames * geometry_ms / 1e3,
        path_traced,
        o.spp,
        reference.seconds_per_frame,
        o.width,
        o.height,
        path_traced / walkthrough.max(1e-9)
    )?;

    if let Some(line) = crate::streaming_figures(pack, path)? {
        writeln!(s, "\n{line}")?;
    }

    let best = results
        .iter()
        .map(|r| min(&r.lrms))
        .fold(f64::INFINITY, f64::min);
    let geometry = results
        .iter()
        .find(|r| r.name == "geometry")
        .map_or(f64::NAN, |r| mean(&r.lrms));
    writeln!(
        s,
        "\n| thesis figure | thesis | ours |\n|---|---|---|\n\
         | spatial reconstruction, best relative LRMS (table 6.1) | 0.117 | {best:.3} (best frame of any mode) |\n\
         | temporal reconstruction, relative LRMS (table 6.3) | 0.576 | {geometry:.3} (geometry-assisted, mean along the tour) |\n\
         | walk-through construction vs full rendering (table 6.4) | 8.6–46× | {:.1}× |",
        path_traced / walkthrough.max(1e-9)
    )?;
    Ok(s)
}
