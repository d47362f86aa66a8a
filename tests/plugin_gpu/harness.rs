//! The GPU-against-CPU harness of the plugin's GPU tests: a test pack rendered by the
//! plugin into an `Rgba16Float` target and by `plenoptic_recon` for the same camera and time,
//! and the comparison of the two frames.

use crate::common::*;
use crate::pack::{Materials, PackSpec, open_room, open_room_with_ball, room, write_pack};
use bevy::prelude::*;
use bevy_plenoptic::prelude::*;
use bevy_plenoptic::reconstruct::upload::KeyUploadStats;
use bevy_plenoptic::streaming::{StreamState, StreamingStats, key_bytes};

/// plenoptic_recon's reconstructor on the pack at `path`, set to reconstruct as the plugin's
/// GPU path does: the surface a mirror's ray meets shows the base views' radiance there
/// (`ReconSettings::shaded_reflections` off; the GPU does not shade it as a pixel yet).
pub(crate) fn cpu_as_gpu(path: &std::path::Path) -> plenoptic_recon::Reconstructor {
    let mut rec = plenoptic_recon::Reconstructor::open(path).unwrap();
    rec.settings.shaded_reflections = false;
    rec
}

/// What [`plugin_and_cpu_frames`] returns.
pub(crate) struct Frames {
    /// The plugin's frame, linear radiance.
    pub(crate) gpu: Vec<Vec3>,
    /// plenoptic_recon's CPU frame.
    pub(crate) cpu: Vec<Vec3>,
    /// The pack object id at each pixel of the CPU frame (0: none).
    pub(crate) cpu_object: Vec<u32>,
    /// plenoptic_recon's CPU frame in geometry-assisted mode (whatever the compared mode).
    pub(crate) cpu_geometry: Vec<Vec3>,
    /// plenoptic_recon's CPU frame in image mode (whatever the compared mode).
    pub(crate) cpu_image: Vec<Vec3>,
    /// plenoptic_recon's CPU frame in the compared mode with the baked specular
    /// (`Specular::Baked`).
    pub(crate) cpu_baked: Vec<Vec3>,
    /// The CPU frame's fallbacks.
    pub(crate) fallback: plenoptic_recon::FallbackReport,
    /// Streaming counters at the end.
    pub(crate) stats: StreamingStats,
    /// Key uploads at the end.
    pub(crate) uploads: KeyUploadStats,
    /// Chunks the CPU backend's reconstructor read from the pack itself (0 on the GPU).
    pub(crate) cpu_backend_reads: u64,
    /// Bytes the streaming cache held resident at the end.
    pub(crate) resident_bytes: u64,
}

/// Renders the 3-view room (with `volume_samples` temporal-volume samples per view and
/// bucket, 0 for none) at t = 0.7 with `backend` into an Rgba16Float target (no MSAA: the CPU
/// frame samples pixel centres), and plenoptic_recon's CPU frame of the same pack, camera and
/// time. With `budget_keys`, the memory budget holds that many keys and the camera first
/// shows t = 1.7 then t = 0.3, each until its keys are resident, so that keys are evicted and
/// their slots of the key texture reused before the compared frame.
pub(crate) fn plugin_and_cpu_frames(
    backend: Backend,
    volume_samples: usize,
    budget_keys: Option<u64>,
) -> Frames {
    let view = (Vec3::new(0.3, 1.3, 1.0), Vec3::new(0.0, 0.8, -2.5));
    plugin_and_cpu_frames_from(
        backend,
        volume_samples,
        budget_keys,
        view,
        ReconMode::GeometryAssisted,
    )
}

/// [`plugin_and_cpu_frames`] from the eye `view.0` looking at `view.1`, in `mode`.
pub(crate) fn plugin_and_cpu_frames_from(
    backend: Backend,
    volume_samples: usize,
    budget_keys: Option<u64>,
    view: (Vec3, Vec3),
    mode: ReconMode,
) -> Frames {
    plugin_and_cpu_frames_with(
        backend,
        volume_samples,
        budget_keys,
        view,
        mode,
        Materials::None,
    )
}

