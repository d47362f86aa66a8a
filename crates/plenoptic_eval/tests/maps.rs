//! `plenoptic compare --maps`: the low-frequency difference pictures and the error maps
//! ([`plenoptic_eval::maps`]).

use std::path::{Path, PathBuf};

use plenoptic_eval::maps::{TILE, write_error_maps, write_low_frequency_maps};
use plenoptic_eval::tools::{frame_name, write_frame_files};
use plenoptic_trace::glam::Vec3;

const W: u32 = 64;
const H: u32 = 36;

/// A frame of grey `level`, its left third `left` times brighter.
fn frame(level: f32, left: f32) -> Vec<Vec3> {
    (0..H)
        .flat_map(|_| (0..W).map(move |x| Vec3::splat(level * if x < W / 3 { left } else { 1.0 })))
        .collect()
}

/// Frame 0 of `pixels` (W × H) written into `root/name`, which is returned.
fn write_frame(root: &Path, name: &str, pixels: &[Vec3]) -> PathBuf {
    let d = root.join(name);
    std::fs::create_dir_all(&d).unwrap();
    write_frame_files(&d, 0, W, H, pixels, None, 1.0).unwrap();
    d
}

#[test]
fn a_brighter_patch_is_red_a_darker_one_blue_and_the_rest_white() {
    let dir = tempfile::tempdir().unwrap();
    let write = |name: &str, pixels: &[Vec3]| write_frame(dir.path(), name, pixels);
    let (a, b) = (write("a", &frame(0.5, 1.0)), write("b", &frame(0.5, 1.0)));
    let bright = write("bright", &frame(0.5, 1.5));
    let dark = write("dark", &frame(0.5, 0.5));
    let out = dir.path().join("maps");
    let candidates = vec![("bright".to_string(), bright), ("dark".to_string(), dark)];
    let n = write_low_frequency_maps(&a, Some(&b), &candidates, &out).unwrap();
    assert_eq!(n, 2);
    let pixel = |label: &str, x: u32| {
        let path = out.join(format!("{label}_{}", frame_name(0, "png")));
        image::open(&path).unwrap().to_rgb8().get_pixel(x, H / 2).0
    };
    // Well inside the left third: saturated (the difference is 0.25 of the mean or more).
    assert_eq!(pixel("bright", 4), [255, 0, 0]);
    assert_eq!(pixel("dark", 4), [0, 0, 255]);
    // Far from it, the blur (σ = 2 % of the width) leaves no difference.
    assert_eq!(pixel("bright", W - 4), [255, 255, 255]);
    // A candidate frame of another size names its file.
    let small = dir.path().join("small");
    std::fs::create_dir_all(&small).unwrap();
    let half = &frame(0.5, 1.0)[..(W * H / 2) as usize];
    write_frame_files(&small, 0, W, H / 2, half, None, 1.0).unwrap();
    let e =
        write_low_frequency_maps(&a, Some(&b), &[("small".to_string(), small)], &out).unwrap_err();
    assert!(
        e.to_string().contains("small") && e.to_string().contains("64×18"),
        "{e}"
    );
    // A missing reference half names the file.
    std::fs::remove_file(b.join(frame_name(0, "exr"))).unwrap();
    let e = write_low_frequency_maps(&a, Some(&b), &candidates, &out).unwrap_err();
    assert!(e.to_string().contains("frame_00000.exr"), "{e}");
}

#[test]
fn an_error_map_is_red_where_the_error_is_and_names_its_worst_tile() {
    let dir = tempfile::tempdir().unwrap();
    let write = |name: &str, pixels: &[Vec3]| write_frame(dir.path(), name, pixels);
    // Halves A and B differ by a checker of ±0.05 (the reference's noise); their mean is 0.5.
    let half = |sign: f32| -> Vec<Vec3> {
        (0..H)
            .flat_map(|y| {
                (0..W).map(move |x| {
                    let s = if (x + y) % 2 == 0 { sign } else { -sign };
                    Vec3::splat(0.5 + 0.05 * s)
                })
            })
            .collect()
    };
    let (a, b) = (write("a", &half(1.0)), write("b", &half(-1.0)));
    // The candidate is the mean, but for a 2 × 2 spot at 3.0 in the tile at (40, 16).
    let mut spot = vec![Vec3::splat(0.5); (W * H) as usize];
    for (x, y) in [(42, 18), (43, 18), (42, 19), (43, 19)] {
        spot[(y * W + x) as usize] = Vec3::splat(3.0);
    }
    let spot_dir = write("spot", &spot);
    let out = dir.path().join("maps");
    let written = write_error_maps(&a, Some(&b), &[("spot".to_string(), spot_dir)], &out).unwrap();
    assert_eq!(written.len(), 1);
    let (label, frame, c) = &written[0];
    assert_eq!((label.as_str(), *frame), ("spot", 0));
    assert_eq!((c.x, c.y), (40, 16));
    assert_eq!(TILE, 8);
    // The spot's error (4 × 2.5²), less the reference's variance (0.05² at every pixel), in
    // the tile and in the frame: more than the frame's sum, as the rest is below the noise.
    let (spot_error, variance) = (4.0 * 2.5f64.powi(2), 0.05f64.powi(2));
    let expected = (spot_error - 64.0 * variance) / (spot_error - f64::from(W * H) * variance);
    assert!(
        (c.share - expected).abs() < 1e-3,
        "{} against {expected}",
        c.share
    );
    let pixel = |x: u32, y: u32| {
        let path = out.join(format!("spot_error_{}", frame_name(0, "png")));
        image::open(&path).unwrap().to_rgb8().get_pixel(x, y).0
    };
    assert_eq!(pixel(42, 18), [255, 0, 0]);
    // Away from the spot the candidate is the reference's mean: below its noise, not red.
    let far = pixel(4, 4);
    assert!(far[0] < 255 && far[2] == 255, "{far:?}");
}
