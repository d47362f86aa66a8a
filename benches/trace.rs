//! Tracing throughput of `plenoptic_trace`, single-threaded:
//!
//! - rays per second for closest-hit and shadow queries, coherent (pinhole camera rays) and
//!   incoherent (random points and directions in the scene bounds), on a scene of ~140k
//!   triangles in 14 objects (8 finely tessellated spheres, boxes, a floor), through the
//!   two-level structure (`SceneAccel`/`PlacedScene`), and — in the same run, on the same rays
//!   — through obvhs's bare traversal of one flat BVH over all world-space triangles
//!   (`FlatBvh`); the ratio ours/bare is printed at the start;
//! - the time to place the scene (top-level rebuild) at a new time;
//! - samples per second of the reference path tracer and the multi-stage renderer on the
//!   furnished room, on all cores (the ambient field is built once, outside the measurement,
//!   and its build is measured separately);
//! - the path tracer in a room lit by the sky through one window, with and without
//!   environment importance sampling: time per frame, and the noise at equal time.
//!
//! `cargo bench --no-default-features --bench trace`

use std::hint::black_box;
use std::time::Instant;

use criterion::measurement::WallTime;
use criterion::{BenchmarkGroup, Criterion, Throughput, criterion_group, criterion_main};
use plenoptic_trace::glam::{Vec2, Vec3};
use plenoptic_trace::sampling::{Sampler, uniform_sphere};
use plenoptic_trace::*;

fn big_scene() -> plenoptic_scene::Scene {
    let mut b = shapes::SceneBuilder::default();
    let grey = b.material(shapes::plastic(Vec3::splat(0.6), 0.5));
    b.object("floor", shapes::quad(Vec2::splat(30.0)), grey, Vec3::ZERO);
    for i in 0..8 {
        let x = (i % 4) as f32 * 3.0 - 4.5;
        let z = (i / 4) as f32 * 3.0 - 1.5;
        b.object(
            "sphere",
            shapes::uv_sphere(1.0, 128, 68),
            grey,
            Vec3::new(x, 1.0, z),
        );
    }
    for i in 0..5 {
        let x = i as f32 * 2.5 - 5.0;
        b.object(
            "box",
            shapes::cuboid(Vec3::new(1.0, 2.0, 1.0)),
            grey,
            Vec3::new(x, 1.0, 3.5),
        );
    }
    b.point_light(Vec3::new(0.0, 6.0, 0.0), Vec3::ONE, 50.0);
    b.build()
}

const RAYS: usize = 64 * 64;

fn coherent_rays() -> Vec<Ray> {
    let cam = PinholeCamera::look_at(
        Vec3::new(0.0, 4.0, 12.0),
        Vec3::new(0.0, 0.5, 0.0),
        Vec3::Y,
        0.9,
        64,
        64,
    )
    .unwrap();
    (0..64)
        .flat_map(|y| (0..64).map(move |x| (x, y)))
        .map(|(x, y)| cam.ray(x, y, Vec2::splat(0.5)).unwrap())
        .collect()
}

fn incoherent_rays() -> Vec<Ray> {
    let mut s = Sampler::new(1, 2, 3);
    let lo = Vec3::new(-7.0, 0.05, -4.0);
    let hi = Vec3::new(7.0, 4.0, 5.0);
    (0..RAYS)
        .map(|_| {
            let p = lo + (hi - lo) * Vec3::new(s.next_f32(), s.next_f32(), s.next_f32());
            Ray::new(p, uniform_sphere(s.next_2d()))
        })
        .collect()
}

fn with_tmax(rays: &[Ray], tmax: f32) -> Vec<Ray> {
    rays.iter().map(|r| Ray { tmax, ..*r }).collect()
}

/// Benchmark `query/structure`: `hit` over every ray of `rays`, counting the hits.
fn cast(
    g: &mut BenchmarkGroup<'_, WallTime>,
    query: &str,
    structure: &str,
    rays: &[Ray],
    hit: impl Fn(&Ray) -> bool,
) {
    g.bench_function(format!("{query}/{structure}"), |b| {
        b.iter(|| rays.iter().filter(|r| hit(r)).count())
    });
}

