//! Reconstruction against analytic test packs (see `common`).

mod common;

use common::*;
use plenoptic_pack::{ChunkKind, PackReader};
use plenoptic_recon::{Camera, Mode, Reconstructor};
use plenoptic_trace::glam::Vec3;
use plenoptic_trace::metrics::{psnr, relative_lrms};
use plenoptic_trace::{Image, SceneAccel};

fn image(w: u32, h: u32, pixels: Vec<Vec3>) -> Image<Vec3> {
    Image {
        width: w,
        height: h,
        pixels,
    }
}

/// Fraction of pixels whose luminance is within `tol` (relative, floor 0.02) of the expected.
fn fraction_close(a: &[Vec3], b: &[Vec3], tol: f32) -> f32 {
    let lum = |c: Vec3| c.dot(Vec3::new(0.2126, 0.7152, 0.0722));
    let ok = a
        .iter()
        .zip(b)
        .filter(|(x, y)| (lum(**x) - lum(**y)).abs() <= tol * lum(**y).max(0.02))
        .count();
    ok as f32 / a.len() as f32
}

/// Pixels away from object edges and creases in the cube: the cube's id and normal along the
/// pixel's direction equal those three pixels away in each direction (at object edges the
/// cube's nearest texel and the geometry mask legitimately disagree; at a crease the nearest
/// texel may show the object's other face, which the lookups' face test refuses).
fn interior(
    ids: &plenoptic_pack::CubeImage<u32>,
    normals: &plenoptic_pack::CubeImage<Vec3>,
    camera: &Camera,
) -> Vec<bool> {
    let b = camera.basis();
    let (w, h) = (camera.width as i32, camera.height as i32);
    let dir = |x: i32, y: i32| {
        b.direction(
            x.clamp(0, w - 1) as f32 + 0.5,
            y.clamp(0, h - 1) as f32 + 0.5,
        )
    };
    let id = |x: i32, y: i32| {
        (
            *ids.lookup(dir(x, y)).unwrap(),
            *normals.lookup(dir(x, y)).unwrap(),
        )
    };
    (0..w * h)
        .map(|j| {
            let (x, y) = (j % w, j / w);
            let c = id(x, y);
            [
                (-3, 0),
                (3, 0),
                (0, -3),
                (0, 3),
                (-3, -3),
                (3, 3),
                (3, -3),
                (-3, 3),
            ]
            .iter()
            .all(|&(dx, dy)| {
                let (o, n) = id(x + dx, y + dy);
                o == c.0 && n.dot(c.1) > 0.99
            })
        })
        .collect()
}

#[test]
fn at_a_base_view_and_key_every_mode_returns_the_range_image() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("id.pack");
    let scene = room(true);
    let mut spec = PackSpec::segment(3, vec![0.0, 1.0, 2.0], 32);
    spec.volume_samples = 3000;
    write_pack(&scene, &spec, &path);
    let rec = Reconstructor::open(&path).unwrap();
    let pos = spec.views[1];
    let camera = Camera::look_at(pos, Vec3::new(0.3, 0.8, -2.0), Vec3::Y, 1.2, 80, 60).unwrap();
    let pack = PackReader::open(&path).unwrap();
    let cube = pack.radiance(1, 1).unwrap();
    let inside = interior(
        &pack.object_id(1, 1).unwrap(),
        &pack.normal(1, 1).unwrap(),
        &camera,
    );
    let expected = sample_cube(&cube, &camera);
    let exp_img = image(80, 60, expected.clone());
    let pick = |v: &[Vec3]| -> Vec<Vec3> {
        v.iter()
            .zip(&inside)
            .filter(|x| *x.1)
            .map(|x| *x.0)
            .collect()
    };
    let exp_in = pick(&expected);
    let exp_in_img = image(exp_in.len() as u32, 1, exp_in.clone());
    println!(
        "{:.1}% of the pixels are away from object edges",
        100.0 * exp_in.len() as f32 / inside.len() as f32
    );
    // (mode, least fraction of interior pixels within 2 %, largest interior relative LRMS)
    for (mode, min_close, max_lrms) in [
        (Mode::GeometryAssisted, 0.99, 0.06),
        (Mode::Image, 0.85, 0.2),
        (Mode::Volume, 0.05, 0.35),
    ] {
        let (frame, report) = rec.render(&camera, 1.0, mode).unwrap();
        let got_in = pick(&frame.radiance);
        let close = fraction_close(&got_in, &exp_in, 0.02);
        let lrms_in = relative_lrms(&image(got_in.len() as u32, 1, got_in.clone()), &exp_in_img);
        let lrms = relative_lrms(&to_image(&frame), &exp_img);
        if std::env::var("RECON_DEBUG").is_ok() {
            to_image(&frame)
                .save_png(format!("/tmp/id_{mode:?}.png"), 1.0)
                .unwrap();
            exp_img.save_png("/tmp/id_expected.png", 1.0).unwrap();
        }
        println!(
            "identity {mode:?}: interior {:.1}% within 2%, relative LRMS {lrms_in:.4}; whole frame relative LRMS {lrms:.4}, PSNR {:.1} dB; {:?}",
            close * 100.0,
            psnr(&to_image(&frame), &exp_img),
            report.fallback
        );
        assert!(report.missing.is_empty(), "{:?}", report.missing);
        assert!(
            close >= min_close && lrms_in <= max_lrms,
            "{mode:?}: {close} {lrms_in}"
        );
    }
}

