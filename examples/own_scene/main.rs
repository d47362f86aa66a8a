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
//! # or 30 frames headless, the last one written to target/own_scene/frame.png
//! cargo run --release --example own_scene -- --frames 30
//! ```
//!
//! Options: `--pack PATH` (default: the tour's, `target/architectural_tour/tour.pack`),
//! `--proxies` (the pack's own proxies instead of the glb, for comparison), `--size WxH`
//! (the headless frame, default 640x360),
//! `--frames N` (headless: once the camera's keys are resident and the scene is lit, render
//! N frames into an image, write the last, exit).
//!
//! [`PlenopticLit`]: bevy_plenoptic::lit::scene::PlenopticLit

mod scene;

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::{Arc, Mutex};
use std::time::Instant;

use bevy::asset::io::AssetSourceBuilder;
use bevy::camera::RenderTarget;
use bevy::core_pipeline::tonemapping::Tonemapping;
use bevy::prelude::*;
use bevy::render::gpu_readback::{Readback, ReadbackComplete};
use bevy::render::render_resource::{TextureFormat, TextureUsages};
use bevy::window::ExitCondition;
use bevy_plenoptic::lit::scene::LitObject;
use bevy_plenoptic::prelude::*;

/// The headless frame's size unless `--size` says otherwise.
const SIZE: (u32, u32) = (640, 360);

fn main() -> ExitCode {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| root.join("target"));
    let mut pack = target.join("architectural_tour/tour.pack");
    let mut frames: Option<u32> = None;
    let mut own_scene = true;
    let mut size = SIZE;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        if a == "--proxies" {
            own_scene = false;
            continue;
        }
        match (a.as_str(), args.next()) {
            ("--pack", Some(p)) => pack = PathBuf::from(p),
            ("--frames", Some(n)) if n.parse::<u32>().is_ok() => frames = n.parse().ok(),
            ("--size", Some(wh)) if parse_size(&wh).is_some() => {
                size = parse_size(&wh).unwrap_or(SIZE)
            }
            _ => {
                eprintln!("usage: own_scene [--pack PATH] [--frames N] [--size WxH] [--proxies]");
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
        own_scene,
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
            scene::add(
                &mut app,
                scene,
                (Camera3d::default(), Tonemapping::AcesFitted),
            );
            app.run();
            ExitCode::SUCCESS
        }
        Some(n) => headless(
            app,
            asset_plugin,
            scene,
            (n, size),
            &target.join("own_scene"),
        ),
    }
}

/// `WxH`, e.g. `320x180`.
fn parse_size(s: &str) -> Option<(u32, u32)> {
    let (w, h) = s.split_once('x')?;
    let (w, h) = (w.parse().ok()?, h.parse().ok()?);
    (w > 0 && h > 0 && w <= 8192 && h <= 8192).then_some((w, h))
}

/// Renders `n` frames into an image and writes the last one to `out/frame.png`.
fn headless(
    mut app: App,
    asset_plugin: AssetPlugin,
    scene: scene::OwnScene,
    (n, size): (u32, (u32, u32)),
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
            Image::new_target_texture(size.0, size.1, TextureFormat::Rgba8UnormSrgb, None);
        image.texture_descriptor.usage |= TextureUsages::COPY_SRC;
        images.add(image)
    };
    scene::add(
        &mut app,
        scene,
        (
            Camera3d::default(),
            Tonemapping::AcesFitted,
            RenderTarget::Image(image.clone().into()),
        ),
    );
    app.finish();
    app.cleanup();
    // Every frame read back; the scene is on screen once a read-back shows more than one
    // colour (the software driver compiles pipelines for a while, and keys stream in).
    let latest: Arc<Mutex<Option<Vec<u8>>>> = Arc::default();
    let sink = latest.clone();
    app.world_mut()
        .spawn(Readback::texture(image))
        .observe(move |event: On<ReadbackComplete>| {
            *sink.lock().unwrap_or_else(|e| e.into_inner()) = Some(event.data.clone());
        });
    let shown = |d: &[u8]| d.chunks_exact(4).any(|p| p != &d[..4]);
    let start = Instant::now();
    let mut updates = 0;
    loop {
        app.update();
        updates += 1;
        let got = latest.lock().unwrap_or_else(|e| e.into_inner()).take();
        if got.as_deref().is_some_and(shown) {
            break;
        }
        if updates == 5000 {
            eprintln!("own_scene: nothing on screen after {updates} updates");
            return ExitCode::FAILURE;
        }
    }
    println!(
        "own_scene: on screen after {updates} updates ({:.1} s)",
        start.elapsed().as_secs_f64()
    );
    let start = Instant::now();
    for _ in 0..n {
        app.update();
    }
    // The last frame's read-back arrives a frame or two later.
    let mut last = None;
    for _ in 0..10 {
        if let Some(d) = latest.lock().unwrap_or_else(|e| e.into_inner()).take() {
            last = Some(d);
            break;
        }
        app.update();
    }
    let world = app.world_mut();
    let lit = world.query::<&LitObject>().iter(world).count();
    println!(
        "own_scene: {n} frames in {:.1} s ({:.0} ms each); {lit} meshes of the glb lit by the pack",
        start.elapsed().as_secs_f64(),
        start.elapsed().as_secs_f64() * 1e3 / n.max(1) as f64
    );
    let file = out.join("frame.png");
    let written = std::fs::create_dir_all(out)
        .map_err(|e| e.to_string())
        .and_then(|()| {
            let data = last.ok_or("no read-back of the last frame")?;
            image::RgbaImage::from_raw(size.0, size.1, data)
                .ok_or("read-back of the wrong size")?
                .save(&file)
                .map_err(|e| e.to_string())
        });
    if let Err(e) = written {
        eprintln!("own_scene: {}: {e}", file.display());
        return ExitCode::FAILURE;
    }
    println!("own_scene: the last frame is in {}", file.display());
    ExitCode::SUCCESS
}