fn rays(c: &mut Criterion) {
    let scene = big_scene();
    let accel = SceneAccel::new(&scene).unwrap();
    let placed = accel.at_time(0.0);
    let flat = FlatBvh::new(&placed);
    let sets = [
        ("coherent", coherent_rays()),
        ("incoherent", incoherent_rays()),
    ];
    println!(
        "scene: {} triangles in {} objects",
        flat.triangle_count(),
        scene.objects.len()
    );

    // Same-run ratios, by plain timing (criterion's figures below are the reference).
    for (name, rays) in &sets {
        let time = |f: &dyn Fn() -> usize| {
            let t = Instant::now();
            let mut n = 0;
            for _ in 0..20 {
                n += f();
            }
            (t.elapsed().as_secs_f64(), n)
        };
        let (ours, n1) = time(&|| {
            rays.iter()
                .filter(|r| placed.intersect(r).is_some())
                .count()
        });
        let (bare, n2) = time(&|| rays.iter().filter(|r| flat.closest(r).is_some()).count());
        println!(
            "closest {name}: ours {:.2} Mrays/s, bare obvhs {:.2} Mrays/s, ratio ours/bare {:.2} (hits {n1} vs {n2})",
            (20 * RAYS) as f64 / ours / 1e6,
            (20 * RAYS) as f64 / bare / 1e6,
            bare / ours
        );
    }

    let mut g = c.benchmark_group("rays");
    g.throughput(Throughput::Elements(RAYS as u64));
    for (name, set) in &sets {
        let shadow = with_tmax(set, 3.0);
        let (closest, shadow_of) = (format!("closest_{name}"), format!("shadow_{name}"));
        cast(&mut g, &closest, "ours", set, |r| {
            black_box(placed.intersect(r)).is_some()
        });
        cast(&mut g, &closest, "bare_obvhs", set, |r| {
            black_box(flat.closest(r)).is_some()
        });
        cast(&mut g, &shadow_of, "ours", &shadow, |r| {
            black_box(placed.occluded(r))
        });
        cast(&mut g, &shadow_of, "bare_obvhs", &shadow, |r| {
            black_box(flat.occluded(r))
        });
    }
    g.finish();

    let mut g = c.benchmark_group("placement");
    g.bench_function("at_time_tlas_rebuild", |b| {
        b.iter(|| black_box(accel.at_time(0.5)).time())
    });
    g.finish();
}

fn renderers(c: &mut Criterion) {
    let scene = shapes::furnished_room();
    let accel = SceneAccel::new(&scene).unwrap();
    let placed = accel.at_time(1.0);
    let cam = shapes::room_camera(32, 24).unwrap();
    let ambient = AmbientSettings {
        quality: 0.3,
        rays_per_point: 64,
        seed: 2,
        ..AmbientSettings::low()
    };
    let field = AmbientField::build(&placed, &ambient).unwrap();
    let pt = PathTracer::new(PathTracerSettings {
        samples_per_pixel: 1,
        max_depth: 16,
        ..PathTracerSettings::default()
    });
    let ms = MultiStageRenderer::new(
        MultiStageSettings {
            samples_per_pixel: 1,
            shadow_samples: 2,
            glossy_samples: 2,
            max_specular_depth: 3,
            seed: 3,
            final_gather: 0,
        },
        &field,
    );
    // Rendering runs on rayon's global pool (all cores).
    let mut g = c.benchmark_group("room_samples");
    g.throughput(Throughput::Elements(32 * 24));
    g.bench_function("path_tracer", |b| {
        b.iter(|| black_box(pt.render(&placed, &cam)))
    });
    g.bench_function("multi_stage", |b| {
        b.iter(|| black_box(ms.render(&placed, &cam)))
    });
    g.finish();
    let mut g = c.benchmark_group("ambient_field");
    g.sample_size(10);
    g.bench_function("build_room_q0.3", |b| {
        b.iter(|| {
            AmbientField::build(&placed, &ambient)
                .unwrap()
                .mean_irradiance()
        })
    });
    g.finish();
}

/// Relative noise of a render: the luminance RMS of the difference of two independent
/// renders, over √2 (one render's σ), over the mean.
fn relative_noise(pt: &PathTracer, placed: &PlacedScene<'_>, cam: &PinholeCamera) -> f64 {
    let mut a = *pt;
    let mut b = *pt;
    a.settings.seed = 101;
    b.settings.seed = 202;
    let (a, b) = (
        a.render(placed, cam).radiance(),
        b.render(placed, cam).radiance(),
    );
    let lrms = metrics::relative_lrms(&a, &b);
    lrms / std::f64::consts::SQRT_2
}

/// The path tracer in the sky-lit room with and without environment importance sampling:
/// time per frame measured by criterion, and the noise at equal time printed before it (noise
/// at 64 spp times √(time per frame), the inverse square root of the estimator's
/// efficiency).
fn environment_sampling(c: &mut Criterion) {
    let scene = shapes::sky_lit_room();
    let accel = SceneAccel::new(&scene).unwrap();
    let placed = accel.at_time(0.0);
    let cam = shapes::sky_room_camera(32, 24).unwrap();
    let tracer = |on: bool, spp: u32| {
        PathTracer::new(PathTracerSettings {
            samples_per_pixel: spp,
            max_depth: 16,
            environment_sampling: on,
            ..PathTracerSettings::default()
        })
    };
    let mut efficiency = [0.0f64; 2];
    for (i, on) in [true, false].into_iter().enumerate() {
        let pt = tracer(on, 64);
        let start = Instant::now();
        let noise = relative_noise(&pt, &placed, &cam);
        let seconds = start.elapsed().as_secs_f64() / 2.0;
        efficiency[i] = noise * seconds.sqrt();
        println!(
            "sky-lit room, environment sampling {}: noise {noise:.4} at 64 spp in {seconds:.3} s per frame",
            if on { "on" } else { "off" },
        );
    }
    println!(
        "noise at equal time, off / on: {:.3}",
        efficiency[1] / efficiency[0]
    );
    let mut g = c.benchmark_group("sky_room_path_tracer_8spp");
    g.sample_size(10);
    for on in [true, false] {
        let pt = tracer(on, 8);
        let name = if on {
            "environment_sampling"
        } else {
            "bsdf_sampling_only"
        };
        g.bench_function(name, |b| b.iter(|| black_box(pt.render(&placed, &cam))));
    }
    g.finish();
}

criterion_group!(benches, rays, renderers, environment_sampling);
criterion_main!(benches);
