//! Your own glTF scene lit by a radiance pack: the architectural tour's `tour.glb`, loaded by
//! Bevy's own glTF loader (`WorldAssetRoot`, `StandardMaterial`s with their textures), shaded
//! with the pack's reconstructed lighting through [`PlenopticLit`], and a sphere that is not
//! in the pack moving through room A, lit by the pack's light probes
//! (`bevy_plenoptic::lit`).
//!
//! ```sh
//! # the tour's pack first (the tour bakes it when it is missing)
//! cargo run --release --example architectural_tour -- --frames 1
//! # a window
//! cargo run --release --example own_scene
//! # or 120 frames headless, the last one written to target/own_scene/frame.png
//! cargo run --release --example own_scene -- --frames 120
//! ```
//!
//! Options: `--pack PATH` (default: the tour's, `target/architectural_tour/tour.pack`),
//! `--frames N` (headless: render N frames into an image, write the last, exit).
//!
//! [`PlenopticLit`]: bevy_plenoptic::lit::scene::PlenopticLit

mod scene;

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use bevy::asset::io::AssetSourceBuilder;
use bevy::camera::RenderTarget;
use bevy::prelude::*;
use bevy::render::render_resource::{TextureFormat, TextureUsages};
use bevy::render::view::screenshot::{Screenshot, save_to_disk};
use bevy::window::ExitCondition;
use bevy_plenoptic::prelude::*;

/// The headless frame's size.
const SIZE: (u32, u32) = (640, 360);

fn main() -> ExitCode {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| root.join("target"));
    let mut pack = target.join("architectural_tour/tour.pack");
    let mut frames: Option<u32> = None;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match (a.as_str(), args.next()) {
            ("--pack", Some(p)) => pack = PathBuf::from(p),
            ("--frames", Some(n)) if n.parse::<u32>().is_ok() => frames = n.parse().ok(),
            _ => {
                eprintln!("usage: own_scene [--pack PATH] [--frames N]");
                return ExitCode::FAILURE;
            }
        }
    }
    let (Some(dir), Some(file)) = (
        pack.parent()
            .filter(|_| pack.is_file())
            .and_then(|d| d.canonicalize().ok()),
        pack.file_name(),
    ) else {
        eprintln!(
            "own_scene: {} not found; bake the tour's pack first: cargo run --release \
             --example architectural_tour -- --frames 1",
            pack.display()
        );
        return ExitCode::FAILURE;
    };
    let assets = root.join("examples/architectural_tour/assets");
    let scene = scene::OwnScene {
        pack: format!("pack://{}", file.to_string_lossy()),
        ..default()
    };
    let mut app = App::new();
    // The pack's folder as a second asset source, beside the glb's.
    app.register_asset_source(
        "pack",
        AssetSourceBuilder::platform_default(&dir.to_string_lossy(), None),
    );
    let asset_plugin = AssetPlugin {
        file_path: assets.to_string_lossy().into_owned(),
        ..default()
    };
    match frames {
        None => {
            app.add_plugins((DefaultPlugins.set(asset_plugin), PlenopticPlugin));
            scene::add(&mut app, scene, Camera3d::default());
            app.run();
            ExitCode::SUCCESS
        }
        Some(n) => headless(app, asset_plugin, scene, n, &target.join("own_scene")),
    }
}

/// Renders `n` frames into an image and writes the last one to `out/frame.png`.
fn headless(
    mut app: App,
    asset_plugin: AssetPlugin,
    scene: scene::OwnScene,
    n: u32,
    out: &Path,
) -> ExitCode {
    let plugins = DefaultPlugins
        .set(asset_plugin)
        .set(WindowPlugin {
            primary_window: None,
            exit_condition: ExitCondition::DontExit,
            ..default()
        })
        .build();
    #[cfg(feature = "window")]
    let plugins = plugins.disable::<bevy::winit::WinitPlugin>();
    app.add_plugins((plugins, PlenopticPlugin));
    let image = {
        let mut images = app.world_mut().resource_mut::<Assets<Image>>();
        let mut image =
            Image::new_target_texture(SIZE.0, SIZE.1, TextureFormat::Rgba8UnormSrgb, None);
        image.texture_descriptor.usage |= TextureUsages::COPY_SRC;
        images.add(image)
    };
    scene::add(
        &mut app,
        scene,
        (
            Camera3d::default(),
            RenderTarget::Image(image.clone().into()),
        ),
    );
    app.finish();
    app.cleanup();
    for _ in 0..n {
        app.update();
    }
    if let Err(e) = std::fs::create_dir_all(out) {
        eprintln!("own_scene: {}: {e}", out.display());
        return ExitCode::FAILURE;
    }
    let file = out.join("frame.png");
    app.world_mut()
        .spawn(Screenshot::image(image))
        .observe(save_to_disk(file.clone()));
    // The screenshot is read back and written a few frames later.
    for _ in 0..5 {
        app.update();
    }
    println!("own_scene: {n} frames; the last in {}", file.display());
    ExitCode::SUCCESS
}
