//! Benchmarks of the Bevy plugin (`bevy_plenoptic`):
//!
//! - `plugin/decode_key`: streaming decode throughput of one key (its radiance, distance,
//!   object-id and normal chunks: checksum, zstd, KTX2 → GPU-ready texel bytes), MB/s of
//!   decoded output, at face sizes 64 and 128;
//! - `plugin/decode_volume`: a temporal-volume block read, decoded and binned by direction
//!   for the GPU's volume fallback, MB/s of binned output;
//! - `plugin/time_to_first_frame`: a headless app from nothing to the first reconstructed
//!   frame read back from the GPU (build the app and renderer, load the pack, spawn the proxy
//!   geometry, stream the working set, compile the pipelines, render, read back). The frame
//!   counts once the working set is resident and the read-back image shows the
//!   reconstruction (no clear colour left, more than the placeholder's one colour).
//!
//! GPU frame time is not measured here: the only adapter on CI is Mesa's software Vulkan
//! driver (lavapipe), whose timings say nothing about real GPUs, and time to first frame on
//! it is dominated by compiling the shaders on the CPU.
//!
//! `cargo bench --no-default-features --features bevy --bench plugin` (the `bevy` feature is
//! required; the window feature is not).

#[path = "../crates/plenoptic_recon/tests/common/mod.rs"]
mod pack;

use std::hint::black_box;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use bevy::camera::RenderTarget;
use bevy::core_pipeline::tonemapping::Tonemapping;
use bevy::prelude::*;
use bevy::render::gpu_readback::{Readback, ReadbackComplete};
use bevy::render::render_resource::{TextureFormat, TextureUsages};
use bevy::window::ExitCondition;
use bevy_plenoptic::prelude::*;
use bevy_plenoptic::streaming::{StreamState, decode_key, decode_volume, key_bytes, volume_bytes};
use criterion::{Criterion, SamplingMode, Throughput, criterion_group, criterion_main};
use plenoptic_pack::PackReader;

fn decode(c: &mut Criterion) {
    let dir = tempfile::tempdir().unwrap();
    let mut g = c.benchmark_group("plugin/decode_key");
    for face in [64, 128] {
        let path = dir.path().join(format!("room{face}.pack"));
        pack::write_pack(
            &pack::room(true),
            &pack::PackSpec::segment(2, vec![0.0, 1.0], face),
            &path,
        );
        let reader = PackReader::open(&path).unwrap();
        g.throughput(Throughput::Bytes(key_bytes(&reader, (0, 0))));
        g.bench_function(format!("face{face}"), |b| {
            b.iter(|| black_box(decode_key(&reader, (0, 0)).unwrap()))
        });
    }
    g.finish();

    let path = dir.path().join("volumes.pack");
    pack::write_pack(
        &pack::room(true),
        &pack::PackSpec {
            volume_samples: 20_000,
            time: (0.0, 0.5),
            ..pack::PackSpec::segment(1, vec![0.0], 16)
        },
        &path,
    );
    let reader = PackReader::open(&path).unwrap();
    let binned = decode_volume(&reader, (0, 0)).unwrap();
    let mut g = c.benchmark_group("plugin/decode_volume");
    g.throughput(Throughput::Bytes(binned.bytes()));
    assert!(binned.bytes() <= volume_bytes(&reader, (0, 0)).unwrap());
    g.bench_function(format!("samples{}", binned.len()), |b| {
        b.iter(|| black_box(decode_volume(&reader, (0, 0)).unwrap()))
    });
    g.finish();
}

const WIDTH: u32 = 320;
const HEIGHT: u32 = 240;

/// One headless app from nothing to its first reconstructed frame; returns the elapsed time.
fn first_frame_once(assets: &std::path::Path) -> Duration {
    let start = Instant::now();
    let mut app = App::new();
    let plugins = DefaultPlugins
        .set(WindowPlugin {
            primary_window: None,
            exit_condition: ExitCondition::DontExit,
            ..default()
        })
        .set(AssetPlugin {
            file_path: assets.to_string_lossy().into_owned(),
            ..default()
        })
        .disable::<bevy::log::LogPlugin>();
    // The tour's window backend is not wanted here (no display; its event loop).
    #[cfg(feature = "window")]
    let plugins = plugins.disable::<bevy::winit::WinitPlugin>();
    app.add_plugins((plugins, PlenopticPlugin));
    app.finish();
    app.cleanup();
    let handle: Handle<RadiancePack> = app.world().resource::<AssetServer>().load("room.pack");
    let image = {
        let mut img = Image::new_target_texture(WIDTH, HEIGHT, TextureFormat::Rgba8Unorm, None);
        img.texture_descriptor.usage |= TextureUsages::COPY_SRC;
        app.world_mut().resource_mut::<Assets<Image>>().add(img)
    };
    let camera = app
        .world_mut()
        .spawn((
            Camera {
                clear_color: ClearColorConfig::Custom(Color::linear_rgb(1.0, 0.0, 0.0)),
                ..default()
            },
            RenderTarget::Image(image.clone().into()),
            Tonemapping::None,
            bevy::camera::Exposure {
                ev100: bevy_plenoptic::camera::EV100_UNIT,
            },
            Transform::from_xyz(0.3, 1.3, 1.0).looking_at(Vec3::new(0.0, 0.8, -2.5), Vec3::Y),
            PlenopticCamera {
                playback: Playback::Manual,
                time: 0.7,
                ..PlenopticCamera::new(handle)
            },
        ))
        .id();
    let latest: Arc<Mutex<Option<Vec<u8>>>> = Arc::default();
    let sink = latest.clone();
    app.world_mut()
        .spawn(Readback::texture(image))
        .observe(move |event: On<ReadbackComplete>| {
            *sink.lock().unwrap() = Some(event.data.clone());
        });
    for _ in 0..100_000 {
        app.update();
        let complete = app.world().get::<StreamState>(camera).unwrap().complete;
        let Some(data) = latest.lock().unwrap().take() else {
            continue;
        };
        if complete && shows_reconstruction(&data) {
            return start.elapsed();
        }
    }
    panic!("no reconstructed frame");
}

/// No red clear colour left and more distinct colours than the placeholder material's one.
fn shows_reconstruction(rgba: &[u8]) -> bool {
    let px: Vec<&[u8]> = rgba.chunks_exact(4).collect();
    let cleared = px.iter().any(|p| p[0] == 255 && p[1] == 0 && p[2] == 0);
    let mut colours: Vec<[u8; 3]> = px.iter().map(|p| [p[0], p[1], p[2]]).collect();
    colours.sort_unstable();
    colours.dedup();
    !cleared && colours.len() > 16
}

fn first_frame(c: &mut Criterion) {
    let dir = tempfile::tempdir().unwrap();
    pack::write_pack(
        &pack::room(true),
        &pack::PackSpec::segment(3, vec![0.0, 1.0, 2.0], 32),
        &dir.path().join("room.pack"),
    );
    let mut g = c.benchmark_group("plugin/time_to_first_frame");
    // Seconds per iteration: one iteration per sample, few samples.
    g.sample_size(10)
        .sampling_mode(SamplingMode::Flat)
        .warm_up_time(Duration::from_millis(1))
        .measurement_time(Duration::from_secs(10));
    g.bench_function("room_face32_320x240", |b| {
        b.iter_custom(|iters| (0..iters).map(|_| first_frame_once(dir.path())).sum())
    });
    g.finish();
}

criterion_group!(benches, decode, first_frame);
criterion_main!(benches);
