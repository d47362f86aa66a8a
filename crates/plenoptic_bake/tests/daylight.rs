//! Daylight through the baker's input: environment images read from disk, a recipe's
//! `[sun]`/`[sky]` applied to the scene, a generated building in the style of a BIM export
//! (alpha-blended glass, no lights of its own, sun and sky from the recipe) lit inside as the
//! path tracer lights it, and a sun study's plan.

use exr::prelude::WritableImage;
use std::io::Write;
use std::path::Path;

#[path = "../../../examples/sun_study/scene.rs"]
mod scene;

use glam::Vec3;
use plenoptic_bake::daylight::read_equirect;
use plenoptic_bake::input::load_recipe;
use plenoptic_bake::plan::{ambient, decompose, sunlit};
use plenoptic_trace::{
    AmbientField, Image, MultiStageRenderer, MultiStageSettings, PathTracer, PathTracerSettings,
    PinholeCamera, SceneAccel,
};

/// A flat (uncompressed) Radiance file of `w` × `h` RGBE texels, `w` < 8 so that no run-length
/// encoding is expected.
fn write_hdr(path: &Path, w: usize, h: usize, rgbe: &[[u8; 4]], claim: Option<(usize, usize)>) {
    let (cw, ch) = claim.unwrap_or((w, h));
    let mut f = std::fs::File::create(path).unwrap();
    write!(f, "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y {ch} +X {cw}\n").unwrap();
    for t in rgbe {
        f.write_all(t).unwrap();
    }
}

