//! Image comparison: relative LRMS (the thesis's metric, chapter 5.4) and PSNR.

use glam::Vec3;

use crate::image::{Image, luminance};

/// Relative luminance RMS error: the RMS over pixels of the luminance difference, divided by
/// the mean luminance of the reference (thesis table 5.2, "LRMS error / average luminance").
/// Returns infinity for images of different sizes and NaN for a black reference.
pub fn relative_lrms(test: &Image<Vec3>, reference: &Image<Vec3>) -> f64 {
    if test.width != reference.width || test.height != reference.height {
        return f64::INFINITY;
    }
    let n = reference.pixels.len().max(1) as f64;
    let sq: f64 = test
        .pixels
        .iter()
        .zip(&reference.pixels)
        .map(|(&a, &b)| f64::from(luminance(a) - luminance(b)).powi(2))
        .sum();
    (sq / n).sqrt() / reference.mean_luminance()
}

/// The scale PSNR applies before clamping: one over the 99th percentile of the reference's
/// luminance (so a few fireflies do not set the peak).
pub fn psnr_scale(reference: &Image<Vec3>) -> f32 {
    let mut l: Vec<f32> = reference.pixels.iter().map(|&c| luminance(c)).collect();
    if l.is_empty() {
        return 1.0;
    }
    let k = ((l.len() - 1) as f32 * 0.99) as usize;
    let (_, v, _) = l.select_nth_unstable_by(k, f32::total_cmp);
    if *v > 0.0 { 1.0 / *v } else { 1.0 }
}

/// PSNR in dB over RGB. Both images are multiplied by [`psnr_scale`]`(reference)` and clamped
/// to [0, 1]; the peak is 1. Infinite for identical images.
pub fn psnr(test: &Image<Vec3>, reference: &Image<Vec3>) -> f64 {
    if test.width != reference.width || test.height != reference.height {
        return f64::NEG_INFINITY;
    }
    let k = psnr_scale(reference);
    let n = (reference.pixels.len().max(1) * 3) as f64;
    let sq: f64 = test
        .pixels
        .iter()
        .zip(&reference.pixels)
        .map(|(&a, &b)| {
            let d = (a * k).clamp(Vec3::ZERO, Vec3::ONE) - (b * k).clamp(Vec3::ZERO, Vec3::ONE);
            f64::from(d.length_squared())
        })
        .sum();
    let mse = sq / n;
    if mse == 0.0 {
        f64::INFINITY
    } else {
        -10.0 * mse.log10()
    }
}
