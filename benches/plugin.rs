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
//!   reconstruction (no clear colour left, more than the placeholder's one colour), at
//!   320 × 240 with one camera and at 1280 × 720 with one and with two cameras;
//! - `plugin/frame`: one `App::update` of a settled app at 1280 × 720 with one and with two
//!   plenoptic cameras (each reconstructs its own frame: its own proxies and passes);
//! - `plugin/costs`: the same frames with the shaders' cost counters on
//!   (`PlenopticSettings::cost_counters`), on HDR cameras without MSAA (as the tests' frames),
//!   each case with the screen-space hole fill (the default), with the lookup kernel too
//!   (`PlenopticSettings::lookup_kernel`; with the sparse lighting, the cameras' default,
//!   and `_dense` without it, `ReconSettings::sparse_lighting`) and with the fragment fill
//!   (`PlenopticSettings::screen_fill` off): each prints, per fragment, its lookups, loads by
//!   width, samples, march steps and fallback entries, the screen-fill kernel's loads, the
//!   loads of a diffuse fragment, and the mean over 32-pixel groups of the group's largest
//!   loads and work against the mean (what divergence costs), then the two fills' ratio.
//!   Counts need no GPU: on lavapipe they are what a GPU would do, which its frame times are
//!   not.
//!
//! With `PLENOPTIC_TOUR_PACK` set to the architectural tour's baked pack, both groups also
//! measure the tour (`tour_1280x720`: one camera at 35 % of its camera path, in room B;
//! `plugin/frame` also room A with its mirror in view, `tour_mirror_1280x720`, and the same
//! with the baked specular instead of reflections marched for the camera,
//! `tour_mirror_baked_specular_1280x720`). The `plugin/frame` cameras render to an 8-bit
//! target with Bevy's default MSAA and take the screen-space hole fill; its
//! `tour_hdr_lookup_kernel_1280x720`, `tour_hdr_lookup_kernel_dense_1280x720`,
//! `tour_hdr_screen_fill_1280x720` and `tour_hdr_fragment_fill_1280x720` cases are the tour
//! on an HDR camera without MSAA with the lookup kernel (with and without the sparse
//! lighting), with the lookups in the fragments and the screen fill, and with the fragment
//! fill; `tour_hdr_screen_fill_msaa4_1280x720` is the screen-fill case with 4× MSAA. With
//! `PLENOPTIC_BENCH_PASSES` set, each frame case also prints its passes' CPU and GPU times
//! (Bevy's render diagnostics).
//!
//! On CI the only adapter is Mesa's software Vulkan driver (lavapipe): its frame times say
//! how the cost grows with pixels and cameras, not what a real GPU takes, and time to first
//! frame on it is dominated by compiling the shaders on the CPU.
//!
//! `cargo bench --no-default-features --features bevy --bench plugin` (the `bevy` feature is
//! required; the window feature is not).

#[path = "../crates/plenoptic_recon/tests/common/mod.rs"]
mod pack;

use std::hint::black_box;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use bevy::camera::{Hdr, RenderTarget};
use bevy::core_pipeline::tonemapping::Tonemapping;
use bevy::prelude::*;
use bevy::render::gpu_readback::{Readback, ReadbackComplete};
use bevy::render::render_resource::{TextureFormat, TextureUsages};
use bevy::window::ExitCondition;
use bevy_plenoptic::prelude::*;
use bevy_plenoptic::reconstruct::counters::CostReport;
use bevy_plenoptic::reconstruct::geometry::view::ViewBuffer;
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

/// An app on the default plugins without a window, with plenoptic, loading from `assets`.
fn headless_app(assets: &std::path::Path) -> App {
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
    if std::env::var_os("PLENOPTIC_BENCH_PASSES").is_some() {
        app.add_plugins(bevy::render::diagnostic::RenderDiagnosticsPlugin);
    }
    app.finish();
    app.cleanup();
    app
}

/// An app with plenoptic cameras, each with a read-back of its image into a slot.
struct Scene {
    app: App,
    cameras: Vec<Entity>,
    latest: Vec<Arc<Mutex<Option<Vec<u8>>>>>,
}

