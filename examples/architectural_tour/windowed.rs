//! The windowed tour: a Bevy app with [`PlenopticPlugin`] showing the pack in a window.
//!
//! The camera flies the tour's path while the animation plays (the path sets both the pose
//! and the scene time); `Tab` hands the camera to Bevy's free-fly controller (WASD, Q/E,
//! mouse with the right button held or `M` to capture, scroll for speed) with the animation
//! playing on the clock, and back. `Space` pauses, `1`/`2`/`3` switch the reconstruction
//! mode (geometry-assisted, image, volume), `Esc` quits. On a pack baked with light groups
//! (`--recipe examples/architectural_tour/assets/tour_groups.toml`), `L` switches room B's
//! lamp off and on and `D` steps the daylight (the `sun` and `sky` groups) through 1, 0.2
//! and 0: the camera's [`LightSettings`], applied by the plugin every frame. The window
//! title shows the frame rate, the scene time, the mode, the lights and the plugin's
//! resident streaming memory; the peak resident memory is printed when the window closes.
//!
//! `--screenshot FILE` (with `--screenshot-at SECONDS` along the path) holds the tour at that
//! moment, waits until the plugin has streamed what the frame needs and the pipelines are
//! compiled, saves the window to FILE and quits: how the README's window picture was taken.
//!
//! Exposure: the reconstruction writes linear radiance times the camera's physical exposure
//! into the HDR target, as Bevy's lights do. The tour is lit far below daylight (a sun of
//! about 6 lux), so its camera's `Exposure` is [`EV100_UNIT`] (multiplier 1, the radiance as
//! baked); on top of that the example sets the colour-grading exposure from the CPU
//! reconstruction's automatic exposure at the start of the path and tonemaps with ACES, the
//! same curve as the headless frames.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

use bevy::camera::{Exposure, Hdr};
use bevy::camera_controller::free_camera::{FreeCamera, FreeCameraPlugin, FreeCameraState};
use bevy::core_pipeline::tonemapping::Tonemapping;
use bevy::diagnostic::{DiagnosticPath, DiagnosticsStore, FrameTimeDiagnosticsPlugin};
use bevy::prelude::*;
use bevy::render::view::screenshot::{Capturing, Screenshot, save_to_disk};
use bevy::render::view::{ColorGrading, ColorGradingGlobal};
use bevy::window::WindowResolution;
use bevy_plenoptic::camera::EV100_UNIT;
use bevy_plenoptic::prelude::*;
use bevy_plenoptic::streaming::RESIDENT_BYTES;
use plenoptic_recon::CameraPath;

/// What the window shows and how the camera is driven.
#[derive(Resource)]
struct Tour {
    path: CameraPath,
    /// Seconds along the camera path (advances while flying the tour and not paused).
    path_time: f32,
    /// The path drives the camera (else the free-fly controller does).
    flying_tour: bool,
    paused: bool,
    /// Largest resident-bytes diagnostic seen (read after the app has exited).
    peak_resident: Arc<AtomicU64>,
    title_timer: Timer,
    screenshot: Option<ScreenshotPlan>,
    /// Room B's lamp is on (`L`).
    lamp_on: bool,
    /// Index into [`DAYLIGHT`] of the daylight's intensity (`D`).
    daylight: usize,
}

/// The daylight intensities `D` steps through.
const DAYLIGHT: [f32; 3] = [1.0, 0.2, 0.0];

/// A screenshot to take and then quit.
pub struct ScreenshotPlan {
    /// Where the PNG goes.
    pub file: PathBuf,
    /// Seconds along the camera path.
    pub at: f32,
}

/// Frames rendered with everything resident before the screenshot (lavapipe compiles
/// pipelines lazily; the first frames can be blank).
const SETTLE_FRAMES: u32 = 10;

