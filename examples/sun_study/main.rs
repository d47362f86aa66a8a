//! # A sun study
//!
//! A day's daylight through the windows and the skylight of a building exported as a CAD/BIM
//! tool would (`scene.rs`: glass as `alphaMode: BLEND`, no lights of its own). The recipe
//! (`sun_study.toml`) adds the sun for Paris on 21 June from 7:00 to 20:00 and the
//! Hosek–Wilkie sky it lights, compressed onto the bake's 14 s.
//!
//! What the example does:
//!
//! 1. writes `building.glb` and copies the recipe into the output folder
//!    (`target/sun_study/`, under `$CARGO_TARGET_DIR` if set);
//! 2. bakes the pack (draft preset) unless it is there;
//! 3. renders 4 frames of the day from one camera inside with the CPU reconstruction
//!    (geometry-assisted mode, one exposure for all four) and writes them as PNGs plus a 2 × 2
//!    montage, `sun_study.png`; with `--results` the montage also goes to
//!    `docs/results/sun_study.png`.
//!
//! ```text
//! cargo run --release --no-default-features --example sun_study -- --results
//! ```

mod scene;

use std::path::{Path, PathBuf};

use plenoptic_bake::{BakeOptions, bake_recipe};
use plenoptic_eval::tools::{RenderOptions, render_path_with};
use plenoptic_recon::{CameraPath, Keyframe, Mode, Reconstructor};

/// Frames shown: evenly spread over the day.
const FRAMES: usize = 4;

fn out_dir() -> PathBuf {
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("target"));
    target.join("sun_study")
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let results = std::env::args().any(|a| a == "--results");
    let dir = out_dir();
    std::fs::create_dir_all(&dir)?;
    scene::building().write_glb(&dir.join("building.glb"))?;
    let recipe = dir.join("sun_study.toml");
    std::fs::copy(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/sun_study/sun_study.toml"),
        &recipe,
    )?;
    let pack = dir.join("sun_study.pack");
    // A pack of an older format is baked again.
    let outdated = pack.exists() && plenoptic_pack::is_outdated(&pack);
    if !pack.exists() || outdated {
        let start = std::time::Instant::now();
        bake_recipe(
            &recipe,
            &BakeOptions {
                progress: plenoptic_bake::progress::Progress::new(true),
                ..BakeOptions::default()
            },
        )?;
        println!(
            "baked {} in {:.1} s",
            pack.display(),
            start.elapsed().as_secs_f64()
        );
    }
    // One camera in the hall's west half looking east along the south wall's windows, the
    // floor and the skylight's patch in view; the four frames step through the day.
    let position = glam::Vec3::new(-4.0, 1.6, 1.8);
    let target = glam::Vec3::new(2.5, 0.9, -1.5);
    let keyframes = (0..FRAMES)
        .map(|i| {
            let t = 14.0 * i as f32 / (FRAMES - 1) as f32;
            Keyframe::looking_at(t, position, target, 70.0, t)
        })
        .collect();
    let path = CameraPath {
        frame_rate: (FRAMES - 1) as f32 / 14.0,
        width: 480,
        height: 270,
        keyframes,
    };
    let rec = Reconstructor::open(&pack)?;
    let frames = dir.join("frames");
    let summary = render_path_with(
        &rec,
        &path,
        &frames,
        &RenderOptions {
            mode: Mode::GeometryAssisted,
            exr: false,
            progress: true,
            ..RenderOptions::default()
        },
    )?;
    let montage = montage(&frames, path.width, path.height)?;
    let png = dir.join("sun_study.png");
    montage.save(&png)?;
    println!("{} frames, montage {}", summary.frames, png.display());
    if results {
        let docs = Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/results/sun_study.png");
        montage.save(&docs)?;
        println!("wrote {}", docs.display());
    }
    Ok(())
}

/// The frames 2 × 2.
fn montage(frames: &Path, w: u32, h: u32) -> Result<image::RgbImage, Box<dyn std::error::Error>> {
    let mut out = image::RgbImage::new(2 * w + 4, 2 * h + 4);
    for i in 0..FRAMES {
        let frame =
            image::open(frames.join(plenoptic_eval::tools::frame_name(i, "png")))?.to_rgb8();
        let (x, y) = ((i as u32 % 2) * (w + 4), (i as u32 / 2) * (h + 4));
        image::imageops::overlay(&mut out, &frame, i64::from(x), i64::from(y));
    }
    Ok(out)
}
