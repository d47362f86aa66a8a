//! Light groups against the path tracer: the sunlit room of `sunlit_interior.rs` with a lamp,
//! its emitters in two groups (`lamp`: the lamp; `daylight`: the sun and a uniform sky). One
//! bake stores each group's light apart (docs/pack-format.md, "Light groups"); the
//! geometry-assisted frame at group intensities (1, 1), (1, 0), (0, 1) and (0.5, 2) is
//! compared with a reference path-traced at the same intensities (`Scene::relit`), and with
//! the frame of an ungrouped bake of the room whose emitters are set to those intensities in
//! the scene itself (what a user without groups would have to bake):
//!
//! - mean luminance within 3 % of the reference's;
//! - corrected relative LRMS within 1.2× of the ungrouped bake's at the same intensities;
//!   at (1, 1) that is the grouped pack against one ungrouped bake.
//!
//! The LRMS relative to the (1, 1) frame's is printed too: the daylight alone is a frame of
//! higher contrast (a sun patch ten times brighter than the room), whose error relative to
//! its mean is larger for any bake. Frames go to `target/tmp/light_groups/`.

mod common;

use std::path::Path;

use common::sunlit_room::{camera, scene_with_sun};
use glam::Vec3;
use plenoptic_bake::BakeOptions;
use plenoptic_eval::metrics::{corrected_relative_lrms, mean_image, mean_luminance_ratio};
use plenoptic_pack::GroupWeights;
use plenoptic_recon::{Mode, Reconstructor};
use plenoptic_scene::builder::{LightDesc, NodeDesc, SceneBuilder};
use plenoptic_trace::Image;

const QUALITY: &str = "range_image_size = 32\nsamples_per_pixel = 8\nambient_samples = 64\n\
                       ambient_rms = 0.1\nmax_specular_depth = 2";
const VIEW: &str = "kind = \"segment\"\na = [-1.2, 0.0, -1.0]\nb = [-0.4, 0.0, 0.6]";
const GROUPS: &str = "[[light_group]]\nname = \"lamp\"\nemitters = [\"Lamp\"]\n\n\
                      [[light_group]]\nname = \"daylight\"\nemitters = [\"sun\", \"sky\"]\n";
const SIZE: (u32, u32) = (160, 90);
const T: f32 = 0.5;
/// The sun's illuminance, the lamp's intensity and the sky's radiance at weight 1.
const SUN: f32 = 4.0;
const LAMP: f32 = 3.0;
const SKY: Vec3 = Vec3::new(0.25, 0.3, 0.4);

/// The sunlit room with a warm lamp near the ceiling, away from the window; the lamp and the
/// sun at `lamp` and `daylight` times their intensities.
fn lit_room(lamp: f32, daylight: f32) -> SceneBuilder {
    let mut b = scene_with_sun(SUN * daylight);
    b.add_node(
        NodeDesc::new("LampNode")
            .light(LightDesc::point(Vec3::new(1.0, 0.85, 0.7), LAMP * lamp).named("Lamp"))
            .translation(Vec3::new(-1.2, 1.4, 1.0)),
    );
    b
}

/// The `[sky]` table with the sky at `daylight` times its radiance.
fn sky(daylight: f32) -> String {
    let c = SKY * daylight;
    format!(
        "[sky]\nkind = \"uniform\"\ncolor = [{}, {}, {}]\n",
        c.x, c.y, c.z
    )
}

/// Bakes `room` with `extra` recipe tables into `dir`; returns the recipe's path.
fn bake(dir: &Path, room: &SceneBuilder, extra: &str) -> std::path::PathBuf {
    let recipe = common::write_recipe_with(dir, room, VIEW, QUALITY, extra);
    plenoptic_bake::bake_recipe(&recipe, &BakeOptions::default()).unwrap();
    recipe
}

/// The geometry-assisted frame of `rec` as an image.
fn frame(rec: &Reconstructor) -> Image<Vec3> {
    let (frame, _) = rec
        .render(&camera(SIZE.0, SIZE.1), T, Mode::GeometryAssisted)
        .unwrap();
    Image {
        width: SIZE.0,
        height: SIZE.1,
        pixels: frame.radiance,
    }
}