/// Opens the window and runs the tour until it is closed.
pub fn run(
    pack: &Path,
    path: CameraPath,
    exposure: f32,
    backend: Backend,
    mode: ReconMode,
    screenshot: Option<ScreenshotPlan>,
) -> Result<(), Box<dyn std::error::Error>> {
    let dir = pack
        .parent()
        .and_then(|d| d.canonicalize().ok())
        .ok_or_else(|| format!("{}: no parent folder", pack.display()))?;
    let file = pack
        .file_name()
        .ok_or_else(|| format!("{}: not a file name", pack.display()))?
        .to_string_lossy()
        .into_owned();
    let (width, height) = (path.width.max(320), path.height.max(180));

    let peak = Arc::new(AtomicU64::new(0));
    let mut app = App::new();
    app.add_plugins(
        DefaultPlugins
            .set(AssetPlugin {
                file_path: dir.to_string_lossy().into_owned(),
                ..default()
            })
            .set(WindowPlugin {
                primary_window: Some(Window {
                    title: "plenoptic — architectural tour".into(),
                    resolution: WindowResolution::new(width * 2, height * 2),
                    ..default()
                }),
                ..default()
            }),
    )
    .add_plugins((
        PlenopticPlugin,
        FreeCameraPlugin,
        FrameTimeDiagnosticsPlugin::default(),
    ))
    .insert_resource(PlenopticSettings {
        memory_budget_bytes: 512 << 20,
        backend,
        ..default()
    })
    .insert_resource(ClearColor(Color::BLACK))
    .insert_resource(Tour {
        path_time: screenshot.as_ref().map_or(0.0, |s| s.at),
        paused: screenshot.is_some(),
        path,
        flying_tour: true,
        peak_resident: peak.clone(),
        title_timer: Timer::from_seconds(0.5, TimerMode::Repeating),
        screenshot,
        lamp_on: true,
        daylight: 0,
    })
    .add_systems(
        Startup,
        move |mut commands: Commands, assets: Res<AssetServer>, tour: Res<Tour>| {
            let start = tour.path.sample(tour.path_time);
            let mut camera = PlenopticCamera::new(assets.load(file.clone()));
            camera.playback = Playback::Manual;
            camera.mode = mode;
            camera.time = start.scene_time;
            commands.spawn((
                camera,
                Hdr,
                Exposure { ev100: EV100_UNIT },
                Tonemapping::AcesFitted,
                ColorGrading {
                    global: ColorGradingGlobal {
                        exposure: exposure.max(1e-6).log2(),
                        ..default()
                    },
                    ..default()
                },
                Projection::Perspective(PerspectiveProjection {
                    fov: start.camera.vfov,
                    ..default()
                }),
                Transform::from_translation(start.camera.position)
                    .with_rotation(start.camera.orientation),
                FreeCamera {
                    walk_speed: 2.0,
                    run_speed: 6.0,
                    ..default()
                },
            ));
        },
    )
    .add_systems(
        Update,
        (
            keys,
            light_keys,
            fly_tour.before(PlenopticSystems::Playback),
            title,
            take_screenshot,
        ),
    );
    app.run();

    println!(
        "peak resident streaming memory: {:.1} MiB",
        peak.load(Ordering::Relaxed) as f64 / (1024.0 * 1024.0)
    );
    Ok(())
}

/// Tab, Space, 1/2/3, Esc.
fn keys(
    input: Res<ButtonInput<KeyCode>>,
    mut tour: ResMut<Tour>,
    mut cameras: Query<(&mut PlenopticCamera, &mut FreeCameraState, &Transform)>,
    mut exit: MessageWriter<AppExit>,
) {
    if input.just_pressed(KeyCode::Escape) {
        exit.write(AppExit::Success);
    }
    if input.just_pressed(KeyCode::Space) {
        tour.paused = !tour.paused;
    }
    let toggle = input.just_pressed(KeyCode::Tab);
    if toggle {
        tour.flying_tour = !tour.flying_tour;
    }
    let mode = [
        (KeyCode::Digit1, ReconMode::GeometryAssisted),
        (KeyCode::Digit2, ReconMode::Image),
        (KeyCode::Digit3, ReconMode::Volume),
    ]
    .into_iter()
    .find(|(k, _)| input.just_pressed(*k))
    .map(|(_, m)| m);
    for (mut camera, mut free, transform) in &mut cameras {
        if let Some(m) = mode {
            camera.mode = m;
        }
        if toggle && !tour.flying_tour {
            // Hand over where the tour left the camera.
            let (yaw, pitch, _) = transform.rotation.to_euler(EulerRot::YXZ);
            free.yaw = yaw;
            free.pitch = pitch;
            free.velocity = Vec3::ZERO;
        }
        free.enabled = !tour.flying_tour;
        let speed = if tour.paused { 0.0 } else { 1.0 };
        camera.playback = if tour.flying_tour {
            Playback::Manual
        } else {
            Playback::Clock {
                speed,
                looping: true,
            }
        };
    }
}

/// `L` and `D`: the lamp and the daylight, set on the camera for the groups its pack has.
fn light_keys(
    input: Res<ButtonInput<KeyCode>>,
    mut tour: ResMut<Tour>,
    packs: Res<Assets<RadiancePack>>,
    mut cameras: Query<&mut PlenopticCamera>,
) {
    if input.just_pressed(KeyCode::KeyL) {
        tour.lamp_on = !tour.lamp_on;
    }
    if input.just_pressed(KeyCode::KeyD) {
        tour.daylight = (tour.daylight + 1) % DAYLIGHT.len();
    }
    let lamp = if tour.lamp_on { 1.0 } else { 0.0 };
    let wanted = [
        ("lamp", lamp),
        ("sun", DAYLIGHT[tour.daylight]),
        ("sky", DAYLIGHT[tour.daylight]),
    ];
    for mut camera in &mut cameras {
        let Some(pack) = packs.get(camera.pack.id()) else {
            continue;
        };
        let groups = pack.reader.manifest().light_groups.as_ref();
        let names = groups.map(|g| &g.names[..]).unwrap_or_default();
        for (name, w) in wanted {
            let w = Vec3::splat(w);
            if names.iter().any(|n| n == name) && camera.lights.get(name) != w {
                camera.lights.set(name, w);
            }
        }
    }
}

