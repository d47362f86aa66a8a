//! The render and compare tools end to end on a small pack.

#[path = "../../plenoptic_recon/tests/common/mod.rs"]
mod common;

use common::*;
use plenoptic_eval::tools::{compare, compare_with, frame_name, render_path, write_frame_files};
use plenoptic_recon::path::{CameraPath, Keyframe};
use plenoptic_recon::{Camera, Mode};
use plenoptic_trace::SceneAccel;
use plenoptic_trace::glam::Vec3;

/// Deterministic zero-mean noise in [−1, 1) (xorshift).
struct Noise(u64);
impl Noise {
    fn next(&mut self) -> f32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 40) as f32 / (1u64 << 23) as f32 - 1.0
    }
}

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
    assert!(
        text.starts_with(
            "frame,image_lrms,image_psnr,image_mean_ratio,image_ssim,image_low_frequency,volume_lrms"
        ),
        "{text}"
    );
    assert_eq!(text.lines().count(), 6);
    assert!(png.exists() && png.with_extension("svg").exists());
    for m in &metrics {
        println!("{}: mean relative LRMS {:.4}", m.label, m.mean_lrms());
        assert!(m.relative_lrms.iter().all(|x| x.is_finite()));
        assert!(m.mean_ratio.iter().all(|r| (0.5..2.0).contains(r)), "{m:?}");
        assert!(m.corrected_lrms.is_empty());
        assert!(m.ssim.iter().all(|q| (0.0..=1.0).contains(q)), "{m:?}");
    }
    if let Ok(keep) = std::env::var("RECON_KEEP") {
        std::fs::copy(&png, &keep).unwrap();
        std::fs::copy(png.with_extension("svg"), format!("{keep}.svg")).unwrap();
    }

    // The reference as two noisy halves A and B of the same frames (noise of standard
    // deviation 0.2 × the pixel's luminance, independent per half): the corrected error is
    // close to the error against the clean reference, the uncorrected one is not.
    let (half_a, half_b) = (dir.path().join("ref_a"), dir.path().join("ref_b"));
    for (k, half) in [&half_a, &half_b].into_iter().enumerate() {
        std::fs::create_dir_all(half).unwrap();
        let mut noise = Noise(0x9e37_79b9 + k as u64);
        for s in path.frames() {
            let img = reference(&accel.at_time(s.scene_time), &s.camera);
            let noisy: Vec<Vec3> = img
                .pixels
                .iter()
                .map(|&c| c * (1.0 + 0.2 * 3f32.sqrt() * noise.next()))
                .collect();
            write_frame_files(half, s.index, img.width, img.height, &noisy, None, 1.0).unwrap();
        }
    }
    let csv2 = dir.path().join("halves.csv");
    let cmp = compare_with(
        &half_a,
        Some(&half_b),
        &candidates,
        &csv2,
        &dir.path().join("halves.png"),
    )
    .unwrap();
    let text = std::fs::read_to_string(&csv2).unwrap();
    assert!(
        text.starts_with(
            "frame,noise_floor,halves_ssim,image_lrms_corrected,image_lrms,image_psnr"
        ),
        "{text}"
    );
    assert!(
        text.lines()
            .next()
            .unwrap()
            .contains(",image_ssim,image_low_frequency,volume_lrms_corrected"),
        "{text}"
    );
    assert!(cmp.table().contains("low-freq"), "{}", cmp.table());
    print!("{}", cmp.table());
    let floor = cmp.mean_noise_floor();
    assert!(floor > 0.05, "{floor}");
    for (m, clean) in cmp.candidates.iter().zip(&metrics) {
        let (c, u, truth) = (m.mean_corrected_lrms(), m.mean_lrms(), clean.mean_lrms());
        println!(
            "{}: corrected {c:.4}, uncorrected {u:.4}, clean {truth:.4}",
            m.label
        );
        assert!(u > c, "{m:?}");
        assert!((c - truth).abs() < 0.25 * truth + 0.01, "{c} vs {truth}");
        // SSIM is not corrected: the reference's noise lowers it.
        assert!(m.mean_ssim() < clean.mean_ssim(), "{m:?} {clean:?}");
    }
    let halves_ssim = cmp.halves_ssim.as_deref().unwrap();
    assert_eq!(halves_ssim.len(), cmp.frames.len());
    assert!(
        halves_ssim.iter().all(|q| (0.0..0.99).contains(q)),
        "{halves_ssim:?}"
    );
    assert_eq!(cmp.plots.len(), 2);
    // A missing frame in B names the file.
    std::fs::remove_file(half_b.join(frame_name(2, "exr"))).unwrap();
    let e = compare_with(&half_a, Some(&half_b), &candidates, &csv2, &png).unwrap_err();
    assert!(e.to_string().contains("frame_00002.exr"), "{e}");
    let _ = Camera::look_at(Vec3::ZERO, -Vec3::Z, Vec3::Y, 1.0, 2, 2).unwrap();
}
