//! Benchmarks of the Bevy plugin (`bevy_plenoptic`): streaming decode throughput (a key's
//! chunks → GPU-ready texel bytes, MB/s of decoded output) and time to first frame of a
//! headless app (load the pack, spawn proxies, stream, render one frame, read it back).
//!
//! GPU frame time is not measured here: the only adapter on CI is Mesa's software Vulkan
//! driver (lavapipe), whose timings say nothing about real GPUs.
//!
//! `cargo bench --bench plugin` (needs the default `bevy` feature).

#[path = "../crates/plenoptic_recon/tests/common/mod.rs"]
mod pack;

use std::hint::black_box;
use std::time::{Duration, Instant};

use bevy::prelude::*;
use bevy::window::ExitCondition;
use bevy_plenoptic::prelude::*;
use bevy_plenoptic::streaming::{StreamingStats, decode_key, key_bytes};
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use plenoptic_pack::PackReader;

fn decode(c: &mut Criterion) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("room.pack");
    pack::write_pack(
        &pack::room(true),
        &pack::PackSpec::segment(2, vec![0.0, 1.0], 64),
        &path,
    );
    let reader = PackReader::open(&path).unwrap();
    let bytes = key_bytes(&reader, (0, 0));
    let mut g = c.benchmark_group("plugin/decode_key");
    g.throughput(Throughput::Bytes(bytes));
    g.bench_function("face64", |b| {
        b.iter(|| black_box(decode_key(&reader, (0, 0)).unwrap()))
    });
    g.finish();
}

fn first_frame(c: &mut Criterion) {
    let dir = tempfile::tempdir().unwrap();
    pack::write_pack(
        &pack::room(true),
        &pack::PackSpec::segment(2, vec![0.0, 1.0, 2.0], 16),
        &dir.path().join("room.pack"),
    );
    let mut g = c.benchmark_group("plugin/time_to_first_frame");
    g.sample_size(10);
    g.bench_function("room_16", |b| {
        b.iter_custom(|iters| {
            let mut total = Duration::ZERO;
            for _ in 0..iters {
                let start = Instant::now();
                let mut app = App::new();
                app.add_plugins((
                    DefaultPlugins
                        .set(WindowPlugin {
                            primary_window: None,
                            exit_condition: ExitCondition::DontExit,
                            ..default()
                        })
                        .set(AssetPlugin {
                            file_path: dir.path().to_string_lossy().into_owned(),
                            ..default()
                        }),
                    PlenopticPlugin,
                ));
                app.finish();
                app.cleanup();
                let handle: Handle<RadiancePack> =
                    app.world().resource::<AssetServer>().load("room.pack");
                app.world_mut().spawn((
                    PlenopticCamera::new(handle),
                    Transform::from_xyz(0.0, 1.3, 1.0),
                ));
                // First frame with the working set resident.
                for _ in 0..10_000 {
                    app.update();
                    if app.world().resource::<StreamingStats>().hits > 0 {
                        break;
                    }
                }
                total += start.elapsed();
            }
            total
        })
    });
    g.finish();
}

criterion_group!(benches, decode, first_frame);
criterion_main!(benches);
