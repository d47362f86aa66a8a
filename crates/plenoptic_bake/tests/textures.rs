//! Pack v2's textures at screen resolution (docs/architecture.md, "Pack v2"): a rug with a 2 cm
//! checker in a closed room is baked with small cubes, reconstructed in geometry-assisted mode
//! as `albedo(uv) · lighting + non-diffuse` ([`Shading::Materials`]), and compared with the
//! path tracer, beside the same scene's radiance reconstruction ([`Shading::Radiance`], what a
//! version-1 pack showed) from small cubes and from cubes eight times larger. The errors are
//! variance-corrected against a two-half reference (docs/architecture.md, "Measuring against
//! a noisy reference"). Frames go to `target/tmp/textures/`.

mod common;

use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3};
use plenoptic_eval::metrics::corrected_relative_lrms;
use plenoptic_recon::{Camera, Mode, Reconstructor, Shading};
use plenoptic_scene::builder::{MaterialDesc, NodeDesc, SceneBuilder};
use plenoptic_trace::Image;

/// A `n × n` checker, black and near-white squares of one texel.
fn checker(n: u32) -> Vec<u8> {
    (0..n * n)
        .flat_map(|i| {
            let v = if (i % n + i / n).is_multiple_of(2) {
                20
            } else {
                235
            };
            [v, v, v, 255]
        })
        .collect()
}

/// The static test room with a 1.28 m rug of 64 × 64 squares (2 cm) on its floor.
fn scene() -> SceneBuilder {
    let mut b = common::static_room();
    let tex = b.add_texture_rgba8(64, 64, checker(64));
    let rug = b.add_material(MaterialDesc::diffuse(Vec3::ONE).base_color_texture(tex));
    let plane = b.add_plane("rug", Vec2::splat(1.28), 1, rug);
    b.add_node(
        NodeDesc::new("rug")
            .mesh(plane)
            .translation(Vec3::new(-0.4, -1.95, -0.4)),
    );
    b
}

/// Bakes the scene with cubes of `face` texels into `dir/<face>/out/scene.pack`.
fn bake(dir: &Path, face: u32) -> PathBuf {
    let dir = dir.join(face.to_string());
    std::fs::create_dir_all(&dir).unwrap();
    let quality = format!(
        "range_image_size = {face}\nsamples_per_pixel = 4\nambient_samples = 64\n\
         ambient_rms = 0.1\ntemporal_volume_samples = 16"
    );
    let recipe = common::write_recipe(&dir, &scene(), common::STATIC_SEGMENT, &quality);
    plenoptic_bake::bake_recipe(&recipe, &plenoptic_bake::BakeOptions::default()).unwrap();
    dir.join("out/scene.pack")
}

fn image(frame: &plenoptic_recon::Frame) -> Image<Vec3> {
    Image {
        width: frame.width,
        height: frame.height,
        pixels: frame.radiance.clone(),
    }
}

/// Corrected relative LRMS and mean-luminance ratio of each reconstruction, in order:
/// materials from the small cubes, radiance from the small cubes, radiance from the large.
fn measure(small: u32, large: u32, width: u32, height: u32, spp: u32) -> Vec<(String, f64, f64)> {
    let dir = tempfile::tempdir().unwrap();
    let scene_file = dir.path().join("scene.glb");
    scene().write_glb(&scene_file).unwrap();
    let scene = plenoptic_scene::load(&scene_file).unwrap();
    let camera = Camera::look_at(
        Vec3::new(-0.2, -1.1, -1.2),
        Vec3::new(-0.4, -1.95, -0.3),
        Vec3::Y,
        50f32.to_radians(),
        width,
        height,
    )
    .unwrap();
    let (a, b) = common::reference_halves(&scene, &camera, 0.5, spp, 21);
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join("textures");
    std::fs::create_dir_all(&out).unwrap();
    let exposure = 0.5 / a.mean_luminance() as f32;
    a.save_png(out.join(format!("{width}_reference.png")), exposure)
        .unwrap();
    let mut figures = Vec::new();
    let packs = [
        (small, bake(dir.path(), small)),
        (large, bake(dir.path(), large)),
    ];
    for (face, shading) in [
        (small, Shading::Materials),
        (small, Shading::Radiance),
        (large, Shading::Radiance),
    ] {
        let pack = &packs.iter().find(|p| p.0 == face).unwrap().1;
        let mut rec = Reconstructor::open(pack).unwrap();
        rec.settings.shading = shading;
        let (frame, _) = rec.render(&camera, 0.5, Mode::GeometryAssisted).unwrap();
        let test = image(&frame);
        let name = format!("{shading:?} from {face}-px cubes");
        test.save_png(
            out.join(format!("{width}_{shading:?}_{face}.png").to_lowercase()),
            exposure,
        )
        .unwrap();
        let c = corrected_relative_lrms(&test, &a, &b);
        println!(
            "{name}: corrected relative LRMS {:.3} (noise floor {:.3}), mean luminance {:.3}",
            c.corrected, c.noise_floor, c.mean_ratio
        );
        figures.push((name, c.corrected, c.mean_ratio));
    }
    figures
}

/// CI's size: 16-px lighting cubes against radiance from 16-px and 128-px cubes, at 256 × 144.
#[test]
fn textures_at_screen_resolution_beat_radiance_from_cubes_eight_times_larger() {
    let f = measure(16, 128, 256, 144, 64);
    assert!(f[0].1 < f[2].1, "{f:?}");
    assert!(f[0].1 < f[1].1, "{f:?}");
    assert!((f[0].2 - 1.0).abs() < 0.05, "{f:?}");
}

/// At full size (release build, minutes): 64-px lighting cubes against radiance from
/// 64-px and 512-px cubes, at 1280 × 720.
#[test]
#[ignore]
fn textures_at_1280x720_from_64_px_lighting_cubes() {
    let f = measure(64, 512, 1280, 720, 32);
    assert!(f[0].1 < f[2].1, "{f:?}");
}