/// Where a plenoptic camera looks from, with which vertical field of view (`None`: Bevy's
/// default) and at which scene time.
struct View {
    transform: Transform,
    vfov: Option<f32>,
    time: f32,
    settings: ReconSettings,
    lights: LightSettings,
}

/// `cameras` split-screen players 0.5 m apart in the room of `room.pack`.
fn room_views(cameras: usize) -> Vec<View> {
    (0..cameras)
        .map(|n| View {
            transform: Transform::from_translation(Vec3::new(0.3 - 0.5 * n as f32, 1.3, 1.0))
                .looking_at(Vec3::new(0.0, 0.8, -2.5), Vec3::Y),
            vfov: None,
            time: 0.7,
            settings: ReconSettings::default(),
            lights: LightSettings::default(),
        })
        .collect()
}

/// The architectural tour's pack named by `PLENOPTIC_TOUR_PACK` (baked by the example), or
/// `None` when the variable is not set.
fn tour_pack() -> Option<std::path::PathBuf> {
    std::env::var_os("PLENOPTIC_TOUR_PACK").map(Into::into)
}

/// A camera at `s` (0 to 1) along the tour's camera path in `file` (in its assets folder).
fn tour_view(file: &str, s: f32) -> View {
    // From this checkout, else from the working directory (the bench binary run from a copy
    // of the repository on another machine).
    let file = format!("examples/architectural_tour/assets/{file}");
    let at = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(&file);
    let path =
        plenoptic_recon::CameraPath::load(if at.exists() { at } else { file.into() }).unwrap();
    let (t0, t1) = path.time_range();
    let sample = path.sample(t0 + (t1 - t0) * s);
    let cam = sample.camera;
    View {
        transform: Transform::from_translation(cam.position).with_rotation(cam.orientation),
        vfov: Some(cam.vfov),
        time: sample.scene_time,
        settings: ReconSettings::default(),
        lights: LightSettings::default(),
    }
}

/// The tour's view measured: one camera at 35 % of its camera path, in room B (no mirror or
/// glossy surface in view).
fn tour() -> Option<(std::path::PathBuf, Vec<View>)> {
    Some((tour_pack()?, vec![tour_view("tour_path.json", 0.35)]))
}

/// A plenoptic camera per view on the pack `pack` in `assets`, each rendering `size` into
/// its own image, with a read-back of each image into a slot.
fn scene(assets: &std::path::Path, pack: &str, views: &[View], size: UVec2) -> Scene {
    let mut app = headless_app(assets);
    let handle: Handle<RadiancePack> = app.world().resource::<AssetServer>().load(pack.to_owned());
    let mut entities = Vec::new();
    let mut latest = Vec::new();
    for (n, view) in views.iter().enumerate() {
        let image = {
            let mut img =
                Image::new_target_texture(size.x, size.y, TextureFormat::Rgba8Unorm, None);
            img.texture_descriptor.usage |= TextureUsages::COPY_SRC;
            app.world_mut().resource_mut::<Assets<Image>>().add(img)
        };
        let mut camera = app.world_mut().spawn((
            Camera {
                clear_color: ClearColorConfig::Custom(Color::linear_rgb(1.0, 0.0, 0.0)),
                order: n as isize,
                ..default()
            },
            RenderTarget::Image(image.clone().into()),
            Tonemapping::None,
            bevy::camera::Exposure {
                ev100: bevy_plenoptic::camera::EV100_UNIT,
            },
            view.transform,
            PlenopticCamera {
                playback: Playback::Manual,
                time: view.time,
                settings: view.settings.clone(),
                lights: view.lights.clone(),
                ..PlenopticCamera::new(handle.clone())
            },
        ));
        if let Some(fov) = view.vfov {
            camera.insert(Projection::Perspective(PerspectiveProjection {
                fov,
                ..default()
            }));
        }
        let camera = camera.id();
        let slot: Arc<Mutex<Option<Vec<u8>>>> = Arc::default();
        let sink = slot.clone();
        app.world_mut().spawn(Readback::texture(image)).observe(
            move |event: On<ReadbackComplete>| {
                *sink.lock().unwrap() = Some(event.data.clone());
            },
        );
        entities.push(camera);
        latest.push(slot);
    }
    Scene {
        app,
        cameras: entities,
        latest,
    }
}

