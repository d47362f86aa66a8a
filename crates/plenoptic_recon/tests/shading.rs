//! Geometry-assisted shading of pack 2.0 (`plenoptic_recon::shading`): objects with a
//! material show albedo × lighting + non-diffuse, `Shading::Radiance` shows the baked radiance
//! exactly as a pack without materials does, and a pack whose lighting cannot be read falls
//! back to the radiance with the reason in the report.

mod common;

use common::*;
use plenoptic_recon::{Camera, Mode, Reconstructor, Shading};
use plenoptic_trace::glam::Vec3;

fn camera() -> Camera {
    Camera::look_at(
        Vec3::new(0.3, 1.3, 1.0),
        Vec3::new(0.0, 0.8, -2.5),
        Vec3::Y,
        0.9,
        64,
        48,
    )
    .unwrap()
}

fn pack(dir: &std::path::Path, name: &str, materials: Materials, lighting: bool) -> Reconstructor {
    let path = dir.join(name);
    write_pack(
        &room(true),
        &PackSpec {
            materials,
            lighting_chunks: lighting,
            ..PackSpec::segment(3, vec![0.0, 1.0, 2.0], 8)
        },
        &path,
    );
    Reconstructor::open(&path).unwrap()
}

fn frame(rec: &Reconstructor) -> (Vec<Vec3>, plenoptic_recon::Report) {
    let (f, r) = rec.render(&camera(), 0.7, Mode::GeometryAssisted).unwrap();
    (f.radiance, r)
}

fn mean_difference(a: &[Vec3], b: &[Vec3]) -> f32 {
    let d: f32 = a
        .iter()
        .zip(b)
        .map(|(x, y)| (*x - *y).abs().max_element())
        .sum();
    d / a.len() as f32
}

#[test]
fn materials_shade_the_lighting_and_radiance_shading_is_version_one_s_frame() {
    let dir = tempfile::tempdir().unwrap();
    let plain = frame(&pack(dir.path(), "plain.pack", Materials::None, true)).0;
    let mut rec = pack(dir.path(), "factors.pack", Materials::Factors, true);
    let (lit, report) = frame(&rec);
    assert!(
        report.stage_ms.iter().any(|s| s.0 == "lighting_pass"),
        "{:?}",
        report.stage_ms
    );
    // The analytic scene's radiance has a checker in its albedo; the factors do not: the
    // shaded frame is not the radiance frame.
    let apart = mean_difference(&lit, &plain);
    assert!(apart > 0.02, "{apart}");
    // Radiance shading of the same pack is the frame of the pack without materials.
    rec.settings.shading = Shading::Radiance;
    let (radiance, _) = frame(&rec);
    assert!(mean_difference(&radiance, &plain) < 1e-6);
}

#[test]
fn a_pack_without_lighting_cubes_falls_back_to_the_radiance_and_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let plain = frame(&pack(dir.path(), "plain.pack", Materials::None, true)).0;
    let rec = pack(dir.path(), "damaged.pack", Materials::Factors, false);
    let (f, report) = frame(&rec);
    assert!(
        report
            .missing
            .iter()
            .any(|m| m.contains("materials not applied") || m.contains("lighting cube")),
        "{:?}",
        report.missing
    );
    assert!(mean_difference(&f, &plain) < 1e-6);
}
