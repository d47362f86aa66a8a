//! Unit tests of [`crate::geometry`] that need a pack (written by the integration tests'
//! writer, `tests/common`).

#[path = "../tests/common/mod.rs"]
mod common;

use common::{Materials, PackSpec, open_room, room, write_pack};
use glam::Vec3;

use crate::frame::Report;
use crate::geometry::{self, Layer, Pass, Shot};
use crate::settings::CubeFilter;
use crate::shading::Channel;
use crate::{Camera, Reconstructor};

/// A small pack of `scene` with textured materials (two views, three keys, 32-px cubes),
/// opened; the directory holds it.
fn textured_pack(scene: &plenoptic_scene::Scene) -> (tempfile::TempDir, Reconstructor) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("textured.pack");
    let spec = PackSpec {
        materials: Materials::Textured,
        ..PackSpec::segment(2, vec![0.0, 1.0, 2.0], 32)
    };
    write_pack(scene, &spec, &path);
    let rec = Reconstructor::open(&path).unwrap();
    (dir, rec)
}

/// A `w` × `h` camera in the test room, looking across it at its boxes.
fn room_camera(w: u32, h: u32) -> Camera {
    Camera::look_at(
        Vec3::new(0.3, 1.2, 0.8),
        Vec3::new(-0.2, 0.7, -2.0),
        Vec3::Y,
        1.2,
        w,
        h,
    )
    .unwrap()
}

/// One pass that looks up two channels gives each what a pass of its own gives: the same
/// lookups, weights and fallbacks, nearest and bilinear.
#[test]
fn a_pass_with_a_second_channel_gives_what_two_passes_give() {
    let (_dir, rec) = textured_pack(&room(true));
    let camera = room_camera(96, 64);
    for filter in [CubeFilter::Nearest, CubeFilter::Bilinear] {
        let pass = |channel, second| Pass {
            layer: Layer::All,
            channel,
            skip: &[],
            filter,
            second,
            environment: None,
            sparse: false,
        };
        let mut report = Report::default();
        let pair = geometry::render_pair(
            Shot::new(&rec, &camera, 0.6, None),
            pass(Channel::Lighting, Some(Channel::NonDiffuse)),
            &mut report,
        )
        .unwrap();
        let (lighting, non_diffuse) = (pair.frame, pair.second);
        let alone = |channel| {
            let mut report = Report::default();
            let shot = Shot::new(&rec, &camera, 0.6, None);
            geometry::render(shot, pass(channel, None), &mut report)
                .unwrap()
                .radiance
        };
        let close = |a: &[Vec3], b: &[Vec3]| {
            a.len() == b.len()
                && a.iter()
                    .zip(b)
                    .all(|(x, y)| (*x - *y).abs().max_element() <= 1e-5 * (1.0 + y.max_element()))
        };
        assert!(close(&lighting.radiance, &alone(Channel::Lighting)));
        let nd = alone(Channel::NonDiffuse);
        assert!(close(&non_diffuse, &nd), "{filter:?}");
        // The non-diffuse radiance is not the lighting: the test compares something.
        assert!(nd.iter().any(|c| c.max_element() > 1e-4));
        assert!(!close(&non_diffuse, &lighting.radiance));
    }
}