impl Scene {
    /// Updates until every camera's working set is resident and every read-back shows the
    /// reconstruction.
    fn until_reconstructed(&mut self) {
        let mut shown = vec![false; self.cameras.len()];
        for _ in 0..100_000 {
            self.app.update();
            for (n, &camera) in self.cameras.iter().enumerate() {
                let complete = self
                    .app
                    .world()
                    .get::<StreamState>(camera)
                    .unwrap()
                    .complete;
                if let Some(data) = self.latest[n].lock().unwrap().take() {
                    shown[n] = complete && shows_reconstruction(&data);
                }
            }
            if shown.iter().all(|s| *s) {
                return;
            }
        }
        panic!("no reconstructed frame");
    }
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

/// The room pack the frame benchmarks show, in a temporary folder.
fn room_pack() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    pack::write_pack(
        &pack::room(true),
        &pack::PackSpec::segment(3, vec![0.0, 1.0, 2.0], 32),
        &dir.path().join("room.pack"),
    );
    dir
}

/// Frame sizes and camera counts measured: the small first frame of earlier runs, and one
/// and two cameras at 1280 × 720 (each camera reconstructs its own frame).
const CASES: [(&str, UVec2, usize); 3] = [
    ("room_face32_320x240", UVec2::new(320, 240), 1),
    ("room_face32_1280x720_1camera", UVec2::new(1280, 720), 1),
    ("room_face32_1280x720_2cameras", UVec2::new(1280, 720), 2),
];

fn first_frame(c: &mut Criterion) {
    let dir = room_pack();
    let mut g = c.benchmark_group("plugin/time_to_first_frame");
    // Seconds per iteration: one iteration per sample, few samples.
    g.sample_size(10)
        .sampling_mode(SamplingMode::Flat)
        .warm_up_time(Duration::from_millis(1))
        .measurement_time(Duration::from_secs(10));
    for (name, size, cameras) in CASES {
        g.bench_function(name, |b| {
            b.iter_custom(|iters| {
                (0..iters)
                    .map(|_| {
                        let start = Instant::now();
                        scene(dir.path(), "room.pack", &room_views(cameras), size)
                            .until_reconstructed();
                        start.elapsed()
                    })
                    .sum()
            })
        });
    }
    if let Some((pack, views)) = tour() {
        let (assets, name) = tour_location(&pack);
        g.bench_function("tour_1280x720", |b| {
            b.iter_custom(|iters| {
                (0..iters)
                    .map(|_| {
                        let start = Instant::now();
                        scene(assets, name, &views, TOUR_SIZE).until_reconstructed();
                        start.elapsed()
                    })
                    .sum()
            })
        });
    }
    g.finish();
}

/// Says which adapter the frames were measured on (the figures mean little without it).
fn print_adapter(app: &App) {
    let info = app
        .world()
        .resource::<bevy::render::renderer::RenderAdapterInfo>();
    eprintln!(
        "adapter: {} ({:?}, {:?}, driver {} {})",
        info.name, info.backend, info.device_type, info.driver, info.driver_info
    );
}

/// With `PLENOPTIC_BENCH_PASSES` set (which adds Bevy's render diagnostics: timestamp
/// queries around each pass), prints each pass's mean CPU and GPU time over the last frames.
fn print_passes(app: &App) {
    let Some(store) = app
        .world()
        .get_resource::<bevy::diagnostic::DiagnosticsStore>()
    else {
        return;
    };
    let mut rows: Vec<(String, f64)> = store
        .iter()
        .filter(|d| d.path().as_str().starts_with("render/"))
        .filter_map(|d| Some((d.path().to_string(), d.average()?)))
        .collect();
    rows.sort_by(|a, b| a.0.cmp(&b.0));
    for (path, mean) in rows {
        eprintln!("{path}: {mean:.3}");
    }
}

/// The tour's frames are measured at 1280 × 720.
const TOUR_SIZE: UVec2 = UVec2::new(1280, 720);

/// The folder holding `pack` (the asset root) and its file name.
fn tour_location(pack: &std::path::Path) -> (&std::path::Path, &str) {
    let name = pack.file_name().and_then(|n| n.to_str()).unwrap();
    (pack.parent().unwrap(), name)
}