#[test]
fn error_falls_as_base_views_get_denser() {
    let dir = tempfile::tempdir().unwrap();
    let scene = room(false);
    let accel = SceneAccel::new(&scene).unwrap();
    let placed = accel.at_time(0.0);
    let cams: Vec<Camera> = [-0.55f32, 0.2, 0.72]
        .iter()
        .map(|&x| {
            Camera::look_at(
                Vec3::new(x, 1.25, 1.3),
                Vec3::new(0.0, 0.7, -2.0),
                Vec3::Y,
                1.1,
                64,
                48,
            )
            .unwrap()
        })
        .collect();
    let refs: Vec<Image<Vec3>> = cams.iter().map(|c| reference(&placed, c)).collect();
    let mut errors = Vec::new();
    for count in [2usize, 4, 8] {
        let path = dir.path().join(format!("q{count}.pack"));
        write_pack(&scene, &PackSpec::segment(count, vec![0.0], 32), &path);
        let rec = Reconstructor::open(&path).unwrap();
        let mut row = Vec::new();
        for mode in [Mode::GeometryAssisted, Mode::Image] {
            let mut sum = 0.0;
            for (c, r) in cams.iter().zip(&refs) {
                let (f, _) = rec.render(c, 0.0, mode).unwrap();
                sum += relative_lrms(&to_image(&f), r);
            }
            row.push(sum / cams.len() as f64);
        }
        println!(
            "{count} base views: relative LRMS geometry-assisted {:.4}, image {:.4}",
            row[0], row[1]
        );
        errors.push(row);
    }
    assert!(
        errors[2][0] < errors[0][0] && errors[1][0] <= errors[0][0] * 1.02,
        "{errors:?}"
    );
    assert!(errors[2][1] < errors[0][1], "{errors:?}");
}

#[test]
fn geometry_assisted_beats_image_mode_on_a_moving_object() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("motion.pack");
    let scene = room(true);
    let spec = PackSpec::segment(3, vec![0.0, 0.5, 1.0, 1.5, 2.0], 32);
    write_pack(&scene, &spec, &path);
    let rec = Reconstructor::open(&path).unwrap();
    let accel = SceneAccel::new(&scene).unwrap();
    let (mut gsum, mut isum) = (0.0, 0.0);
    for (t, x) in [(0.3f32, -0.4f32), (0.8, 0.1), (1.3, 0.5)] {
        let cam = Camera::look_at(
            Vec3::new(x, 1.3, 1.2),
            Vec3::new(0.0, 0.4, -1.0),
            Vec3::Y,
            1.1,
            64,
            48,
        )
        .unwrap();
        let r = reference(&accel.at_time(t), &cam);
        let (g, rep) = rec.render(&cam, t, Mode::GeometryAssisted).unwrap();
        let (i, _) = rec.render(&cam, t, Mode::Image).unwrap();
        let (eg, ei) = (
            relative_lrms(&to_image(&g), &r),
            relative_lrms(&to_image(&i), &r),
        );
        println!(
            "t = {t}: relative LRMS geometry-assisted {eg:.4} (PSNR {:.1} dB), image {ei:.4} (PSNR {:.1} dB); {:?}",
            psnr(&to_image(&g), &r),
            psnr(&to_image(&i), &r),
            rep.fallback
        );
        gsum += eg;
        isum += ei;
    }
    println!(
        "mean relative LRMS: geometry-assisted {:.4}, image {:.4}",
        gsum / 3.0,
        isum / 3.0
    );
    assert!(gsum < isum);
}

