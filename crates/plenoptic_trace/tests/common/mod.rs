//! Shared helpers of the integration tests.
#![allow(dead_code)]

use glam::Vec3;
use plenoptic_trace::{Image, image::luminance};

/// Mean and standard error of the mean of the per-pixel luminance.
pub fn mean_and_se(img: &Image<Vec3>) -> (f64, f64) {
    let v: Vec<f64> = img
        .pixels
        .iter()
        .map(|&c| f64::from(luminance(c)))
        .collect();
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

/// The directory tests write images into.
pub fn out_dir() -> std::path::PathBuf {
    let d = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("plenoptic_trace");
    std::fs::create_dir_all(&d).unwrap();
    d
}
