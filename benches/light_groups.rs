//! The CPU frame time of a pack with light groups (docs/architecture.md, "Light groups"): the
//! architectural tour baked with groups (`examples/architectural_tour/assets/tour_groups.toml`)
//! against the same tour baked without (`tour.toml`), in one run, 640 × 360 geometry-assisted
//! frames of the tour's path, the chunk cache warm:
//!
//! - `ungrouped`: the pack without groups;
//! - `groups_as_baked`: the grouped pack at every group's own intensity (the total alone);
//! - `lamp_off`, `daylight_0.2`: one group's layer blended into each key once, then looked
//!   up as before;
//! - `dimmer_moving`: the daylight's weight changed every frame, so every frame blends every
//!   key it touches again (an animated dimmer's worst case).
//!
//! The ratios to `ungrouped` are printed. Needs both packs (they are not committed):
//!
//! ```sh
//! target/release/plenoptic bake examples/architectural_tour/assets/tour.toml
//! target/release/plenoptic bake examples/architectural_tour/assets/tour_groups.toml
//! PLENOPTIC_TOUR_PACK=$PWD/target/architectural_tour/tour.pack \
//! PLENOPTIC_GROUPS_PACK=$PWD/target/architectural_tour/tour_groups.pack \
//!     cargo bench --no-default-features --bench light_groups -- --warm-up-time 1 --measurement-time 5
//! ```
//!
//! Without them it says so and measures nothing.

use std::hint::black_box;
use std::path::PathBuf;
use std::time::Instant;

use criterion::{Criterion, criterion_group, criterion_main};
use plenoptic_pack::{GroupWeights, glam::Vec3};
use plenoptic_recon::{CameraPath, Mode, PathSample, Reconstructor};

/// Frames of the tour's path each iteration renders (spread over the path).
const FRAMES: usize = 4;

fn pack(var: &str) -> Option<PathBuf> {
    std::env::var_os(var).map(Into::into)
}

/// The tour's path at 640 × 360, `FRAMES` frames spread over it.
fn frames() -> Vec<PathSample> {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/architectural_tour/assets/tour_path.json"
    );
    CameraPath::load(path).unwrap().spread(FRAMES)
}

/// Weights by group name over `rec`'s pack.
fn weights(rec: &Reconstructor, settings: &[(&str, f32)]) -> GroupWeights {
    let names = &rec.pack().manifest().light_groups.as_ref().unwrap().names;
    let settings: Vec<(String, Vec3)> = settings
        .iter()
        .map(|(n, w)| ((*n).to_owned(), Vec3::splat(*w)))
        .collect();
    GroupWeights::from_names(names, &settings).unwrap()
}

fn render_all(rec: &Reconstructor, frames: &[PathSample]) {
    for f in frames {
        black_box(
            rec.render(&f.camera, f.scene_time, Mode::GeometryAssisted)
                .unwrap(),
        );
    }
}

/// Mean milliseconds per frame of `run` over `n` runs of the frames.
fn mean_ms(n: usize, frames: usize, mut run: impl FnMut()) -> f64 {
    let clock = Instant::now();
    for _ in 0..n {
        run();
    }
    clock.elapsed().as_secs_f64() * 1e3 / (n * frames) as f64
}

fn bench(c: &mut Criterion) {
    let (Some(plain), Some(grouped)) = (pack("PLENOPTIC_TOUR_PACK"), pack("PLENOPTIC_GROUPS_PACK"))
    else {
        eprintln!(
            "light_groups: set PLENOPTIC_TOUR_PACK and PLENOPTIC_GROUPS_PACK to the tour baked \
             without and with groups (see the bench's doc); nothing measured"
        );
        return;
    };
    let frames = frames();
    let plain = Reconstructor::open(plain).unwrap();
    let mut cases: Vec<(&str, Reconstructor)> = vec![("ungrouped", plain)];
    for (name, settings) in [
        ("groups_as_baked", &[][..]),
        ("lamp_off", &[("lamp", 0.0)][..]),
        ("daylight_0.2", &[("sun", 0.2), ("sky", 0.2)][..]),
    ] {
        let mut rec = Reconstructor::open(&grouped).unwrap();
        let w = weights(&rec, settings);
        rec.set_light_weights(w);
        cases.push((name, rec));
    }
    let mut group = c.benchmark_group("light_groups");
    group.sample_size(10);
    let mut means = Vec::new();
    for (name, rec) in &cases {
        render_all(rec, &frames); // warm the chunk cache
        group.bench_function(format!("{name}/640x360"), |b| {
            b.iter(|| render_all(rec, &frames))
        });
        means.push((*name, mean_ms(3, frames.len(), || render_all(rec, &frames))));
    }
    let mut dimmer = Reconstructor::open(&grouped).unwrap();
    let mut step = 0u32;
    let mut moving = || {
        step += 1;
        let w = 0.2 + 0.01 * (step % 2) as f32;
        let weights = weights(&dimmer, &[("sun", w), ("sky", w)]);
        dimmer.set_light_weights(weights);
        render_all(&dimmer, &frames);
    };
    moving();
    group.bench_function("dimmer_moving/640x360", |b| b.iter(&mut moving));
    means.push(("dimmer_moving", mean_ms(3, frames.len(), moving)));
    group.finish();
    let base = means[0].1;
    for (name, ms) in &means {
        println!(
            "light_groups {name}: {ms:.1} ms per frame, {:.2}× the ungrouped pack's",
            ms / base
        );
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
