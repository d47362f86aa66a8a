//! Reference frames: the path tracer of `plenoptic_trace` along a camera path, the ground
//! truth every reconstruction mode is compared with (thesis §6.7: "relative LRMS against
//! the fully rendered frame").
//!
//! Used by `plenoptic reference` and by the architectural tour's results.

use std::path::Path;
use std::time::Instant;

use plenoptic_recon::{CameraPath, PathSample};
use plenoptic_scene::Scene;
use plenoptic_trace::{PathTracer, PathTracerSettings, SceneAccel};

use crate::progress::Progress;
use crate::{BakeError, Result};

/// What [`render_reference`] did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ReferenceSummary {
    /// Frames written.
    pub frames: usize,
    /// The exposure of the PNGs.
    pub exposure: f32,
    /// Mean wall-clock seconds per frame.
    pub seconds_per_frame: f64,
}

/// Path-traces `samples` of a camera path through `scene` with `spp` samples per pixel into
/// `out` (`frame_NNNNN.exr` linear and `.png` tonemapped with `exposure`, or with the first
/// frame's automatic exposure when `None`). `seed` picks the random sequence (`None`: the
/// tracer's default); two seeds give independent references, whose difference measures the
/// reference's own noise.
pub fn render_reference(
    scene: &Scene,
    samples: &[PathSample],
    spp: u32,
    seed: Option<u64>,
    out: &Path,
    exposure: Option<f32>,
    progress: &Progress,
) -> Result<ReferenceSummary> {
    let accel = SceneAccel::new(scene)?;
    std::fs::create_dir_all(out).map_err(|e| BakeError::io(out, e))?;
    let defaults = PathTracerSettings::default();
    let tracer = PathTracer::new(PathTracerSettings {
        samples_per_pixel: spp,
        seed: seed.unwrap_or(defaults.seed),
        ..defaults
    });
    let bar = progress.phase("reference", samples.len() as u64);
    let mut exposure = exposure;
    let clock = Instant::now();
    for f in samples {
        let camera = plenoptic_eval::camera::to_pinhole(&f.camera)
            .map_err(|e| BakeError::Invalid(format!("frame {}: {e}", f.index)))?;
        let placed = accel.at_time(f.scene_time);
        let image = tracer.render(&placed, &camera).radiance();
        let e =
            *exposure.get_or_insert_with(|| plenoptic_eval::frame_io::auto_exposure(&image.pixels));
        plenoptic_eval::tools::write_frame_files(
            out,
            f.index,
            image.width,
            image.height,
            &image.pixels,
            None,
            e,
        )
        .map_err(|e| BakeError::Invalid(format!("frame {}: {e}", f.index)))?;
        bar.inc(1);
    }
    bar.finish_and_clear();
    Ok(ReferenceSummary {
        frames: samples.len(),
        exposure: exposure.unwrap_or(1.0),
        seconds_per_frame: clock.elapsed().as_secs_f64() / samples.len().max(1) as f64,
    })
}

/// The frames of the camera path file `path` (its frame rate and size): every frame, or
/// `spread` frames spread evenly over it ([`CameraPath::spread`]).
pub fn path_frames(path: &Path, spread: Option<usize>) -> Result<Vec<PathSample>> {
    let camera_path = CameraPath::load(path)
        .map_err(|e| BakeError::Invalid(format!("{}: {e}", path.display())))?;
    Ok(match spread {
        Some(n) => camera_path.spread(n),
        None => camera_path.frames().collect(),
    })
}