/// What a test pack has beyond its views and keys.
pub(crate) struct PackExtras {
    pub(crate) materials: Materials,
    /// Whether the pack leaves the sun to the runtime (pack 3's `direct_sun`).
    pub(crate) direct_sun: bool,
    /// The room with a skylight instead of the closed one.
    pub(crate) open: bool,
    /// With `open`, the room with a smooth-shaded ball on its floor.
    pub(crate) ball: bool,
    /// Whether the pack leaves its lamp's diffuse light to the runtime (pack 5).
    pub(crate) runtime_lamps: bool,
}

impl From<Materials> for PackExtras {
    fn from(materials: Materials) -> Self {
        Self {
            materials,
            direct_sun: false,
            open: false,
            ball: false,
            runtime_lamps: false,
        }
    }
}

/// [`plugin_and_cpu_frames_from`] of a pack whose objects have `materials`.
pub(crate) fn plugin_and_cpu_frames_with(
    backend: Backend,
    volume_samples: usize,
    budget_keys: Option<u64>,
    view: (Vec3, Vec3),
    mode: ReconMode,
    extras: impl Into<PackExtras>,
) -> Frames {
    let PackExtras {
        materials,
        direct_sun,
        open,
        ball,
        runtime_lamps,
    } = extras.into();
    use bevy::camera::Hdr;

    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("room.pack");
    let scene = match (open, ball) {
        (true, true) => open_room_with_ball(),
        (true, false) => open_room(),
        (false, _) => room(true),
    };
    write_pack(
        &scene,
        &PackSpec {
            volume_samples,
            materials,
            direct_sun,
            runtime_lamps,
            ..PackSpec::segment(3, vec![0.0, 1.0, 2.0], 8)
        },
        &path,
    );
    let (eye, t) = (view.0, 0.7);
    let transform = Transform::from_translation(eye).looking_at(view.1, Vec3::Y);

    // CPU reference.
    let mut rec = cpu_as_gpu(&path);
    // The plugin's CPU backend reconstructs with the camera's settings, as plenoptic_recon does.
    rec.settings.shaded_reflections = backend == Backend::Cpu;
    let cam = plenoptic_recon::Camera::new(
        eye,
        transform.rotation,
        std::f32::consts::FRAC_PI_4,
        WIDTH,
        HEIGHT,
    )
    .unwrap();
    let (cpu, report) = rec.render(&cam, t, mode.into()).unwrap();
    let (cpu_geometry, _) = rec
        .render(&cam, t, plenoptic_recon::Mode::GeometryAssisted)
        .unwrap();
    let (cpu_image, _) = rec.render(&cam, t, plenoptic_recon::Mode::Image).unwrap();
    eprintln!(
        "CPU frame: {:?}, reflections {:?}",
        report.fallback, report.reflections
    );
    rec.settings.specular = plenoptic_recon::Specular::Baked;
    let (cpu_baked, _) = rec.render(&cam, t, mode.into()).unwrap();

    // GPU.
    let mut app = headless_app_in(dir.path());
    {
        let mut settings = app.world_mut().resource_mut::<PlenopticSettings>();
        settings.backend = backend;
        if let Some(n) = budget_keys {
            let reader = plenoptic_pack::PackReader::open(&path).unwrap();
            settings.memory_budget_bytes = n * key_bytes(&reader, (0, 0));
        }
    }
    let handle: Handle<RadiancePack> = app.world().resource::<AssetServer>().load("room.pack");
    let image = hdr_target(&mut app);
    let detour: &[f32] = if budget_keys.is_some() {
        &[1.7, 0.3, t]
    } else {
        &[t]
    };
    app.world_mut().spawn((
        camera_into(image.clone(), transform),
        Hdr,
        Msaa::Off,
        PlenopticCamera {
            playback: Playback::Manual,
            time: detour[0],
            mode,
            ..PlenopticCamera::new(handle)
        },
    ));
    let decode = crate::common::rgba16f_pixels;
    let cam_entity = {
        let mut q = app
            .world_mut()
            .query_filtered::<Entity, With<PlenopticCamera>>();
        q.single(app.world()).unwrap()
    };
    for &time in detour {
        app.world_mut()
            .get_mut::<PlenopticCamera>(cam_entity)
            .unwrap()
            .time = time;
        // A few frames at each time so that its keys are uploaded and drawn.
        let mut complete_frames = 0;
        for _ in 0..500 {
            app.update();
            if app.world().get::<StreamState>(cam_entity).unwrap().complete {
                complete_frames += 1;
                if complete_frames == 3 {
                    break;
                }
            }
            std::thread::sleep(std::time::Duration::from_millis(5));
        }
        assert!(
            app.world().get::<StreamState>(cam_entity).unwrap().complete,
            "t = {time}"
        );
    }
    let data = settled_frame(&mut app, &image);
    Frames {
        gpu: decode(&data),
        cpu_object: cpu.object,
        cpu: cpu.radiance,
        cpu_geometry: cpu_geometry.radiance,
        cpu_image: cpu_image.radiance,
        cpu_baked: cpu_baked.radiance,
        fallback: report.fallback,
        stats: app.world().resource::<StreamingStats>().clone(),
        uploads: *app.world().resource::<KeyUploadStats>(),
        cpu_backend_reads: app
            .world()
            .resource::<bevy_plenoptic::cpu::CpuFrames>()
            .chunks_read(cam_entity),
        resident_bytes: app
            .world()
            .resource::<bevy_plenoptic::streaming::StreamCache>()
            .committed_bytes(),
    }
}