/// A pass asked for the environment of another channel shows, where nothing is, what a pass
/// of that channel and filter shows there (the radiance pass that the materials' frame then
/// skips when every object has a material).
#[test]
fn a_pass_shows_the_environment_of_the_channel_asked_for() {
    let (_dir, rec) = textured_pack(&open_room());
    // Looking up through the skylight.
    let camera = Camera::look_at(
        Vec3::new(0.0, 1.2, 0.5),
        Vec3::new(0.2, 4.0, -1.0),
        Vec3::Y,
        1.4,
        64,
        48,
    )
    .unwrap();
    let all: Vec<u32> = rec.proxy().unwrap().object_ids().to_vec();
    for filter in [CubeFilter::Nearest, CubeFilter::Bilinear] {
        let mut report = Report::default();
        let pair = geometry::render_pair(
            Shot::new(&rec, &camera, 0.6, None),
            Pass {
                layer: Layer::All,
                channel: Channel::Lighting,
                skip: &[],
                filter: CubeFilter::Bilinear,
                second: Some(Channel::NonDiffuse),
                environment: Some((Channel::Radiance, filter)),
                sparse: false,
            },
            &mut report,
        )
        .unwrap();
        assert!(pair.environment);
        let radiance = geometry::render(
            Shot::new(&rec, &camera, 0.6, None),
            Pass {
                skip: &all,
                ..Pass::radiance(Layer::All, filter)
            },
            &mut report,
        )
        .unwrap();
        let sky: Vec<usize> = (0..radiance.object.len())
            .filter(|&j| radiance.object[j] == 0)
            .collect();
        assert!(sky.len() > 100, "{} sky pixels", sky.len());
        assert_eq!(pair.frame.object, radiance.object);
        for &j in &sky {
            let (a, b) = (pair.frame.radiance[j], radiance.radiance[j]);
            assert!(
                (a - b).abs().max_element() <= 1e-6 * (1.0 + b.max_element()),
                "{a} {b}"
            );
        }
        assert!(
            sky.iter()
                .any(|&j| radiance.radiance[j].max_element() > 0.0)
        );
    }
}

/// The lighting looked up at a quarter of the pixels and interpolated where the lookups
/// agree (geometry/sparse.rs) is the lighting looked up at every pixel, within 0.3 % on
/// average and 20 % at any pixel, with the same objects and fallbacks; and more than a
/// third of the pixels were interpolated. Measured on the lighting: 0.036 % on average; the
/// largest, 13.6 % and 11.9 %, at two pixels of the contact shadow beside a box, where the
/// baked lighting changes from one texel to the next and bilinear weights across the cube
/// and across the screen differ; 41 % of the pixels interpolated (of the 75 % that are not
/// anchors).
#[test]
fn sparse_lighting_agrees_with_every_pixel() {
    let (_dir, rec) = textured_pack(&room(true));
    let camera = room_camera(160, 120);
    let render = |sparse| {
        let pass = Pass {
            layer: Layer::All,
            channel: Channel::Lighting,
            skip: &[],
            filter: CubeFilter::Bilinear,
            second: Some(Channel::NonDiffuse),
            environment: None,
            sparse,
        };
        let mut report = Report::default();
        let shot = Shot::new(&rec, &camera, 0.6, None);
        let pair = geometry::render_pair(shot, pass, &mut report).unwrap();
        (pair, report.fallback)
    };
    let ((dense, dense_fallback), (sparse, sparse_fallback)) = (render(false), render(true));
    assert_eq!(dense.frame.object, sparse.frame.object);
    for (a, b) in dense.frame.depth.iter().zip(&sparse.frame.depth) {
        assert!(a == b || (a - b).abs() <= 1e-5 * a, "{a} {b}");
    }
    for (a, b) in [
        (&dense.frame.radiance, &sparse.frame.radiance),
        (&dense.second, &sparse.second),
    ] {
        let (mut diff, mut total, mut worst) = (0.0f64, 0.0f64, 0.0f32);
        for (x, y) in a.iter().zip(b.iter()) {
            let d = (*x - *y).abs().max_element();
            diff += d as f64;
            total += x.max_element() as f64;
            worst = worst.max(d / (x.max_element() + 0.02));
        }
        let mean = diff / total;
        eprintln!("mean {mean}, largest {worst}");
        assert!(mean < 0.003, "mean relative difference {mean}");
        assert!(worst < 0.2, "largest relative difference {worst}");
    }
    let n = sparse.frame.object.len();
    eprintln!("{} of {n} interpolated", sparse.interpolated);
    assert!(
        sparse.interpolated > n / 3,
        "{} of {n}",
        sparse.interpolated
    );
    assert_eq!(dense.interpolated, 0);
    let (d, s) = (dense_fallback, sparse_fallback);
    assert!((d.direct - s.direct).abs() < 0.01, "{d:?} {s:?}");
}