#[test]
fn groups_relight_the_room_as_the_path_tracer_and_a_bake_of_that_lighting_do() {
    let dir = tempfile::tempdir().unwrap();
    let recipe = bake(
        dir.path(),
        &lit_room(1.0, 1.0),
        &format!("{}\n{GROUPS}", sky(1.0)),
    );
    let (_, scene) = plenoptic_bake::input::load_recipe(&recipe).unwrap();
    assert_eq!(scene.light_groups.names, ["lamp", "daylight"]);
    let mut rec = Reconstructor::open(dir.path().join("out/scene.pack")).unwrap();
    let entry = rec.pack().manifest().light_groups.clone().unwrap();
    assert!(!entry.default_has_emitters, "every emitter is in a group");
    let camera = camera(SIZE.0, SIZE.1);
    radiance_cubes_relight_linearly(&rec);

    let mut at_one = None;
    for (lamp, daylight) in [(1.0, 1.0), (1.0, 0.0), (0.0, 1.0), (0.5, 2.0)] {
        let settings = [format!("lamp={lamp}"), format!("daylight={daylight}")];
        let relit = plenoptic_bake::groups::relit_scene(&scene, &settings).unwrap();
        let (a, b) = common::reference_halves(&relit, &camera, T, 256, 11);
        rec.set_light_weights(GroupWeights {
            default: Vec3::ONE,
            groups: vec![Vec3::splat(lamp), Vec3::splat(daylight)],
        });
        let ours = frame(&rec);
        let plain_dir = tempfile::tempdir().unwrap();
        bake(plain_dir.path(), &lit_room(lamp, daylight), &sky(daylight));
        let plain = frame(&Reconstructor::open(plain_dir.path().join("out/scene.pack")).unwrap());
        let name = format!("{lamp}_{daylight}_");
        let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join("light_groups");
        std::fs::create_dir_all(&out).unwrap();
        let exposure = 0.5 / a.mean_luminance() as f32;
        for (what, image) in [("reference", &a), ("grouped", &ours), ("ungrouped", &plain)] {
            let png = out.join(format!("{name}{what}.png"));
            image.save_png(png, exposure).unwrap();
        }

        let reference = mean_image(&a, &b).unwrap();
        let ratio = mean_luminance_ratio(&ours, &reference);
        let lrms = corrected_relative_lrms(&ours, &a, &b).corrected;
        let control = corrected_relative_lrms(&plain, &a, &b).corrected;
        let base = *at_one.get_or_insert(lrms);
        println!(
            "lamp {lamp}, daylight {daylight}: mean luminance {ratio:.4} of the path tracer's; \
             corrected relative LRMS {lrms:.4} ({:.2}× the (1, 1) frame's), ungrouped bake \
             {control:.4} (mean {:.4})",
            lrms / base,
            mean_luminance_ratio(&plain, &reference)
        );
        assert!(
            (ratio - 1.0).abs() < 0.03,
            "({lamp}, {daylight}): mean {ratio:.4}"
        );
        assert!(
            lrms <= 1.2 * control,
            "({lamp}, {daylight}): LRMS {lrms:.4} against the ungrouped bake's {control:.4}"
        );
    }
}

/// `Relight::radiance_cube` (what the plugin's light probes read) is linear in the weights:
/// the lamp alone plus the daylight alone is the radiance as baked, and both at a half is
/// half of it, texel by texel within the layers' rounding.
fn radiance_cubes_relight_linearly(rec: &Reconstructor) {
    let (pack, manifest) = (rec.pack(), rec.pack().manifest());
    let cube = |lamp: f32, daylight: f32| {
        let weights = GroupWeights {
            default: Vec3::ONE,
            groups: vec![Vec3::splat(lamp), Vec3::splat(daylight)],
        };
        let relight = plenoptic_recon::relight::Relight::new(manifest, &weights);
        relight.radiance_cube(pack, 0, 0).unwrap().texels
    };
    let (baked, lamp, day, half) = (
        cube(1.0, 1.0),
        cube(1.0, 0.0),
        cube(0.0, 1.0),
        cube(0.5, 0.5),
    );
    let error = |a: &[Vec3], b: &[Vec3]| {
        let e = a
            .iter()
            .zip(b)
            .map(|(a, b)| (*a - *b).abs().max_element() / (b.max_element() + 0.01));
        e.sum::<f32>() / a.len() as f32
    };
    let sum: Vec<Vec3> = lamp.iter().zip(&day).map(|(a, b)| *a + *b).collect();
    let halved: Vec<Vec3> = baked.iter().map(|b| *b * 0.5).collect();
    let (e_sum, e_half) = (error(&sum, &baked), error(&half, &halved));
    println!("relit radiance cubes: lamp + daylight against as baked {e_sum:.4}, half {e_half:.4}");
    assert!(e_sum < 0.02 && e_half < 0.01, "{e_sum} {e_half}");
    assert!(
        error(&lamp, &baked) > 0.1,
        "the lamp alone is not the room as baked"
    );
}