/// One frame of a settled app (every working set resident, pipelines compiled, the frame
/// reconstructed): `App::update`, main world and render world (pipelined) together,
/// read-backs included.
fn frame(c: &mut Criterion) {
    let dir = room_pack();
    let mut g = c.benchmark_group("plugin/frame");
    g.sample_size(10)
        .sampling_mode(SamplingMode::Flat)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(10));
    for (name, size, cameras) in &CASES[1..] {
        settled_frames(&mut g, name, || {
            scene(dir.path(), "room.pack", &room_views(*cameras), *size)
        });
    }
    if let Some((pack, views)) = tour() {
        let (assets, name) = tour_location(&pack);
        // Room A with its mirror in view (a tenth of the pixels reflect for the camera), with
        // the reflections marched and with the baked specular instead: what marching costs.
        let mirror = vec![tour_view("room_a_mirror.json", 0.0)];
        let baked: Vec<View> = mirror
            .iter()
            .map(|v| View {
                settings: ReconSettings {
                    specular: plenoptic_recon::Specular::Baked,
                    ..v.settings.clone()
                },
                lights: v.lights.clone(),
                ..*v
            })
            .collect();
        for (case, views) in [
            ("tour_1280x720", &views),
            ("tour_mirror_1280x720", &mirror),
            ("tour_mirror_baked_specular_1280x720", &baked),
        ] {
            settled_frames(&mut g, case, || scene(assets, name, views, TOUR_SIZE));
        }
        // An HDR camera without MSAA: the lookup kernel with the screen-space fill, the
        // lookups in the fragments with the screen-space fill (the default), and the fragment
        // fill.
        for (case, fill, kernel, sparse) in [
            ("tour_hdr_lookup_kernel_1280x720", true, true, true),
            ("tour_hdr_lookup_kernel_dense_1280x720", true, true, false),
            ("tour_hdr_screen_fill_1280x720", true, false, true),
            ("tour_hdr_fragment_fill_1280x720", false, false, true),
        ] {
            settled_frames(&mut g, case, || {
                let s = lookups_in(
                    hdr_scene(scene(assets, name, &views, TOUR_SIZE), fill),
                    kernel,
                );
                if sparse { s } else { dense_lighting(s) }
            });
        }
        // The same HDR camera with Bevy's 4× MSAA (docs/architecture.md, "Antialiasing").
        settled_frames(&mut g, "tour_hdr_screen_fill_msaa4_1280x720", || {
            with_msaa(
                hdr_scene(scene(assets, name, &views, TOUR_SIZE), true),
                Msaa::Sample4,
            )
        });
    }
    g.finish();
}

/// `s` with the lookup kernel on or off (`PlenopticSettings::lookup_kernel`).
fn lookups_in(mut s: Scene, kernel: bool) -> Scene {
    s.app
        .world_mut()
        .resource_mut::<PlenopticSettings>()
        .lookup_kernel = kernel;
    s
}

/// `s` with every camera's lighting looked up at every pixel
/// (`ReconSettings::sparse_lighting` off).
fn dense_lighting(mut s: Scene) -> Scene {
    for &camera in &s.cameras {
        if let Some(mut c) = s.app.world_mut().get_mut::<PlenopticCamera>(camera) {
            c.settings.sparse_lighting = false;
        }
    }
    s
}

/// `s` with HDR cameras without MSAA (one sample per pixel, as the counted frames), and the
/// screen fill on or off (`PlenopticSettings::screen_fill`).
fn hdr_scene(mut s: Scene, screen_fill: bool) -> Scene {
    s.app
        .world_mut()
        .resource_mut::<PlenopticSettings>()
        .screen_fill = screen_fill;
    for &camera in &s.cameras {
        s.app
            .world_mut()
            .entity_mut(camera)
            .insert((Hdr, Msaa::Off));
    }
    s
}

/// `s` with every camera's MSAA set to `msaa`.
fn with_msaa(mut s: Scene, msaa: Msaa) -> Scene {
    for &camera in &s.cameras {
        s.app.world_mut().entity_mut(camera).insert(msaa);
    }
    s
}

