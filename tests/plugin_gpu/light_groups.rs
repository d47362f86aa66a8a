//! Light groups on the GPU (`bevy_plenoptic::reconstruct::relight`): a tiny grouped bake of
//! the tour's room B (groups `lamp`, `sun` and `sky`, as `tour_groups.toml` declares them),
//! shown by the plugin with each group at a non-trivial colour × intensity set on the camera
//! (`PlenopticCamera::lights`), equals `plenoptic_recon`'s CPU frame relit at the same weights
//! (`Reconstructor::set_light_weights`) as closely as the frame as baked equals the CPU's, in
//! each mode; and the CPU backend shows the camera's weights too.
//!
//! Measured on lavapipe (mean relative difference, share within 5 %), relit against as
//! baked: geometry-assisted 0.0142 / 97.9 % against 0.0123 / 97.9 % (the same few edge
//! pixels apart); image mode 0.0004 / 100 % against 0.0001 / 100 %; volume mode 0.0013 /
//! 99.8 % against 0.0010 / 99.8 %. The weights change the CPU frame by 0.28–0.32.

use crate::common::*;
use crate::harness::{compare, compare_on, cpu_as_gpu};
use crate::sky::settle;
use bevy::camera::Hdr;
use bevy::prelude::*;
use bevy_plenoptic::prelude::*;

fn assets() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/architectural_tour/assets")
}

/// A tiny bake of room B with the groups of `tour_groups.toml` (its sun, sky and groups): a
/// 4 × 4 m rectangle by the lamp, 16-px cubes, 2 samples per texel, the first two seconds.
/// Written to `dir/groups.pack`, with the glb beside it.
fn bake_room_b(dir: &std::path::Path) {
    let recipe = std::fs::read_to_string(assets().join("tour_groups.toml")).unwrap();
    let lighting = &recipe[recipe
        .find("\n[sun]")
        .expect("tour_groups.toml has a sun study")..];
    std::fs::copy(assets().join("tour.glb"), dir.join("tour.glb")).unwrap();
    let recipe = format!(
        "output = \"groups.pack\"\n\n[[scene]]\nfile = \"tour.glb\"\n\n[view_space]\nkind = \
         \"rectangle\"\nmin = [5.5, -2.0]\nmax = [9.5, 2.0]\ny = 1.6\n\n[time]\nstart = 0.0\n\
         end = 2.0\nframe_rate = 24.0\n\n[quality]\npreset = \"draft\"\nid_image_size = 16\n\
         range_image_size = 16\nsamples_per_pixel = 2\nambient_samples = 32\n\
         temporal_volume_samples = 2000\nmax_space_depth = 0\nmax_time_depth = 0\n{lighting}"
    );
    let path = dir.join("groups.toml");
    std::fs::write(&path, recipe).unwrap();
    plenoptic_bake::bake_recipe(&path, &plenoptic_bake::BakeOptions::default()).unwrap();
}

/// Where the camera stands and looks in room B (the lamp's corner, the floor, a window).
const EYE: (Vec3, Vec3) = (Vec3::new(6.5, 1.6, -1.0), Vec3::new(9.5, 0.9, 3.0));
/// The shown time.
const TIME: f32 = 0.5;

/// The weights compared: the lamp dimmed and warmer, the sun brighter, the sky at half.
fn weights() -> LightSettings {
    let mut lights = LightSettings::default();
    lights
        .set("lamp", Vec3::new(0.6, 0.4, 0.3))
        .set("sun", Vec3::splat(1.6))
        .set("sky", Vec3::new(0.5, 0.5, 0.7));
    lights
}

