//! Bake time per phase (`plenoptic_bake`) on a small animated scene: a closed room (six wall
//! slabs), a box sliding across the floor, a static box and a point light; a segment view
//! space; range-image faces of 16 px at 2 samples per pixel, 1,000 temporal-volume samples per
//! base view.
//!
//! Phases, as `plenoptic bake` runs them: `plan` (space and time decomposition from
//! id-images), `ambient_field` (ambient key times and fields), `range_images` (every base view
//! and time key), `volumes` (every base view), `write` (assembling the pack from the work
//! directory's items: proxy geometry, tracks, manifest). All on all cores.
//!
//! `denoise`: the range-image denoiser (`plenoptic_bake::denoise`) on one 128-px and one
//! 256-px cube of the scene with its guides, all cores; the cube's rendering is not timed.
//! `smooth_ambient_*`: the smoothing of the final gather's ambient light that every bake
//! runs (`LightingCube::smooth_ambient` at the bake's passes for the size), on the same
//! cubes.
//!
//! `cargo bench --no-default-features --bench bake` (`-- denoise` for the denoiser only)

use std::hint::black_box;
use std::path::Path;

use criterion::{BatchSize, Criterion, criterion_group, criterion_main};
use plenoptic_bake::bake::render_item;
use plenoptic_bake::plan;
use plenoptic_bake::render::BakeRenderer;
use plenoptic_bake::work::{WorkDir, WorkItem, work_items};
use plenoptic_bake::write::{AssembleOptions, assemble};
use plenoptic_scene::Track;
use plenoptic_scene::builder::{LightDesc, MaterialDesc, NodeDesc, SceneBuilder};
use plenoptic_scene::recipe::Recipe;
use plenoptic_trace::SceneAccel;
use plenoptic_trace::glam::Vec3;

fn scene() -> plenoptic_scene::Scene {
    let mut b = SceneBuilder::new();
    let grey = b.add_material(MaterialDesc::diffuse(Vec3::splat(0.6)));
    let red = b.add_material(MaterialDesc::diffuse(Vec3::new(0.8, 0.2, 0.2)));
    let (h, w) = (2.0f32, 0.2f32);
    for (i, axis) in [Vec3::X, Vec3::Y, Vec3::Z].into_iter().enumerate() {
        let size = Vec3::splat(2.0 * h + 2.0 * w) - axis * (2.0 * h + w);
        let mesh = b.add_box(format!("wall{i}"), size, grey);
        for s in [-1.0f32, 1.0] {
            b.add_node(
                NodeDesc::new(format!("wall{i}{s}"))
                    .mesh(mesh)
                    .translation(axis * s * (h + 0.5 * w)),
            );
        }
    }
    let cube = b.add_box("cube", Vec3::splat(0.8), red);
    let mover = b.add_node(NodeDesc::new("mover").mesh(cube));
    b.animate_translation(
        mover,
        Track::linear([
            (0.0, Vec3::new(-1.2, -1.6, 0.0)),
            (1.0, Vec3::new(1.2, -1.6, 0.0)),
        ]),
    );
    b.add_node(
        NodeDesc::new("still")
            .mesh(cube)
            .translation(Vec3::new(0.8, -1.6, 1.2)),
    );
    b.add_node(
        NodeDesc::new("lamp")
            .light(LightDesc::point(Vec3::ONE, 20.0))
            .translation(Vec3::new(0.0, 1.5, 0.0)),
    );
    b.build_scene().unwrap()
}

const RECIPE: &str = r#"
output = "bench.pack"
[[scene]]
file = "bench.glb"
[view_space]
kind = "segment"
a = [-1.0, 0.3, -1.0]
b = [1.0, 0.3, 1.0]
[time]
start = 0.0
end = 1.0
frame_rate = 24.0
[quality]
preset = "draft"
q = 0.9
id_image_size = 16
range_image_size = 16
samples_per_pixel = 2
ambient_samples = 16
ambient_rms = 0.2
temporal_volume_samples = 1000
max_specular_depth = 1
max_time_depth = 3
max_space_depth = 1
"#;