/// Measures `App::update` of the scene `make` builds, once it shows its reconstruction; says
/// which adapter drew it and, with `PLENOPTIC_BENCH_PASSES`, its passes' times. The scene is
/// made on the first call only (criterion calls the closure once per sample), and not at all
/// when a filter leaves the case out. Returns the scene, where it was made.
fn settled_frames(
    g: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
    name: &str,
    make: impl Fn() -> Scene,
) -> Option<Scene> {
    let mut settled: Option<Scene> = None;
    g.bench_function(name, |b| {
        let s = settled.get_or_insert_with(|| {
            let mut s = make();
            s.until_reconstructed();
            print_adapter(&s.app);
            s
        });
        b.iter(|| s.app.update())
    });
    if let Some(s) = &settled {
        print_passes(&s.app);
    }
    settled
}

/// The frames of `plugin/frame` with the cost counters on, on HDR cameras without MSAA (one
/// sample per pixel, so a count is per pixel): `App::update` timed, and the counts printed with the
/// screen fill and with the fragment fill, and their ratio (see the module doc).
fn costs(c: &mut Criterion) {
    let dir = room_pack();
    let mut g = c.benchmark_group("plugin/costs");
    g.sample_size(10)
        .sampling_mode(SamplingMode::Flat)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(10));
    compared_fills(&mut g, "room_face32_1280x720_1camera", || {
        scene(dir.path(), "room.pack", &room_views(1), TOUR_SIZE)
    });
    if let Some((pack, views)) = tour() {
        let (assets, name) = tour_location(&pack);
        let mirror = vec![tour_view("room_a_mirror.json", 0.0)];
        for (case, views) in [("tour_1280x720", &views), ("tour_mirror_1280x720", &mirror)] {
            compared_fills(&mut g, case, || scene(assets, name, views, TOUR_SIZE));
        }
        if let Some(groups) = std::env::var_os("PLENOPTIC_GROUPS_PACK") {
            compared_groups(
                &mut g,
                (assets, name),
                std::path::Path::new(&groups),
                &views,
            );
        }
    }
    g.finish();
}

/// The tour's view on the pack baked with light groups (`PLENOPTIC_GROUPS_PACK`, from
/// `tour_groups.toml`) with the lamp off and the daylight at 0.2, against the pack without
/// groups, both with the screen fill: the fetches per pixel of each, and the relight pass's
/// loads per pixel (per texel of each looked-up key: its key and shading texels and one per
/// blended layer), printed with their ratio.
fn compared_groups(
    g: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
    (assets, name): (&std::path::Path, &str),
    groups: &std::path::Path,
    views: &[View],
) {
    let plain = counted_frames(g, "tour_1280x720_without_groups", true, || {
        scene(assets, name, views, TOUR_SIZE)
    });
    let mut relit: Vec<View> = views
        .iter()
        .map(|v| View {
            settings: v.settings.clone(),
            lights: LightSettings::default(),
            ..*v
        })
        .collect();
    for v in &mut relit {
        v.lights
            .set("lamp", Vec3::ZERO)
            .set("sun", Vec3::splat(0.2))
            .set("sky", Vec3::splat(0.2));
    }
    let (group_assets, group_name) = tour_location(groups);
    let mut pass = None;
    let grouped = counted_frames_with(
        g,
        "tour_1280x720_groups_lamp_off_daylight_0.2",
        true,
        || scene(group_assets, group_name, &relit, TOUR_SIZE),
        |s| {
            let world = s.app.world();
            let p = world
                .get::<ViewBuffer>(s.cameras[0])
                .map(|v| v.params().clone());
            pass = p.map(|p| {
                let texels = f64::from(p.lookup_count * 6 * p.face * p.face);
                texels * f64::from(2 + p.light_layer_count) / f64::from(TOUR_SIZE.x * TOUR_SIZE.y)
            });
        },
    );
    if let (Some(a), Some(b), Some(pass)) = (plain, grouped, pass) {
        let (a, b) = (a.loads + a.kernel_loads, b.loads + b.kernel_loads);
        eprintln!(
            "costs light groups: fetches per pixel {b:.2} with groups + {pass:.2} in the relight \
             pass, {a:.2} without: {:.3}×",
            (b + pass) / a.max(1e-9)
        );
    }
}