/// The plugin's frame of the camera at `lights` on `backend` in `mode`.
fn plugin_frame(
    dir: &std::path::Path,
    backend: Backend,
    lights: &LightSettings,
    mode: ReconMode,
) -> Vec<Vec3> {
    let mut app = headless_app_in(dir);
    app.world_mut().resource_mut::<PlenopticSettings>().backend = backend;
    let pack = app
        .world()
        .resource::<AssetServer>()
        .load::<RadiancePack>("groups.pack");
    let image = hdr_target(&mut app);
    let transform = Transform::from_translation(EYE.0).looking_at(EYE.1, Vec3::Y);
    let camera = app
        .world_mut()
        .spawn((
            camera_into(image.clone(), transform),
            Hdr,
            Msaa::Off,
            PlenopticCamera {
                playback: Playback::Manual,
                time: TIME,
                mode,
                lights: lights.clone(),
                // The CPU backend reflects as the GPU does (see `cpu_as_gpu`).
                settings: ReconSettings {
                    shaded_reflections: false,
                    ..default()
                },
                ..PlenopticCamera::new(pack)
            },
        ))
        .id();
    settle(&mut app, camera, &image)
}

/// `plenoptic_recon`'s frame of the camera at `lights` in `mode`, reconstructed as the GPU
/// does.
fn cpu_frame(dir: &std::path::Path, lights: &LightSettings, mode: ReconMode) -> Vec<Vec3> {
    let mut rec = cpu_as_gpu(&dir.join("groups.pack"));
    rec.set_light_weights(lights.weights(rec.pack().manifest()).unwrap());
    let transform = Transform::from_translation(EYE.0).looking_at(EYE.1, Vec3::Y);
    let cam = plenoptic_recon::Camera::new(
        EYE.0,
        transform.rotation,
        std::f32::consts::FRAC_PI_4,
        WIDTH,
        HEIGHT,
    )
    .unwrap();
    rec.render(&cam, TIME, mode.into()).unwrap().0.radiance
}

#[test]
fn the_gpu_relights_the_pack_at_the_cameras_group_weights_as_the_cpu_does() {
    let dir = tempfile::tempdir().unwrap();
    bake_room_b(dir.path());
    let baked = LightSettings::default();
    let relit = weights();
    let geometry = ReconMode::GeometryAssisted;
    for mode in [geometry, ReconMode::Image, ReconMode::Volume] {
        let cpu_baked = cpu_frame(dir.path(), &baked, mode);
        let cpu_relit = cpu_frame(dir.path(), &relit, mode);
        // The weights change the frame: a GPU that ignored them could not match.
        let change = compare_on(&cpu_relit, &cpu_baked).0;
        eprintln!("{mode:?}: CPU relit against CPU as baked: mean relative difference {change:.4}");
        assert!(change > 0.1, "{mode:?}: {change}");

        let gpu_baked = plugin_frame(dir.path(), Backend::Gpu, &baked, mode);
        let gpu_relit = plugin_frame(dir.path(), Backend::Gpu, &relit, mode);
        let (m0, f5_0, f20_0) = compare(&gpu_baked, &cpu_baked);
        let (m1, f5_1, f20_1) = compare(&gpu_relit, &cpu_relit);
        eprintln!(
            "{mode:?}: GPU vs CPU as baked: mean {m0:.5}, {f5_0:.4} within 5 %, {f20_0:.4} \
             within 20 %; relit: mean {m1:.5}, {f5_1:.4} within 5 %, {f20_1:.4} within 20 %"
        );
        // As baked, the frame differs from the CPU's only along a few edges of the 16-px
        // bake (geometry-assisted: 0.0123, 97.9 % within 5 %); relit, it differs as little.
        assert!(
            m0 < 0.02 && f5_0 > 0.97 && f20_0 > 0.98,
            "{mode:?} as baked: {m0} {f5_0} {f20_0}"
        );
        assert!(
            m1 < 1.25 * m0 + 1e-3 && f5_1 > f5_0 - 0.005 && f20_1 > f20_0 - 0.005,
            "{mode:?} relit: {m1} {f5_1} {f20_1}"
        );
    }

    // The CPU backend shows the camera's weights.
    let cpu_backend = plugin_frame(dir.path(), Backend::Cpu, &relit, geometry);
    let (m, f5, _) = compare(&cpu_backend, &cpu_frame(dir.path(), &relit, geometry));
    eprintln!("CPU backend relit vs plenoptic_recon relit: mean {m:.5}, {f5:.4} within 5 %");
    assert!(m < 0.01 && f5 > 0.98, "{m} {f5}");
}
