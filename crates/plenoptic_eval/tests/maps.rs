//! `plenoptic compare --maps`: the low-frequency difference pictures
//! ([`plenoptic_eval::maps`]).

use std::path::PathBuf;

use plenoptic_eval::maps::write_low_frequency_maps;
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

#[test]
fn a_brighter_patch_is_red_a_darker_one_blue_and_the_rest_white() {
    let dir = tempfile::tempdir().unwrap();
    let write = |name: &str, pixels: &[Vec3]| -> PathBuf {
        let d = dir.path().join(name);
        std::fs::create_dir_all(&d).unwrap();
        write_frame_files(&d, 0, W, H, pixels, None, 1.0).unwrap();
        d
    };
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
