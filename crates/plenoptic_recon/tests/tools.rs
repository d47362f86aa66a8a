//! The render and compare tools end to end on a small pack.

mod common;

use common::*;
use plenoptic_recon::path::{CameraPath, Keyframe};
use plenoptic_recon::tools::{compare, render_path, write_frame_files};
use plenoptic_recon::{Camera, Mode};
use plenoptic_trace::SceneAccel;
use plenoptic_trace::glam::Vec3;

#[test]
fn render_path_then_compare_writes_frames_csv_and_plot() {
    let dir = tempfile::tempdir().unwrap();
    let pack = dir.path().join("room.pack");
    let scene = room(true);
    let mut spec = PackSpec::segment(3, vec![0.0, 1.0, 2.0], 24);
    spec.volume_samples = 800;
    write_pack(&scene, &spec, &pack);
    let path = CameraPath {
        frame_rate: 2.0,
        width: 48,
        height: 32,
        keyframes: vec![
            Keyframe::looking_at(
                0.0,
                Vec3::new(-0.8, 1.3, 1.2),
                Vec3::new(0.0, 0.5, -2.0),
                65.0,
                0.0,
            ),
            Keyframe::looking_at(
                2.0,
                Vec3::new(0.8, 1.3, 1.2),
                Vec3::new(0.0, 0.5, -2.0),
                65.0,
                2.0,
            ),
        ],
    };
    let path_file = dir.path().join("path.json");
    path.save(&path_file).unwrap();
    // Reference frames through the shared naming.
    let refdir = dir.path().join("reference");
    std::fs::create_dir_all(&refdir).unwrap();
    let accel = SceneAccel::new(&scene).unwrap();
    for s in path.frames() {
        let img = reference(&accel.at_time(s.scene_time), &s.camera);
        write_frame_files(
            &refdir,
            s.index,
            img.width,
            img.height,
            &img.pixels,
            None,
            1.0,
        )
        .unwrap();
    }
    let mut candidates = Vec::new();
    for mode in Mode::ALL {
        let out = dir.path().join(mode.name());
        let summary = render_path(&pack, &path_file, mode, &out, false).unwrap();
        assert_eq!(summary.frames, 5);
        assert!(out.join("frame_00004.png").exists() && out.join("frame_00004.exr").exists());
        println!(
            "{}: {:.1} ms/frame (48×32, dev profile)",
            mode.name(),
            summary.mean_ms
        );
        candidates.push((mode.name().to_string(), out));
    }
    let csv = dir.path().join("metrics.csv");
    let png = dir.path().join("error.png");
    let metrics = compare(&refdir, &candidates, &csv, &png).unwrap();
    let text = std::fs::read_to_string(&csv).unwrap();
    assert!(text.starts_with("frame,image_lrms,image_psnr,volume_lrms"));
    assert_eq!(text.lines().count(), 6);
    assert!(png.exists());
    for m in &metrics {
        println!("{}: mean relative LRMS {:.4}", m.label, m.mean_lrms());
        assert!(m.relative_lrms.iter().all(|x| x.is_finite()));
    }
    if let Ok(keep) = std::env::var("RECON_KEEP") {
        std::fs::copy(&png, keep).unwrap();
    }
    let _ = Camera::look_at(Vec3::ZERO, -Vec3::Z, Vec3::Y, 1.0, 2, 2).unwrap();
}