/// While flying the tour, the path sets the camera's pose, field of view and scene time.
fn fly_tour(
    time: Res<Time>,
    mut tour: ResMut<Tour>,
    mut cameras: Query<(&mut PlenopticCamera, &mut Transform, &mut Projection)>,
) {
    if !tour.flying_tour {
        return;
    }
    let (start, end) = tour.path.time_range();
    if !tour.paused {
        tour.path_time += time.delta_secs();
        if tour.path_time > end {
            tour.path_time = start;
        }
    }
    let s = tour.path.sample(tour.path_time);
    for (mut camera, mut transform, mut projection) in &mut cameras {
        camera.time = s.scene_time;
        *transform =
            Transform::from_translation(s.camera.position).with_rotation(s.camera.orientation);
        if let Projection::Perspective(p) = projection.as_mut() {
            p.fov = s.camera.vfov;
        }
    }
}

/// The window title: frame rate, scene time, mode, resident memory.
fn title(
    time: Res<Time>,
    mut tour: ResMut<Tour>,
    diagnostics: Res<DiagnosticsStore>,
    cameras: Query<&PlenopticCamera>,
    mut windows: Query<&mut Window>,
) {
    let resident = diagnostics
        .get(&RESIDENT_BYTES)
        .and_then(|d| d.value())
        .unwrap_or(0.0);
    tour.peak_resident
        .fetch_max(resident as u64, Ordering::Relaxed);
    if !tour.title_timer.tick(time.delta()).just_finished() {
        return;
    }
    let fps = diagnostics
        .get(&FrameTimeDiagnosticsPlugin::FPS)
        .and_then(|d| d.smoothed())
        .unwrap_or(0.0);
    let Some(camera) = cameras.iter().next() else {
        return;
    };
    let mode = match camera.mode {
        ReconMode::GeometryAssisted => "geometry-assisted",
        ReconMode::Image => "image",
        ReconMode::Volume => "volume",
    };
    let lights = if camera.lights.is_identity() {
        String::new()
    } else {
        format!(
            ", lamp {}, daylight {}",
            if tour.lamp_on { "on" } else { "off" },
            DAYLIGHT[tour.daylight]
        )
    };
    let driver = if tour.flying_tour {
        "tour (Tab: free-fly)"
    } else {
        "free-fly WASD/QE, right mouse (Tab: tour)"
    };
    for mut window in &mut windows {
        let previous = window.title.clone();
        window.title = format!(
            "plenoptic tour — {fps:.0} fps, t = {:.1} s, {mode}{lights}, resident {:.0} MiB — {driver}{}",
            camera.time,
            resident / (1024.0 * 1024.0),
            if tour.paused { " — paused" } else { "" }
        );
        if tour.screenshot.is_some() && window.title != previous {
            // Unattended: the title is the only progress there is.
            println!("{}", window.title);
        }
    }
}

/// With a [`ScreenshotPlan`]: once nothing the frame needs is missing, waits
/// [`SETTLE_FRAMES`] frames, captures the window, and quits when the file is written.
fn take_screenshot(
    mut commands: Commands,
    tour: Res<Tour>,
    diagnostics: Res<DiagnosticsStore>,
    capturing: Query<(), With<Capturing>>,
    mut settled: Local<u32>,
    mut requested: Local<bool>,
    mut exit: MessageWriter<AppExit>,
) {
    let Some(plan) = &tour.screenshot else {
        return;
    };
    if *requested {
        if capturing.is_empty() {
            println!("window saved to {}", plan.file.display());
            exit.write(AppExit::Success);
        }
        return;
    }
    let value =
        |p: DiagnosticPath| -> f64 { diagnostics.get(&p).and_then(|d| d.value()).unwrap_or(0.0) };
    let resident = value(RESIDENT_BYTES);
    let stalls = value(bevy_plenoptic::streaming::STALLS);
    *settled = if resident > 0.0 && stalls == 0.0 {
        *settled + 1
    } else {
        0
    };
    if *settled >= SETTLE_FRAMES {
        commands
            .spawn(Screenshot::primary_window())
            .observe(save_to_disk(plan.file.clone()));
        *requested = true;
    }
}
