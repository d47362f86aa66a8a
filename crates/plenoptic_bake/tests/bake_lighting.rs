//! `plenoptic reference --bake-lighting` (`plenoptic_bake::reference::render_bake_lighting`):
//! the bake's lighting model rendered at a camera, which docs/fidelity.md ("Where the error is
//! made") judges against the path tracer.

mod common;

use common::*;
use plenoptic_bake::progress::Progress;
use plenoptic_bake::reference::{path_frames, render_bake_lighting, render_reference};
use plenoptic_eval::frame_io::read_exr;
use plenoptic_eval::metrics::mean_luminance_ratio;
use plenoptic_trace::Image;

/// In a closed room lit by a point lamp (a box on the floor), the bake's lighting at a
/// camera has the path tracer's mean within 5 %, and is a frame of its own (not a copy of
/// the tracer's): its pixels differ.
#[test]
fn the_bakes_lighting_at_a_camera_has_the_path_tracers_mean() {
    let dir = tempfile::tempdir().unwrap();
    let recipe = write_recipe(
        dir.path(),
        &static_room(),
        STATIC_SEGMENT,
        "ambient_samples = 64\nambient_rms = 0.1",
    );
    let (recipe, scene) = plenoptic_bake::input::load_recipe(&recipe).unwrap();
    let path = dir.path().join("path.json");
    std::fs::write(
        &path,
        r#"{ "frame_rate": 1.0, "width": 24, "height": 16, "keyframes": [
            { "time": 0.0, "position": [-0.8, 0.2, -0.8], "yaw_deg": 225.0, "pitch_deg": -10.0,
              "vfov_deg": 80.0 } ] }"#,
    )
    .unwrap();
    let samples = path_frames(&path, None).unwrap();
    let progress = Progress::new(false);
    let (lighting, reference) = (dir.path().join("lighting"), dir.path().join("reference"));
    let summary = render_bake_lighting(
        &scene,
        &recipe.quality,
        &samples,
        (32, 1),
        &lighting,
        Some(1.0),
        &progress,
    )
    .unwrap();
    assert_eq!(summary.frames, 1);
    render_reference(
        &scene,
        &samples,
        256,
        Some(5),
        &reference,
        Some(1.0),
        &progress,
    )
    .unwrap();
    let image = |dir: &std::path::Path| {
        let (width, height, pixels) = read_exr(dir.join("frame_00000.exr")).unwrap();
        Image {
            width,
            height,
            pixels,
        }
    };
    let (ours, truth) = (image(&lighting), image(&reference));
    assert_eq!((ours.width, ours.height), (24, 16));
    assert!(lighting.join("frame_00000.png").exists());
    let ratio = mean_luminance_ratio(&ours, &truth);
    println!("the bake's lighting over the path tracer's mean: {ratio:.3}");
    assert!((ratio - 1.0).abs() < 0.05, "mean ratio {ratio}");
    assert!(
        ours.pixels
            .iter()
            .zip(&truth.pixels)
            .any(|(a, b)| (*a - *b).length() > 1e-3)
    );
}
