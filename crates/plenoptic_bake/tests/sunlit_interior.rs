//! A sunlit interior against the path tracer: a closed room whose one window is glazed as CAD
//! exporters write glass (a pane 1 cm thick, `alphaMode: BLEND`, alpha 0.12), the sun shining
//! through it onto the floor. The path tracer's shadow rays pass each of the pane's two
//! surfaces with probability 0.88 (coverage, `plenoptic_trace::alpha`); the bake leaves the
//! sun's direct light to the runtime, whose shadow rays must pass the pane the same way
//! (`plenoptic_recon::shadow`, `PlacedShadows::transmittance`), or the sun patch is lost
//! and the room is lit by its bounces alone.
//!
//! Checked on the geometry-assisted frame: the sunlit floor pixels' mean luminance within 5 %
//! of the reference's, the whole frame's within 3 %. Frames go to
//! `target/tmp/sunlit_interior/`.

mod common;

use common::sunlit_room::{camera, scene, sunlit};
use glam::Vec3;
use plenoptic_recon::{Mode, Reconstructor};
use plenoptic_trace::image::luminance;

#[test]
fn sun_through_a_glazed_window_lights_the_floor_as_the_path_tracer_does() {
    let dir = tempfile::tempdir().unwrap();
    let quality = "range_image_size = 32\nsamples_per_pixel = 8\nambient_samples = 64\n\
                   ambient_rms = 0.1\nmax_specular_depth = 2";
    let view = "kind = \"segment\"\na = [-1.2, 0.0, -1.0]\nb = [-0.4, 0.0, 0.6]";
    let recipe = common::write_recipe(dir.path(), &scene(), view, quality);
    plenoptic_bake::bake_recipe(&recipe, &plenoptic_bake::BakeOptions::default()).unwrap();
    let scene = plenoptic_scene::load(&dir.path().join("scene.glb")).unwrap();
    let (width, height) = (160, 90);
    let camera = camera(width, height);
    let t = 0.5;
    let (a, b) = common::reference_halves(&scene, &camera, t, 256, 7);
    let rec = Reconstructor::open(dir.path().join("out/scene.pack")).unwrap();
    assert!(
        rec.runtime_sun().is_some(),
        "the bake leaves the sun to the runtime"
    );
    let (frame, _) = rec.render(&camera, t, Mode::GeometryAssisted).unwrap();
    common::save_frames("sunlit_interior", "", &a, &frame);

    let basis = camera.basis();
    let w = width as usize;
    let point = |j: usize| {
        let d = basis.direction((j % w) as f32 + 0.5, (j / w) as f32 + 0.5);
        basis.position + d * frame.depth[j]
    };
    let lit: Vec<usize> = (0..frame.radiance.len())
        .filter(|&j| frame.depth[j].is_finite() && sunlit(point(j)))
        .collect();
    let all: Vec<usize> = (0..frame.radiance.len()).collect();
    let mean = |img: &dyn Fn(usize) -> Vec3, which: &[usize]| {
        which
            .iter()
            .map(|&j| f64::from(luminance(img(j))))
            .sum::<f64>()
            / which.len() as f64
    };
    let reference = |j: usize| 0.5 * (a.pixels[j] + b.pixels[j]);
    let ours = |j: usize| frame.radiance[j];
    let lit_ratio = mean(&ours, &lit) / mean(&reference, &lit);
    let frame_ratio = mean(&ours, &all) / mean(&reference, &all);
    println!(
        "sunlit floor ({} of {} pixels): mean luminance {lit_ratio:.4} of the path tracer's; \
         whole frame {frame_ratio:.4}",
        lit.len(),
        all.len()
    );
    assert!(
        lit.len() > 400,
        "the sun patch is in view: {} pixels",
        lit.len()
    );
    assert!(
        (lit_ratio - 1.0).abs() < 0.05,
        "sunlit pixels: {lit_ratio:.4}"
    );
    assert!(
        (frame_ratio - 1.0).abs() < 0.03,
        "whole frame: {frame_ratio:.4}"
    );
}
