//! The environment behind the proxies: a camera in a room without a ceiling looks up through
//! the opening; pixels that see no proxy show the pack's sky for their own direction at the
//! camera's time (sun from the pack's track), in every mode, and pixels of the room do not.

mod common;

use common::{PackSpec, open_room, write_pack_with};
use plenoptic_pack::plenoptic_sky::{Environment, SkyParams, SunTrack};
use plenoptic_recon::{Camera, Mode, Reconstructor};
use plenoptic_trace::glam::Vec3;

fn track() -> SunTrack {
    common::moving_sun()
}

#[test]
fn pixels_without_geometry_show_the_sky_at_the_cameras_time_in_every_mode() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("sky.pack");
    let params = SkyParams::default();
    let sky = Environment::Sky(params);
    let mut spec = PackSpec::segment(2, vec![0.0, 2.0], 32);
    spec.volume_samples = 2000;
    spec.bucket = 1.0;
    write_pack_with(
        &open_room(),
        &spec,
        &path,
        Some((sky.clone(), Some(track()))),
    );
    let recon = Reconstructor::open(&path).unwrap();
    let camera = Camera::look_at(
        Vec3::new(0.0, 1.3, 1.0),
        Vec3::new(0.3, 2.2, -1.5),
        Vec3::NEG_Z,
        1.2,
        64,
        48,
    )
    .unwrap();
    let mask = recon.proxy().unwrap().mask_raster(&camera, 0.0);
    let sky_pixels: Vec<usize> = (0..mask.object.len())
        .filter(|&j| mask.object[j] == 0)
        .collect();
    let fraction = sky_pixels.len() as f32 / mask.object.len() as f32;
    eprintln!("sky: {:.1} % of the frame", 100.0 * fraction);
    assert!((0.2..0.8).contains(&fraction), "sky fraction {fraction}");
    let basis = camera.basis();
    let direction = |j: usize| basis.direction((j % 64) as f32 + 0.5, (j / 64) as f32 + 0.5);
    for t in [0.0, 1.3, 2.0] {
        // The sky of the sun at t, built here from the track, not taken from the reconstructor.
        let (sun, _) = track().at(t);
        let expected = sky.at(Some(sun));
        let other = sky.at(Some(track().at(2.0 - t).0));
        for mode in [Mode::GeometryAssisted, Mode::Image, Mode::Volume] {
            let (frame, report) = recon.render(&camera, t, mode).unwrap();
            assert!(report.missing.is_empty(), "{:?}", report.missing);
            let mut differs_from_other_time = 0;
            for &j in &sky_pixels {
                let e = expected.radiance(direction(j));
                let got = frame.radiance[j];
                assert!(e.min_element() > 1.0, "the sky is bright: {e}");
                assert!(
                    (got - e).abs().max_element() <= 1e-3 * e.max_element(),
                    "{mode:?} t={t} pixel {j}: {got} vs {e}"
                );
                assert!(frame.depth[j].is_infinite() && frame.object[j] == 0);
                let o = other.radiance(direction(j));
                if (o - e).abs().max_element() > 0.05 * e.max_element() {
                    differs_from_other_time += 1;
                }
            }
            if t != 1.0 {
                assert!(
                    differs_from_other_time * 2 > sky_pixels.len(),
                    "the sky follows the sun: {differs_from_other_time} of {}",
                    sky_pixels.len()
                );
            }
            // The room's pixels keep the baked radiance (the test shading is below 10; the
            // sky is in the thousands).
            let room: Vec<usize> = (0..mask.object.len())
                .filter(|&j| mask.object[j] != 0)
                .collect();
            let not_sky = room
                .iter()
                .filter(|&&j| frame.radiance[j].max_element() < 10.0)
                .count();
            assert!(
                not_sky as f32 >= 0.97 * room.len() as f32,
                "{mode:?}: {not_sky} of {} room pixels are not sky",
                room.len()
            );
        }
    }
}

#[test]
fn a_uniform_environment_fills_the_opening_and_a_pack_without_one_keeps_the_cube() {
    let dir = tempfile::tempdir().unwrap();
    let spec = PackSpec::segment(1, vec![0.0], 16);
    let camera = Camera::look_at(
        Vec3::new(0.0, 1.3, 1.0),
        Vec3::new(0.0, 3.0, 0.0),
        Vec3::NEG_Z,
        1.0,
        32,
        24,
    )
    .unwrap();
    let colour = Vec3::new(3.0, 5.0, 7.0);
    let path = dir.path().join("uniform.pack");
    write_pack_with(
        &open_room(),
        &spec,
        &path,
        Some((Environment::Uniform(colour), None)),
    );
    let (frame, _) = Reconstructor::open(&path)
        .unwrap()
        .render(&camera, 0.0, Mode::GeometryAssisted)
        .unwrap();
    let sky = frame.object.iter().filter(|&&o| o == 0).count();
    assert!(sky > frame.object.len() / 5, "{sky}");
    for (j, &o) in frame.object.iter().enumerate() {
        if o == 0 {
            assert!((frame.radiance[j] - colour).abs().max_element() < 1e-6);
        }
    }
    let path = dir.path().join("none.pack");
    write_pack_with(&open_room(), &spec, &path, None);
    let (frame, _) = Reconstructor::open(&path)
        .unwrap()
        .render(&camera, 0.0, Mode::GeometryAssisted)
        .unwrap();
    // Without an environment the opening shows the cube's (empty) texels, as before.
    for (j, &o) in frame.object.iter().enumerate() {
        if o == 0 {
            assert!(
                frame.radiance[j].max_element() < 1e-6,
                "{}",
                frame.radiance[j]
            );
        }
    }
}

/// A pack that declares its environment as none (rays that leave the scene see nothing, as the
/// tracer rendered them: a scene with a sun but no sky) shows black where no proxy is; one
/// that declares nothing keeps the modes' fallback (the heaviest key's texels).
#[test]
fn an_environment_declared_none_is_black_and_an_undeclared_one_falls_back() {
    let dir = tempfile::tempdir().unwrap();
    let spec = PackSpec::segment(1, vec![0.0], 16);
    let declared = dir.path().join("declared.pack");
    write_pack_with(
        &open_room(),
        &spec,
        &declared,
        Some((Environment::None, Some(track()))),
    );
    let rec = Reconstructor::open(&declared).unwrap();
    assert!(!rec.environment().is_none());
    assert_eq!(rec.environment().at(0.0).radiance(Vec3::Y), Vec3::ZERO);
    let undeclared = dir.path().join("undeclared.pack");
    write_pack_with(&open_room(), &spec, &undeclared, None);
    assert!(
        Reconstructor::open(&undeclared)
            .unwrap()
            .environment()
            .is_none()
    );
}
