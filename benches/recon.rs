//! Reconstruction speed: milliseconds per frame for each mode at 640×360 and 1280×720 from
//! four base views (face size 128, five time keys, temporal volumes), on a synthetic pack
//! built in the setup; the geometry-assisted mode also with seamless bilinear cube filtering
//! (`geometry_bilinear`, `ReconSettings::cube_filter`; the other cases use the default,
//! nearest texel) and with materials (`geometry_textured`: pack 2.0's albedo from a 256²
//! texture at each pixel's UV × bilinear lighting + non-diffuse, `Shading::Materials`; the
//! lighting looked up at a quarter of the pixels, and `geometry_textured_dense` the same with
//! `ReconSettings::sparse_lighting` off, every pixel looked up), and
//! with pack 3's runtime sun on top (`geometry_sun`: the room with a skylight, the sun's
//! direct light through each pixel's BSDF with `ReconSettings::sun_shadow_rays` = 4 shadow
//! rays against the proxies), and with a mirror and a glossy metal wall that reflect for the
//! camera (`geometry_reflections`, `Specular::Marched`: rays answered where the proxies say
//! they meet a surface, the mirror's hits shaded as pixels) beside the same pack with every
//! reflected ray marched, as the plugin's GPU path does (`geometry_reflections_marched`,
//! `ReconSettings::shaded_reflections` off) and with the baked specular
//! (`geometry_reflections_baked`); and
//! the reference path tracer's time for the same frame, as a ratio
//! measured in the same run. The chunk cache is warm (decoded cubes, interleaved texels and
//! binned volume blocks are built on the first frame), as in a walk-through.
//!
//! Run: `cargo bench --no-default-features --bench recon -- --warm-up-time 1 --measurement-time 3`

#[path = "../crates/plenoptic_recon/tests/common/mod.rs"]
mod common;

use std::hint::black_box;
use std::time::Instant;

use common::*;
use criterion::{Criterion, criterion_group, criterion_main};
use plenoptic_recon::{Camera, CubeFilter, Mode, Reconstructor, Specular};
use plenoptic_trace::glam::Vec3;
use plenoptic_trace::{PathTracer, PathTracerSettings, SceneAccel};

const T: f32 = 0.75;
const PATH_SPP: u32 = 4;

fn camera(w: u32, h: u32) -> Camera {
    Camera::look_at(
        Vec3::new(0.1, 1.3, 1.2),
        Vec3::new(0.0, 0.6, -2.0),
        Vec3::Y,
        1.1,
        w,
        h,
    )
    .unwrap()
}