#[test]
fn corrupt_or_missing_chunks_degrade_without_panicking() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.pack");
    let scene = room(true);
    let mut spec = PackSpec::segment(2, vec![0.0, 1.0, 2.0], 16);
    spec.volume_samples = 300;
    spec.skip = vec![(1, 0)];
    write_pack(&scene, &spec, &path);
    // Flip bytes inside view 0's radiance cube at key 1, the object-id cube of view 1 at key 2
    // and a volume block.
    let pack = PackReader::open(&path).unwrap();
    let mut bytes = std::fs::read(&path).unwrap();
    for (kind, v, k) in [
        (ChunkKind::RadianceCube, 0, 1),
        (ChunkKind::ObjectIdCube, 1, 2),
        (ChunkKind::VolumeBlock, 0, 4),
    ] {
        let e = pack.entries()[pack.find(kind, v, k).unwrap()];
        let mid = (e.offset + e.length / 2) as usize;
        for b in &mut bytes[mid..mid + 8] {
            *b ^= 0x5a;
        }
    }
    std::fs::write(&path, &bytes).unwrap();
    let rec = Reconstructor::open(&path).unwrap();
    let cam = Camera::look_at(
        Vec3::new(0.0, 1.3, 1.0),
        Vec3::new(0.0, 0.5, -2.0),
        Vec3::Y,
        1.0,
        48,
        32,
    )
    .unwrap();
    for mode in Mode::ALL {
        for t in [0.0f32, 0.9, 1.1, 2.0] {
            let (frame, report) = rec.render(&cam, t, mode).unwrap();
            assert_eq!(frame.radiance.len(), 48 * 32);
            assert!(frame.radiance.iter().any(|c| c.max_element() > 0.0));
            if mode != Mode::Volume && (0.5..1.5).contains(&t) {
                assert!(report.degraded(), "{mode:?} t = {t}: {report:?}");
                assert!(
                    report
                        .missing
                        .iter()
                        .any(|m| m.contains("base view 0, key 1")),
                    "{:?}",
                    report.missing
                );
            }
            if t == 0.0 && mode != Mode::Volume {
                assert!(
                    report
                        .missing
                        .iter()
                        .any(|m| m.contains("base view 1, key 0")),
                    "{:?}",
                    report.missing
                );
            }
        }
    }
    // Every range image broken: an error naming why, still no panic.
    let mut all = bytes.clone();
    for e in pack
        .entries()
        .iter()
        .filter(|e| e.kind == ChunkKind::RadianceCube)
    {
        let mid = (e.offset + e.length / 2) as usize;
        all[mid] ^= 0xff;
    }
    std::fs::write(&path, &all).unwrap();
    let rec = Reconstructor::open(&path).unwrap();
    let err = rec.render(&cam, 1.0, Mode::GeometryAssisted).unwrap_err();
    assert!(err.to_string().contains("radiance"), "{err}");
    // Broken proxy geometry: geometry-assisted falls back to image mode and says so.
    let mut noproxy = bytes.clone();
    for e in pack
        .entries()
        .iter()
        .filter(|e| e.kind == ChunkKind::ProxyMesh)
    {
        let mid = (e.offset + e.length / 2) as usize;
        noproxy[mid] ^= 0xff;
    }
    std::fs::write(&path, &noproxy).unwrap();
    let rec = Reconstructor::open(&path).unwrap();
    let (_, report) = rec.render(&cam, 0.5, Mode::GeometryAssisted).unwrap();
    assert_eq!(report.used_mode, Mode::Image);
    assert!(
        report.missing.iter().any(|m| m.contains("proxy mesh")),
        "{:?}",
        report.missing
    );
}

#[test]
fn bilinear_cube_filter_keeps_the_geometry_and_the_error() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bilinear.pack");
    let scene = room(true);
    let spec = PackSpec::segment(3, vec![0.0, 1.0, 2.0], 32);
    write_pack(&scene, &spec, &path);
    let mut rec = Reconstructor::open(&path).unwrap();
    let accel = SceneAccel::new(&scene).unwrap();
    let mut errors = [0.0; 2];
    for (t, x) in [(1.0f32, spec.views[1].x), (0.8, 0.1), (1.3, 0.5)] {
        let camera = Camera::look_at(
            Vec3::new(x, 1.3, 1.2),
            Vec3::new(0.3, 0.8, -2.0),
            Vec3::Y,
            1.2,
            80,
            60,
        )
        .unwrap();
        let r = reference(&accel.at_time(t), &camera);
        rec.settings.cube_filter = plenoptic_recon::CubeFilter::Nearest;
        let (nearest, _) = rec.render(&camera, t, Mode::GeometryAssisted).unwrap();
        rec.settings.cube_filter = plenoptic_recon::CubeFilter::Bilinear;
        let (filtered, report) = rec.render(&camera, t, Mode::GeometryAssisted).unwrap();
        let (en, ef) = (
            relative_lrms(&to_image(&nearest), &r),
            relative_lrms(&to_image(&filtered), &r),
        );
        let changed = filtered
            .radiance
            .iter()
            .zip(&nearest.radiance)
            .filter(|(a, b)| !a.abs_diff_eq(**b, 1e-4))
            .count();
        println!(
            "t = {t}: relative LRMS nearest {en:.4}, bilinear {ef:.4}; {changed} pixels differ; {:?}",
            report.fallback
        );
        // The filter changes radiance only: the same geometry and the same acceptance.
        assert!(changed > 0);
        assert_eq!(filtered.object, nearest.object);
        assert_eq!(filtered.depth, nearest.depth);
        errors[0] += en;
        errors[1] += ef;
    }
    assert!(errors[1] < errors[0], "{errors:?}");
}