fn bench(c: &mut Criterion) {
    let scene = scene();
    let recipe = Recipe::from_str_named(RECIPE, "bench.toml", Path::new(".")).unwrap();
    let accel = SceneAccel::new(&scene).unwrap();
    let (mut p, _) = plan::decompose(&recipe, &scene, &accel);
    let fields = plan::ambient_phase(&mut p, &scene, &accel).unwrap();
    let items = work_items(&p);
    let ranges: Vec<WorkItem> = items
        .iter()
        .copied()
        .filter(|i| matches!(i, WorkItem::RangeImage { .. }))
        .collect();
    let volumes: Vec<WorkItem> = items
        .iter()
        .copied()
        .filter(|i| matches!(i, WorkItem::Volume { .. }))
        .collect();
    eprintln!(
        "bake bench: {} base views, {} range images, {} volumes, {} ambient keys",
        p.base_views.len(),
        ranges.len(),
        volumes.len(),
        p.ambient_keys.len()
    );
    let renderer = BakeRenderer::new(&p, &accel, &fields);

    let mut g = c.benchmark_group("bake");
    g.sample_size(10);
    g.bench_function("plan", |b| {
        b.iter(|| black_box(plan::decompose(&recipe, &scene, &accel)))
    });
    g.bench_function("ambient_field", |b| {
        b.iter(|| {
            let mut q = p.clone();
            black_box(plan::ambient_phase(&mut q, &scene, &accel).unwrap())
        })
    });
    g.bench_function("range_images", |b| {
        b.iter(|| {
            for i in &ranges {
                black_box(render_item(&renderer, i).unwrap());
            }
        })
    });
    g.bench_function("volumes", |b| {
        b.iter(|| {
            for i in &volumes {
                black_box(render_item(&renderer, i).unwrap());
            }
        })
    });
    let dir = tempfile::tempdir().unwrap();
    let work = WorkDir {
        path: dir.path().join("bench.pack.work"),
    };
    work.create().unwrap();
    for i in &items {
        work.write_item(i, &render_item(&renderer, i).unwrap())
            .unwrap();
    }
    let out = dir.path().join("bench.pack");
    g.bench_function("write", |b| {
        b.iter(|| {
            black_box(
                assemble(&p, &scene, &accel, &work, &out, &AssembleOptions::default()).unwrap(),
            )
        })
    });
    g.finish();
}

/// The denoiser alone on one range image of the scene (real guides: ids, normals and
/// distances of the room, the boxes and the lamp's lighting at 2 spp), per cube size.
fn bench_denoise(c: &mut Criterion) {
    use plenoptic_bake::denoise::cube::CubeGrid;
    use plenoptic_bake::denoise::{
        DenoiseSettings, LightingCube, ambient_passes, atrous::denoise_on,
    };
    use plenoptic_trace::{CubeCamera, MultiStageRenderer, MultiStageSettings};
    let scene = scene();
    let recipe = Recipe::from_str_named(RECIPE, "bench.toml", Path::new(".")).unwrap();
    let accel = SceneAccel::new(&scene).unwrap();
    let (mut p, _) = plan::decompose(&recipe, &scene, &accel);
    let fields = plan::ambient_phase(&mut p, &scene, &accel).unwrap();
    let placed = accel.at_time(0.0);
    let renderer = MultiStageRenderer::new(
        MultiStageSettings {
            samples_per_pixel: 2,
            max_specular_depth: 1,
            final_gather: 1,
            ..MultiStageSettings::default()
        },
        &fields[0],
    );
    let settings = DenoiseSettings::default();
    let mut g = c.benchmark_group("denoise");
    g.sample_size(10);
    for n in [128u32, 256] {
        let cube = CubeCamera::new(p.base_views[0].position, n).unwrap();
        let lighting = LightingCube::from_faces(n, &renderer.render_cube(&placed, &cube));
        let grid = CubeGrid::new(n);
        g.bench_function(format!("cube_{n}"), |b| {
            b.iter_batched(
                || lighting.clone(),
                |mut l| {
                    denoise_on(&mut l, &grid, &settings);
                    black_box(l)
                },
                BatchSize::LargeInput,
            )
        });
        g.bench_function(format!("smooth_ambient_{n}"), |b| {
            b.iter_batched(
                || lighting.clone(),
                |mut l| {
                    l.smooth_ambient(ambient_passes(n));
                    black_box(l)
                },
                BatchSize::LargeInput,
            )
        });
    }
    g.finish();
}

criterion_group!(benches, bench, bench_denoise);
criterion_main!(benches);