/// One case counted with the lookup kernel and the screen-space fill, with the lookups in the
/// fragments and the screen-space fill, and with the fragment fill; their fetches per pixel
/// printed.
fn compared_fills(
    g: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
    case: &str,
    make: impl Fn() -> Scene,
) {
    let kernel = counted_frames(g, &format!("{case}_lookup_kernel"), true, || {
        lookups_in(make(), true)
    });
    let dense = counted_frames(g, &format!("{case}_lookup_kernel_dense"), true, || {
        dense_lighting(lookups_in(make(), true))
    });
    let screen = counted_frames(g, &format!("{case}_screen_fill"), true, &make);
    let fragment = counted_frames(g, &format!("{case}_fragment_fill"), false, &make);
    if let (Some(s), Some(d), Some(l), Some(f)) = (kernel, dense, screen, fragment) {
        let total = |r: &CostReport| r.loads + r.kernel_loads;
        eprintln!(
            "costs {case}: fetches per pixel {:.1} (fragments {:.1}, kernels {:.1}) with the \
             lookup kernel and the screen fill, {:.1} without the sparse lighting, \
             {:.1} ({:.1} + {:.1}) with the lookups in the \
             fragments, {:.1} with the fragment fill; a fragment's largest in 32 {:.1}, {:.1} \
             and {:.1}",
            total(&s),
            s.loads,
            s.kernel_loads,
            total(&d),
            total(&l),
            l.loads,
            l.kernel_loads,
            total(&f),
            s.group_max_loads,
            l.group_max_loads,
            f.group_max_loads,
        );
    }
}

/// [`settled_frames`] with the cost counters on (and the screen fill on or off), on HDR
/// cameras without MSAA; the first camera's counts printed and returned.
fn counted_frames(
    g: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
    name: &str,
    screen_fill: bool,
    make: impl Fn() -> Scene,
) -> Option<CostReport> {
    counted_frames_with(g, name, screen_fill, make, |_| {})
}

/// [`counted_frames`], handing the settled scene to `inspect` once its counts are read.
fn counted_frames_with(
    g: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
    name: &str,
    screen_fill: bool,
    make: impl Fn() -> Scene,
    mut inspect: impl FnMut(&Scene),
) -> Option<CostReport> {
    let settled = settled_frames(g, name, || {
        let mut s = hdr_scene(make(), screen_fill);
        s.app
            .world_mut()
            .resource_mut::<PlenopticSettings>()
            .cost_counters = true;
        s
    });
    let mut s = settled?;
    for _ in 0..100 {
        s.app.update();
        if let Some(r) = s.app.world().get::<CostReport>(s.cameras[0]) {
            print_costs(name, r);
            let r = r.clone();
            inspect(&s);
            return Some(r);
        }
    }
    eprintln!("{name}: no cost report was read back");
    None
}

/// One case's counts, per fragment (see the module doc).
fn print_costs(name: &str, r: &CostReport) {
    let m = |n: &str| r.mean_of(n).unwrap_or(f64::NAN);
    eprintln!(
        "costs {name}: {} fragments; per fragment: {:.1} lookups, {:.1} loads \
         ({:.1} × 16 B, {:.1} × 8 B, {:.1} × 4 B, {:.1} gathers), {:.2} samples, {:.1} steps, \
         {:.3} volume, {:.3} fill entries, {:.2} fill lookups, {:.3} neighbour; \
         {:.1} screen-fill kernel loads; {:.1} loads per diffuse fragment ({} of them); 32-pixel groups: largest loads \
         {:.1} ({:.2}× the mean), largest work {:.1} ({:.2}× the mean {:.1})",
        r.fragments,
        m("lookups"),
        r.loads,
        m("loads_16"),
        m("loads_8"),
        m("loads_4"),
        m("gathers"),
        m("samples"),
        m("steps"),
        m("volume"),
        m("fill"),
        m("fill_lookups"),
        m("neighbour"),
        r.kernel_loads,
        r.diffuse_loads,
        r.diffuse_fragments,
        r.group_max_loads,
        r.group_max_loads / r.loads.max(1e-9),
        r.group_max_work,
        r.group_max_work / r.work.max(1e-9),
        r.work,
    );
}

criterion_group!(benches, decode, first_frame, frame, costs);
criterion_main!(benches);
