//! Reference frames: the path tracer of `plenoptic_trace` along a camera path, the ground
//! truth every reconstruction mode is compared with (thesis §6.7: "relative LRMS against
//! the fully rendered frame").
//!
//! Used by `plenoptic reference` and by the architectural tour's results. `plenoptic reference
//! --bake-lighting` renders the bake's lighting model at the cameras instead
//! ([`render_bake_lighting`]).

use std::path::Path;
use std::time::Instant;

use glam::Vec3;
use plenoptic_recon::{CameraPath, PathSample};
use plenoptic_scene::Scene;
use plenoptic_scene::recipe::Quality;
use plenoptic_trace::{
    AmbientField, Image, MultiStageRenderer, PathTracer, PathTracerSettings, PinholeCamera,
    PlacedScene, SceneAccel,
};

use crate::progress::Progress;
use crate::render::multi_stage_settings;
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
    let defaults = PathTracerSettings::default();
    let tracer = PathTracer::new(PathTracerSettings {
        samples_per_pixel: spp,
        seed: seed.unwrap_or(defaults.seed),
        ..defaults
    });
    render_frames(
        &accel,
        samples,
        out,
        exposure,
        progress,
        |placed, camera| Ok(tracer.render(placed, camera).radiance()),
    )
}

/// Final-gather rays per sample of [`render_bake_lighting`]: four times the bake's at
/// 64-px faces (`crate::render::final_gather_rays`), so that the frame's own noise is small.
pub const LIGHTING_GATHER_RAYS: u32 = 16;

/// The bake's lighting model at each camera of `samples`, written as [`render_reference`]
/// writes its frames: the multi-stage renderer over the bake's ambient field (built at each
/// frame's time with `quality`'s settings), as a range image's texels are rendered, but at the
/// camera's own pixels, with `spp` samples and [`LIGHTING_GATHER_RAYS`] final-gather rays
/// each. Judged against the path tracer, it separates the error of the lighting the bake
/// computes from what the pack and the runtime add (docs/fidelity.md, "Where the error is
/// made").
pub fn render_bake_lighting(
    scene: &Scene,
    quality: &Quality,
    samples: &[PathSample],
    (spp, seed): (u32, u64),
    out: &Path,
    exposure: Option<f32>,
    progress: &Progress,
) -> Result<ReferenceSummary> {
    let accel = SceneAccel::new(scene)?;
    let settings = multi_stage_settings(quality, seed, spp, LIGHTING_GATHER_RAYS);
    let ambient = crate::plan::ambient::field_settings(quality, seed);
    render_frames(
        &accel,
        samples,
        out,
        exposure,
        progress,
        |placed, camera| {
            let field = AmbientField::build(placed, &ambient)?;
            Ok(MultiStageRenderer::new(settings, &field)
                .render(placed, camera)
                .radiance())
        },
    )
}

/// Renders each of `samples` with `render` into `out` (the module's file layout).
fn render_frames(
    accel: &SceneAccel<'_>,
    samples: &[PathSample],
    out: &Path,
    exposure: Option<f32>,
    progress: &Progress,
    render: impl Fn(&PlacedScene<'_>, &PinholeCamera) -> Result<Image<Vec3>>,
) -> Result<ReferenceSummary> {
    std::fs::create_dir_all(out).map_err(|e| BakeError::io(out, e))?;
    let bar = progress.phase("reference", samples.len() as u64);
    let mut exposure = exposure;
    let clock = Instant::now();
    for f in samples {
        let camera = plenoptic_eval::camera::to_pinhole(&f.camera)
            .map_err(|e| BakeError::Invalid(format!("frame {}: {e}", f.index)))?;
        let placed = accel.at_time(f.scene_time);
        let image = render(&placed, &camera)?;
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
