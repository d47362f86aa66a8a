//! The runtime's rasterized geometry mask against the ray-cast reference mask, and
//! reconstruction from a given mask.

#[path = "../../plenoptic_recon/tests/common/mod.rs"]
mod common;

use common::*;
use plenoptic_eval::mask::{RayCastMask, proxy_scene};
use plenoptic_recon::{Camera, Mode, Reconstructor};
use plenoptic_trace::glam::Vec3;

#[test]
fn rasterized_mask_matches_the_ray_cast_mask() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("mask.pack");
    let scene = room(true);
    write_pack(&scene, &PackSpec::segment(2, vec![0.0, 2.0], 8), &path);
    let rec = Reconstructor::open(&path).unwrap();
    let proxy = rec.proxy().unwrap();
    let proxies = proxy_scene(proxy);
    let caster = RayCastMask::new(&proxies, proxy).unwrap();
    for (t, eye) in [
        (0.4f32, Vec3::new(0.2, 1.2, 1.5)),
        (1.7, Vec3::new(-1.5, 0.4, -2.0)),
    ] {
        let cam = Camera::look_at(eye, Vec3::new(0.0, 0.5, -1.0), Vec3::Y, 1.3, 96, 64).unwrap();
        let (a, b) = (caster.mask(&cam, t), proxy.mask_raster(&cam, t));
        let same = a
            .object
            .iter()
            .zip(&b.object)
            .filter(|(x, y)| x == y)
            .count() as f32
            / a.object.len() as f32;
        let depth_ok = a
            .depth
            .iter()
            .zip(&b.depth)
            .zip(a.object.iter().zip(&b.object))
            .filter(|((da, db), (oa, ob))| {
                oa == ob && **oa != 0 && (*da - *db).abs() <= 1e-3 * da.max(1.0)
            })
            .count();
        let hits = a
            .object
            .iter()
            .zip(&b.object)
            .filter(|(x, y)| x == y && **x != 0)
            .count();
        println!(
            "t = {t}: raster/ray-cast ids agree on {:.2}% of pixels",
            same * 100.0
        );
        assert!(same > 0.99, "{same}");
        assert_eq!(depth_ok, hits);
    }
}

#[test]
fn reconstruction_from_the_ray_cast_mask_matches_the_rasterized_one() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("mask.pack");
    let scene = room(true);
    write_pack(
        &scene,
        &PackSpec::segment(3, vec![0.0, 1.0, 2.0], 16),
        &path,
    );
    let rec = Reconstructor::open(&path).unwrap();
    let proxy = rec.proxy().unwrap();
    let proxies = proxy_scene(proxy);
    let caster = RayCastMask::new(&proxies, proxy).unwrap();
    let cam = Camera::look_at(
        Vec3::new(0.3, 1.3, 1.1),
        Vec3::new(0.0, 0.5, -2.0),
        Vec3::Y,
        1.1,
        64,
        48,
    )
    .unwrap();
    let t = 0.8;
    let (raster, r_report) = rec.render(&cam, t, Mode::GeometryAssisted).unwrap();
    let (cast, c_report) = rec
        .render_with_mask(&cam, t, &caster.mask(&cam, t))
        .unwrap();
    assert_eq!(c_report.used_mode, Mode::GeometryAssisted);
    let same = raster
        .radiance
        .iter()
        .zip(&cast.radiance)
        .filter(|(a, b)| a.abs_diff_eq(**b, 1e-3 * a.max_element().max(1.0)))
        .count() as f32
        / raster.radiance.len() as f32;
    println!(
        "{:.2}% of pixels agree; direct {:.3} vs {:.3}",
        same * 100.0,
        r_report.fallback.direct,
        c_report.fallback.direct
    );
    assert!(same > 0.97, "{same}");
    assert!((r_report.fallback.direct - c_report.fallback.direct).abs() < 0.02);
    // A mask of the wrong size is refused.
    let small = Camera::look_at(cam.position, Vec3::ZERO, Vec3::Y, 1.1, 8, 8).unwrap();
    assert!(
        rec.render_with_mask(&cam, t, &caster.mask(&small, t))
            .is_err()
    );
}