/// Compares the GPU frame with the CPU frame: (mean relative error, fraction of pixels within
/// 5 %, within 20 %), with the error per pixel the largest channel's |gpu − cpu| / (cpu + 0.02).
/// Prints an error map ('.' < 5 %, 'o' < 20 %, '#' worse).
pub(crate) fn compare(gpu: &[Vec3], cpu: &[Vec3]) -> (f32, f32, f32) {
    let err =
        |j: usize| ((gpu[j] - cpu[j]).abs() / (cpu[j].abs() + Vec3::splat(0.02))).max_element();
    let n = cpu.len();
    assert_eq!(gpu.len(), n);
    for y in 0..HEIGHT as usize {
        let row: String = (0..WIDTH as usize)
            .map(|x| match err(y * WIDTH as usize + x) {
                e if e < 0.05 => '.',
                e if e < 0.2 => 'o',
                _ => '#',
            })
            .collect();
        eprintln!("{row}");
    }
    let (mean, f5, f20) = compare_on(gpu, cpu);
    eprintln!(
        "GPU vs CPU: mean relative error {mean:.5}, {:.2}% within 5%, {:.2}% within 20%",
        100.0 * f5,
        100.0 * f20
    );
    (mean, f5, f20)
}

/// [`compare`]'s figures for any set of pixels (no map): `gpu[i]` against `cpu[i]`.
pub(crate) fn compare_on(gpu: &[Vec3], cpu: &[Vec3]) -> (f32, f32, f32) {
    assert_eq!(gpu.len(), cpu.len());
    let n = cpu.len().max(1);
    let err: Vec<f32> = gpu
        .iter()
        .zip(cpu)
        .map(|(g, c)| ((*g - *c).abs() / (c.abs() + Vec3::splat(0.02))).max_element())
        .collect();
    let mean = err.iter().sum::<f32>() / n as f32;
    let frac = |limit: f32| err.iter().filter(|&&e| e < limit).count() as f32 / n as f32;
    (mean, frac(0.05), frac(0.2))
}
