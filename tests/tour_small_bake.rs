//! The architectural tour end to end at CI's size: the
//! committed, textured `tour.glb` is baked with tiny settings (a few base views, small cubes,
//! few samples), two frames of the tour's camera path are reconstructed in geometry-assisted
//! mode at low resolution, and each is compared with a path-traced reference rendered here as
//! two independent halves (variance-corrected relative LRMS and the mean-luminance ratio,
//! docs/architecture.md "Measuring against a noisy reference"). The bounds are what this
//! bake measures, with margin: a regression in the bake
//! (dark or noisy lighting), the pack or the reconstruction (wrong lookups, textures
//! missing) moves them past it.

use std::path::{Path, PathBuf};

use plenoptic_eval::camera::to_pinhole;
use plenoptic_eval::metrics::corrected_relative_lrms;
use plenoptic_recon::{CameraPath, Mode, Reconstructor};
use plenoptic_trace::{Image, PathTracer, PathTracerSettings, SceneAccel};

fn assets() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/architectural_tour/assets")
}

/// The tour recipe's daylight: its `[sun]` and `[sky]` tables, which end the file.
fn daylight() -> String {
    let recipe = std::fs::read_to_string(assets().join("tour.toml")).unwrap();
    let at = recipe.find("\n[sun]").expect("tour.toml has a sun study");
    let tables = recipe[at..].to_owned();
    assert!(tables.contains("\n[sky]"), "tour.toml has a sky");
    tables
}

/// A tiny bake of the tour (with the recipe's daylight): 3 × 3 base views over the rooms, 16-px cubes, 2 samples per
/// texel, a coarse time lattice.
fn bake(dir: &Path) -> PathBuf {
    let glb = assets().join("tour.glb");
    let recipe = format!(
        "output = \"tour.pack\"\n\n[[scene]]\nfile = \"{}\"\n\n[view_space]\nkind = \
         \"rectangle\"\nmin = [-11.0, -5.0]\nmax = [11.0, 5.0]\ny = 1.6\n\n[time]\nstart = 0.0\n\
         end = 14.0\nframe_rate = 24.0\n\n[quality]\npreset = \"draft\"\nid_image_size = 16\n\
         range_image_size = 16\nsamples_per_pixel = 2\nambient_samples = 32\n\
         temporal_volume_samples = 2000\nmax_space_depth = 1\nmax_time_depth = 1\n\n{}",
        glb.display(),
        daylight()
    );
    let path = dir.join("tour.toml");
    std::fs::write(&path, recipe).unwrap();
    plenoptic_bake::bake_recipe(&path, &plenoptic_bake::BakeOptions::default()).unwrap();
    dir.join("tour.pack")
}

#[test]
fn two_tour_frames_from_a_small_bake_agree_with_the_path_tracer() {
    let dir = tempfile::tempdir().unwrap();
    let start = std::time::Instant::now();
    let pack = bake(dir.path());
    let baked = start.elapsed().as_secs_f64();
    let rec = Reconstructor::open(&pack).unwrap();
    assert!(
        !rec.pack().textures().is_empty(),
        "the tour's textures are in the pack"
    );
    // The scene as the bake saw it: the glb with the recipe's sun study and sky.
    let (_, scene) = plenoptic_bake::input::load_recipe(&dir.path().join("tour.toml")).unwrap();
    let accel = SceneAccel::new(&scene).unwrap();
    let path = CameraPath::load(assets().join("tour_path.json")).unwrap();
    let (t0, t1) = path.time_range();
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join("tour_small_bake");
    std::fs::create_dir_all(&out).unwrap();
    let mut failures = Vec::new();
    // Per frame: where on the path, and the bounds on the corrected error and on the
    // mean-luminance ratio. Measured with the tour's sun study and sky (dev profile): 0.747
    // and 0.464, mean luminance 0.936 and 0.786, with room A's mirror marched for the camera
    // (0.828 and 0.476, mean luminance 0.925 and 0.784, with its baked specular). Before the daylight (pack 3.0, the glb's
    // own sun and no sky): 1.64 and 5.14, mean luminance 1.05 and 1.32; the skylight's
    // steel frame then carried most of frame 1's error (its per-pixel sun highlight on bars
    // a pixel or two wide, one sample per pixel against an antialiased reference); under
    // the sky the frame's other light outweighs it. The errors are high because the bake is
    // tiny (16-px cubes 11 m apart, 2 samples); frame 1's dark share is the skylight's well,
    // lit through hole fill. The bounds leave about half on top.
    for (k, (s, bound, mean_tolerance)) in [(0.3f32, 1.25, 0.15), (0.75, 0.75, 0.3)]
        .into_iter()
        .enumerate()
    {
        let mut sample = path.sample(t0 + (t1 - t0) * s);
        sample.camera.width = 64;
        sample.camera.height = 36;
        let placed = accel.at_time(sample.scene_time);
        let pinhole = to_pinhole(&sample.camera).unwrap();
        let half = |seed| {
            PathTracer::new(PathTracerSettings {
                samples_per_pixel: 128,
                max_depth: 12,
                rr_start_depth: 4,
                seed,
                environment_sampling: true,
            })
            .render(&placed, &pinhole)
            .radiance()
        };
        let (a, b) = (half(41), half(42));
        let (frame, report) = rec
            .render(&sample.camera, sample.scene_time, Mode::GeometryAssisted)
            .unwrap();
        let test = Image {
            width: frame.width,
            height: frame.height,
            pixels: frame.radiance.clone(),
        };
        let exposure = 0.5 / a.mean_luminance() as f32;
        a.save_png(out.join(format!("{k}_reference.png")), exposure)
            .unwrap();
        test.save_png(out.join(format!("{k}_geometry.png")), exposure)
            .unwrap();
        let c = corrected_relative_lrms(&test, &a, &b);
        println!(
            "frame {k} (t = {:.2}): corrected relative LRMS {:.3} (noise floor {:.3}), mean \
             luminance {:.3}; {:?}",
            sample.scene_time, c.corrected, c.noise_floor, c.mean_ratio, report.fallback
        );
        if c.corrected > bound || (c.mean_ratio - 1.0).abs() > mean_tolerance {
            failures.push((k, c.corrected, c.mean_ratio));
        }
    }
    println!(
        "bake {baked:.1} s, all {:.1} s",
        start.elapsed().as_secs_f64()
    );
    assert!(failures.is_empty(), "{failures:?}");
}
