//! A table lamp against the path tracer (pack 5's runtime lamps; docs/architecture.md, "The
//! runtime lamps"): a closed grey room, a small box on the floor, a point light 0.25 m above
//! the box's top. Seen from eye height, the top is a sliver a few pixels tall and several
//! times as bright as the box's sides; at 32-pixel cube faces a texel's samples mix the two.
//!
//! The same recipe is baked twice: with `quality.runtime_lamps` (the default) the lighting
//! leaves the lamp's direct diffuse light to the runtime, which adds it per pixel with a
//! shadow ray against the proxies; with `runtime_lamps = false` it stays in the texels.
//! Checked on the geometry-assisted frame: the box top's mean luminance within 5 % of the
//! reference's with runtime lamps (and closer than the baked pack's), and the whole frame's
//! mean within 3 %. Frames go to `target/tmp/runtime_lamps/`.

mod common;

use glam::Vec3;
use plenoptic_recon::{Camera, Frame, Mode, Reconstructor};
use plenoptic_scene::builder::{LightDesc, MaterialDesc, NodeDesc, SceneBuilder};
use plenoptic_trace::image::luminance;

/// The box's half-size and centre, and where the lamp hangs.
const BOX_HALF: f32 = 0.15;
const BOX_CENTRE: Vec3 = Vec3::new(0.0, -1.85, 0.0);
const LAMP: Vec3 = Vec3::new(0.0, -1.45, 0.0);

/// The closed room (inner half-size 2) with the box on its floor and the lamp above it.
fn scene() -> SceneBuilder {
    let mut b = SceneBuilder::new();
    let grey = b.add_material(MaterialDesc::diffuse(Vec3::splat(0.6)));
    common::room(&mut b, "room", Vec3::ZERO, 2.0, grey);
    let shade = b.add_material(MaterialDesc::diffuse(Vec3::new(0.8, 0.7, 0.5)));
    let mesh = b.add_box("box", Vec3::splat(2.0 * BOX_HALF), shade);
    b.add_node(NodeDesc::new("box").mesh(mesh).translation(BOX_CENTRE));
    b.add_node(
        NodeDesc::new("lamp")
            .light(LightDesc::point(Vec3::new(1.0, 0.85, 0.6), 2.0))
            .translation(LAMP),
    );
    b
}

/// Eye height, 1.6 m from the box, looking at it.
fn camera() -> Camera {
    Camera::look_at(
        Vec3::new(1.3, -0.3, 1.0),
        BOX_CENTRE,
        Vec3::Y,
        50f32.to_radians(),
        160,
        90,
    )
    .unwrap()
}

/// The pack of the recipe with `quality` lines added, opened.
fn bake(dir: &std::path::Path, quality: &str) -> Reconstructor {
    let quality = format!(
        "range_image_size = 32\nsamples_per_pixel = 8\nambient_samples = 64\n\
         ambient_rms = 0.1\nmax_specular_depth = 2\n{quality}"
    );
    let view = "kind = \"segment\"\na = [-1.0, -0.5, 1.0]\nb = [1.0, -0.5, 1.0]";
    let recipe = common::write_recipe(dir, &scene(), view, &quality);
    plenoptic_bake::bake_recipe(&recipe, &plenoptic_bake::BakeOptions::default()).unwrap();
    Reconstructor::open(dir.join("out/scene.pack")).unwrap()
}

/// Mean luminance of `image` over the pixels `which`.
fn mean(image: &dyn Fn(usize) -> Vec3, which: &[usize]) -> f64 {
    let sum: f64 = which.iter().map(|&j| f64::from(luminance(image(j)))).sum();
    sum / which.len().max(1) as f64
}

/// The pixels of `frame` whose point lies on the box's top.
fn box_top(frame: &Frame, camera: &Camera) -> Vec<usize> {
    let basis = camera.basis();
    let w = frame.width as usize;
    (0..frame.radiance.len())
        .filter(|&j| {
            let d = basis.direction((j % w) as f32 + 0.5, (j / w) as f32 + 0.5);
            let p = basis.position + d * frame.depth[j];
            let top = BOX_CENTRE.y + BOX_HALF;
            frame.depth[j].is_finite()
                && (p.y - top).abs() < 0.01
                && (p.x - BOX_CENTRE.x).abs() < BOX_HALF - 0.01
                && (p.z - BOX_CENTRE.z).abs() < BOX_HALF - 0.01
        })
        .collect()
}

#[test]
fn a_lamps_light_evaluated_per_pixel_lights_a_table_lamps_top_as_the_path_tracer_does() {
    let scene_dir = tempfile::tempdir().unwrap();
    let baked_dir = tempfile::tempdir().unwrap();
    let runtime = bake(scene_dir.path(), "");
    let baked = bake(baked_dir.path(), "runtime_lamps = false");
    assert!(
        runtime.pack().lamps_at_runtime(),
        "the default leaves the lamp to the runtime"
    );
    assert!(!baked.pack().lamps_at_runtime());

    let scene = plenoptic_scene::load(&scene_dir.path().join("scene.glb")).unwrap();
    let (camera, t) = (camera(), 0.5);
    let (a, b) = common::reference_halves(&scene, &camera, t, 256, 11);
    let reference = |j: usize| 0.5 * (a.pixels[j] + b.pixels[j]);
    let mut ratios = Vec::new();
    for (label, rec) in [("runtime", &runtime), ("baked", &baked)] {
        let (frame, _) = rec.render(&camera, t, Mode::GeometryAssisted).unwrap();
        common::save_frames("runtime_lamps", &format!("{label}_"), &a, &frame);
        let top = box_top(&frame, &camera);
        let all: Vec<usize> = (0..frame.radiance.len()).collect();
        let ours = |j: usize| frame.radiance[j];
        let top_ratio = mean(&ours, &top) / mean(&reference, &top);
        let frame_ratio = mean(&ours, &all) / mean(&reference, &all);
        println!(
            "lamp {label}: the box's top ({} pixels) {top_ratio:.4} of the path tracer's mean \
             luminance; the whole frame {frame_ratio:.4}",
            top.len()
        );
        assert!(
            top.len() >= 30,
            "the box's top is in view: {} pixels",
            top.len()
        );
        ratios.push((top_ratio, frame_ratio));
    }
    let [(top, frame), (baked_top, _)] = [ratios[0], ratios[1]];
    assert!((top - 1.0).abs() < 0.05, "the top at runtime: {top:.4}");
    assert!(
        (top - 1.0).abs() < (baked_top - 1.0).abs(),
        "runtime {top:.4} against baked {baked_top:.4}"
    );
    assert!((frame - 1.0).abs() < 0.03, "the whole frame: {frame:.4}");
}