fn bench(c: &mut Criterion) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bench.pack");
    let scene = room(true);
    let mut spec = PackSpec::segment(4, vec![0.0, 0.5, 1.0, 1.5, 2.0], 128);
    spec.volume_samples = 12_000;
    write_pack(&scene, &spec, &path);
    let rec = Reconstructor::open(&path).unwrap();
    let mut bilinear = Reconstructor::open(&path).unwrap();
    bilinear.settings.cube_filter = CubeFilter::Bilinear;
    // The same scene with materials: textured albedo × lighting + non-diffuse (pack 2.0).
    let textured_path = dir.path().join("textured.pack");
    write_pack(
        &scene,
        &PackSpec {
            materials: Materials::Textured,
            ..spec.clone()
        },
        &textured_path,
    );
    let textured = Reconstructor::open(&textured_path).unwrap();
    // The same with the lighting looked up at every pixel (`ReconSettings::sparse_lighting`
    // off): the comparison for the sparse lighting, in the same run.
    let mut textured_dense = Reconstructor::open(&textured_path).unwrap();
    textured_dense.settings.sparse_lighting = false;
    // Textured, in the room with a skylight, with the sun left to the runtime (pack 3).
    let sun_path = dir.path().join("sun.pack");
    write_pack(
        &open_room(),
        &PackSpec {
            materials: Materials::Textured,
            direct_sun: true,
            ..spec.clone()
        },
        &sun_path,
    );
    let sun = Reconstructor::open(&sun_path).unwrap();
    // A mirror and a glossy metal wall: reflections marched for the camera, against the same
    // pack with the baked specular.
    let mirror_path = dir.path().join("mirror.pack");
    write_pack(
        &scene,
        &PackSpec {
            materials: Materials::Mirror,
            ..spec.clone()
        },
        &mirror_path,
    );
    let mirror = Reconstructor::open(&mirror_path).unwrap();
    let mut mirror_marched = Reconstructor::open(&mirror_path).unwrap();
    mirror_marched.settings.shaded_reflections = false;
    let mut mirror_baked = Reconstructor::open(&mirror_path).unwrap();
    mirror_baked.settings.specular = Specular::Baked;
    let mut group = c.benchmark_group("recon");
    group.sample_size(10);
    for (w, h) in [(640, 360), (1280, 720)] {
        let cam = camera(w, h);
        for mode in Mode::ALL {
            let _ = rec.render(&cam, T, mode).unwrap(); // warm the chunk cache
            group.bench_function(format!("{}/{w}x{h}", mode.name()), |b| {
                b.iter(|| black_box(rec.render(black_box(&cam), T, mode).unwrap()))
            });
        }
        let mode = Mode::GeometryAssisted;
        let _ = bilinear.render(&cam, T, mode).unwrap();
        group.bench_function(format!("geometry_bilinear/{w}x{h}"), |b| {
            b.iter(|| black_box(bilinear.render(black_box(&cam), T, mode).unwrap()))
        });
        let _ = textured.render(&cam, T, mode).unwrap();
        group.bench_function(format!("geometry_textured/{w}x{h}"), |b| {
            b.iter(|| black_box(textured.render(black_box(&cam), T, mode).unwrap()))
        });
        let _ = textured_dense.render(&cam, T, mode).unwrap();
        group.bench_function(format!("geometry_textured_dense/{w}x{h}"), |b| {
            b.iter(|| black_box(textured_dense.render(black_box(&cam), T, mode).unwrap()))
        });
        let (_, report) = sun.render(&cam, T, mode).unwrap();
        assert!(sun.runtime_sun().is_some(), "{:?}", report.missing);
        group.bench_function(format!("geometry_sun/{w}x{h}"), |b| {
            b.iter(|| black_box(sun.render(black_box(&cam), T, mode).unwrap()))
        });
        let (_, report) = mirror.render(&cam, T, mode).unwrap();
        assert!(report.reflections.0 > 0, "{:?}", report.reflections);
        eprintln!(
            "geometry_reflections/{w}x{h}: {:.1} % of the pixels marched, {} of them unanswered",
            100.0 * report.reflections.0 as f64 / (w * h) as f64,
            report.reflections.1
        );
        let _ = mirror_baked.render(&cam, T, mode).unwrap();
        let _ = mirror_marched.render(&cam, T, mode).unwrap();
        group.bench_function(format!("geometry_reflections/{w}x{h}"), |b| {
            b.iter(|| black_box(mirror.render(black_box(&cam), T, mode).unwrap()))
        });
        group.bench_function(format!("geometry_reflections_marched/{w}x{h}"), |b| {
            b.iter(|| black_box(mirror_marched.render(black_box(&cam), T, mode).unwrap()))
        });
        group.bench_function(format!("geometry_reflections_baked/{w}x{h}"), |b| {
            b.iter(|| black_box(mirror_baked.render(black_box(&cam), T, mode).unwrap()))
        });
    }
    let accel = SceneAccel::new(&scene).unwrap();
    let tracer = PathTracer::new(PathTracerSettings {
        samples_per_pixel: PATH_SPP,
        ..PathTracerSettings::default()
    });
    let pin = plenoptic_eval::camera::to_pinhole(&camera(640, 360)).unwrap();
    group.bench_function(format!("path_tracer_{PATH_SPP}spp/640x360"), |b| {
        b.iter(|| {
            let placed = accel.at_time(T);
            black_box(tracer.render(&placed, &pin))
        })
    });
    group.finish();

    print_ratios(
        &tracer,
        &accel,
        &[
            (&rec, None),
            (&textured, Some("geometry_textured")),
            (&textured_dense, Some("geometry_textured_dense")),
        ],
    );
}

/// Each mode's frame at 640 × 360 against the path tracer's, timed here in the same run
/// (median of 5), printed as a ratio. `cases`: a reconstructor with the case's name, or
/// `None` for every mode of that reconstructor under the mode's name.
fn print_ratios(tracer: &PathTracer, accel: &SceneAccel, cases: &[(&Reconstructor, Option<&str>)]) {
    let pin = plenoptic_eval::camera::to_pinhole(&camera(640, 360)).unwrap();
    let median = |f: &mut dyn FnMut()| {
        let mut v: Vec<f64> = (0..5)
            .map(|_| {
                let s = Instant::now();
                f();
                s.elapsed().as_secs_f64() * 1e3
            })
            .collect();
        v.sort_by(f64::total_cmp);
        v[2]
    };
    let cam = camera(640, 360);
    let pt = median(&mut || {
        black_box(tracer.render(&accel.at_time(T), &pin));
    });
    let cases = cases.iter().flat_map(|&(rec, name)| match name {
        Some(name) => vec![(Mode::GeometryAssisted, name, rec)],
        None => Mode::ALL.into_iter().map(|m| (m, m.name(), rec)).collect(),
    });
    for (mode, name, rec) in cases {
        let ms = median(&mut || {
            black_box(rec.render(&cam, T, mode).unwrap());
        });
        let (_, report) = rec.render(&cam, T, mode).unwrap();
        #[expect(clippy::print_stdout, reason = "the benchmark reports its ratio")]
        {
            println!(
                "ratio 640x360 {name}: {ms:.2} ms vs path tracer {PATH_SPP} spp {pt:.1} ms = {:.0}× faster; {:?}; {} pixels' lighting interpolated; stages {:?}",
                pt / ms,
                report.fallback,
                report.interpolated_pixels,
                report.stage_ms
            );
        }
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