#[test]
fn environment_images_are_read_and_bad_ones_named() {
    let dir = tempfile::tempdir().unwrap();
    // RGBE (128, 64, 32, 129): mantissas × 2^(129 − 136) → (1, 0.5, 0.25).
    let hdr = dir.path().join("sky.hdr");
    write_hdr(&hdr, 4, 2, &[[128, 64, 32, 129]; 8], None);
    let img = read_equirect(&hdr).unwrap();
    assert_eq!((img.width, img.height), (4, 2));
    assert!(
        (img.texels[5] - Vec3::new(1.0, 0.5, 0.25)).length() < 0.01,
        "{}",
        img.texels[5]
    );

    // An EXR written by the exr crate (ZIP, half floats, as compositors write by default).
    let exr_path = dir.path().join("sky.exr");
    let pixels = |p: exr::math::Vec2<usize>| {
        let v = (p.x() + 4 * p.y()) as f32 * 0.25;
        (
            half::f16::from_f32(v),
            half::f16::from_f32(1.0),
            half::f16::from_f32(2.0),
        )
    };
    let layer = exr::prelude::Layer::new(
        (4, 2),
        exr::prelude::LayerAttributes::named("rgb"),
        exr::prelude::Encoding::SMALL_LOSSLESS,
        exr::prelude::SpecificChannels::rgb(pixels),
    );
    exr::prelude::Image::from_layer(layer)
        .write()
        .to_file(&exr_path)
        .unwrap();
    let img = read_equirect(&exr_path).unwrap();
    assert_eq!((img.width, img.height), (4, 2));
    assert!(
        (img.texels[6] - Vec3::new(1.5, 1.0, 2.0)).length() < 1e-3,
        "{}",
        img.texels[6]
    );

    // A header claiming 100 000 × 100 000 texels is refused before anything is allocated.
    let hostile = dir.path().join("hostile.hdr");
    write_hdr(
        &hostile,
        4,
        2,
        &[[128, 64, 32, 129]; 8],
        Some((100_000, 100_000)),
    );
    let e = read_equirect(&hostile).unwrap_err().to_string();
    assert!(e.contains("hostile.hdr") && e.contains("outside"), "{e}");
    // Truncated: the header promises more scanlines than the file has.
    let short = dir.path().join("short.hdr");
    write_hdr(&short, 4, 2, &[[128, 64, 32, 129]; 3], Some((4, 2)));
    let e = read_equirect(&short).unwrap_err().to_string();
    assert!(e.contains("short.hdr"), "{e}");
    let e = read_equirect(&dir.path().join("missing.exr"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("missing.exr"), "{e}");
}

fn bim_building(path: &Path) {
    scene::building().write_glb(path).unwrap();
}

fn recipe(dir: &Path, local_time: [f64; 2], preset: &str) -> std::path::PathBuf {
    recipe_with(dir, local_time, preset, "")
}

/// [`recipe`] with `quality` added to its `[quality]` section.
fn recipe_with(
    dir: &Path,
    local_time: [f64; 2],
    preset: &str,
    quality: &str,
) -> std::path::PathBuf {
    let path = dir.join(format!(
        "bim_{}_{}_{}.toml",
        local_time[0],
        local_time[1],
        quality.len()
    ));
    std::fs::write(
        &path,
        format!(
            r#"output = "bim.pack"
[[scene]]
file = "bim.glb"
[view_space]
kind = "segment"
a = [-2.0, 1.6, 0.0]
b = [2.0, 1.6, 0.0]
[time]
start = 0.0
end = 14.0
frame_rate = 30.0
[quality]
preset = "{preset}"
{quality}
[sun]
latitude = 48.8566
longitude = 2.3522
date = "2026-06-21"
utc_offset = 2.0
local_time = [{}, {}]
[sky]
kind = "hosek-wilkie"
turbidity = 3.0
"#,
            local_time[0], local_time[1]
        ),
    )
    .unwrap();
    path
}

#[test]
fn a_bim_style_building_is_lit_inside_by_sun_and_sky() {
    let dir = tempfile::tempdir().unwrap();
    bim_building(&dir.path().join("bim.glb"));
    let (recipe, scene) = load_recipe(&recipe(dir.path(), [9.0, 17.0], "draft")).unwrap();
    assert!(scene.sun.is_some() && !scene.environment.is_none());
    let accel = SceneAccel::new(&scene).unwrap();
    // Inside, looking north-east across the room at the back wall, floor and sun patches.
    let camera = PinholeCamera::look_at(
        Vec3::new(-3.0, 1.6, 2.4),
        Vec3::new(2.0, 0.6, -3.0),
        Vec3::Y,
        1.1,
        40,
        30,
    )
    .unwrap();
    for t in [2.0f32, 11.0] {
        let placed = accel.at_time(t);
        let field = AmbientField::build(&placed, &ambient::settings(&recipe.quality, 7)).unwrap();
        let ms = MultiStageRenderer::new(
            MultiStageSettings {
                samples_per_pixel: 64,
                shadow_samples: 2,
                glossy_samples: 2,
                max_specular_depth: 4,
                seed: 3,
                final_gather: 0,
            },
            &field,
        )
        .render(&placed, &camera)
        .radiance();
        let pt: Image<Vec3> = PathTracer::new(PathTracerSettings {
            samples_per_pixel: 512,
            max_depth: 32,
            rr_start_depth: 5,
            seed: 17,
            environment_sampling: true,
        })
        .render(&placed, &camera)
        .radiance();
        let (m, r) = (ms.mean_luminance(), pt.mean_luminance());
        let (sun, lux) = scene.sun_at(t).unwrap();
        println!(
            "BIM building t = {t}: interior mean luminance MS {m:.1}, PT {r:.1}, ratio {:.4} (sun {:.1}° up, {:.0} lx)",
            m / r,
            sun.y.asin().to_degrees(),
            lux.x
        );
        // Lit inside: a dark interior would be far below the sun's own scale.
        assert!(r > 100.0, "PT interior mean {r}");
        assert!((m / r - 1.0).abs() < 0.05, "t = {t}: MS/PT {:.4}", m / r);
    }
}

#[test]
fn a_sun_study_adds_time_keys_where_the_sun_moves() {
    let dir = tempfile::tempdir().unwrap();
    bim_building(&dir.path().join("bim.glb"));
    let keys = |local: [f64; 2]| {
        // The sun baked: its own light keys (a runtime sun's are the ambient field's).
        let path = recipe_with(dir.path(), local, "draft", "runtime_sun = false");
        let (recipe, scene) = load_recipe(&path).unwrap();
        let accel = SceneAccel::new(&scene).unwrap();
        let (plan, _) = decompose(&recipe, &scene, &accel);
        plan.light_keys
    };
    // A whole afternoon against one minute of it, over the same 14 s: the sun's patches move
    // far in the first and not at all in the second.
    let day = keys([9.0, 19.0]);
    let minute = keys([12.0, 12.0 + 1.0 / 60.0]);
    println!(
        "light keys: 10 h over 14 s {}, 1 min over 14 s {}",
        day.len(),
        minute.len()
    );
    println!("10 h keys at {day:?}");
    assert!(
        day.len() > minute.len() + 4,
        "{} vs {}",
        day.len(),
        minute.len()
    );
    assert!(minute.len() <= 3, "{minute:?}");
}

/// With the sun left to the runtime (the default) the views' keys do not follow the sun's
/// patches, whose direct light is not stored; the light keys (what the sun and the sky see,
/// which drives the indirect light) stay: fewer range images for the same day.
#[test]
fn a_runtime_sun_needs_fewer_keys_than_a_baked_one() {
    let dir = tempfile::tempdir().unwrap();
    bim_building(&dir.path().join("bim.glb"));
    let keys = |quality: &str| {
        // A lattice fine enough (2^7 steps) that the light keys do not saturate it.
        let quality = format!("max_time_depth = 7\n{quality}");
        let path = recipe_with(dir.path(), [6.0, 21.5], "draft", &quality);
        let (recipe, scene) = load_recipe(&path).unwrap();
        let accel = SceneAccel::new(&scene).unwrap();
        let (plan, _) = decompose(&recipe, &scene, &accel);
        plan.base_views
            .iter()
            .map(|v| v.time_keys.len())
            .sum::<usize>()
    };
    let (runtime, baked) = (keys(""), keys("runtime_sun = false"));
    println!("range images: runtime sun {runtime}, baked sun {baked}");
    assert!(2 * runtime < baked, "{runtime} vs {baked}");
}

#[test]
fn a_day_long_sun_study_gets_more_keys_where_the_sun_patches_move_fast() {
    let dir = tempfile::tempdir().unwrap();
    bim_building(&dir.path().join("bim.glb"));
    // 6:00 to 21:30 in Paris on 21 June over 14 s, on a lattice fine enough (2^7 steps) that
    // the keys do not saturate it; the sun baked into the lighting, whose patches the views'
    // keys then follow.
    let path = recipe_with(
        dir.path(),
        [6.0, 21.5],
        "draft",
        "max_time_depth = 7\nruntime_sun = false",
    );
    let (recipe, scene) = load_recipe(&path).unwrap();
    let accel = SceneAccel::new(&scene).unwrap();
    let (plan, _) = decompose(&recipe, &scene, &accel);
    // The base view nearest the windows' patches, with the most keys.
    let view = plan
        .base_views
        .iter()
        .max_by_key(|v| v.time_keys.len())
        .unwrap();
    let keys = &view.time_keys;
    println!(
        "light keys {}, base views' keys {:?}",
        plan.light_keys.len(),
        plan.base_views
            .iter()
            .map(|v| v.time_keys.len())
            .collect::<Vec<_>>()
    );
    assert!(
        keys.len() < 129,
        "the lattice is not saturated: {}",
        keys.len()
    );

    // How fast the patches move, measured apart from the plan's decision: the share of the
    // sunlit surface this view sees that changes from one lattice step to the next (1 − the
    // overlap of its sunlit masks), at twice the plan's resolution.
    let clear = sunlit::visibility_scene(&scene);
    let patches = sunlit::SunPatches::new(&scene, &clear).unwrap();
    let steps = 128;
    let time = |i: usize| 14.0 * i as f32 / steps as f32;
    let size = 2 * recipe.quality.id_image_size;
    let lit: Vec<Vec<bool>> = (0..=steps)
        .map(|i| patches.sunlit(&accel.at_time(time(i)), view.position, size))
        .collect();
    // Per lattice step: its patch speed, and the length of the plan's interval holding it.
    let mut steps_by_speed: Vec<(f64, f32)> = (0..steps)
        .map(|i| {
            let moved = 1.0 - sunlit::overlap(&lit[i], &lit[i + 1]);
            let mid = 0.5 * (time(i) + time(i + 1));
            let after = keys.iter().position(|&k| k > mid).unwrap_or(keys.len() - 1);
            (moved, keys[after] - keys[after.saturating_sub(1)])
        })
        .collect();
    steps_by_speed.sort_by(|a, b| a.0.total_cmp(&b.0));
    let quarter = steps / 4;
    let mean = |s: &[(f64, f32)]| {
        (
            s.iter().map(|x| x.0).sum::<f64>() / s.len() as f64,
            s.iter().map(|x| x.1).sum::<f32>() / s.len() as f32,
        )
    };
    let (slow_speed, slow_interval) = mean(&steps_by_speed[..quarter]);
    let (fast_speed, fast_interval) = mean(&steps_by_speed[steps - quarter..]);
    println!(
        "sun study, {} keys at the busiest view: the fastest quarter of the day ({:.1} % of the \
         sunlit surface moves per step) lies in key intervals of {fast_interval:.3} s on \
         average, the slowest quarter ({:.1} %) in {slow_interval:.3} s",
        keys.len(),
        100.0 * fast_speed,
        100.0 * slow_speed
    );
    println!("keys at {keys:?}");
    assert!(fast_speed > 2.0 * slow_speed, "the patches do move");
    assert!(
        fast_interval * 1.5 < slow_interval,
        "keys are denser where the patches move fast: {fast_interval} vs {slow_interval}"
    );
}
