//! The low-frequency relative error: what a viewer sees as blotches, halos and dim patches,
//! which the per-pixel relative LRMS hides under the reference's pixel noise.
//!
//! Both images' luminance is blurred with a Gaussian of σ = [`SIGMA_OF_WIDTH`] × the image
//! width (2 %: 3.2 pixels at 160 × 90, 25.6 at 1280 × 720), and the relative LRMS of the
//! difference is taken: √(mean (G∗x − G∗m)²) / mean(G∗m). The blur averages about 2πσ² ≈ 64
//! pixels at 160 px wide, so a path-traced reference's per-pixel noise falls to about a
//! tenth (0.01–0.02 relative at 512 samples per pixel), and the figure needs no variance
//! correction. A mean offset of 5 % alone scores 0.05; a blotch a few σ across keeps most
//! of its error; pixel noise in the candidate scores almost nothing.
//!
//! At the image's borders the kernel is cut and renormalised, so a uniform image stays
//! uniform and the borders are not darkened.

use glam::Vec3;
use plenoptic_trace::Image;
use plenoptic_trace::image::luminance;

/// The Gaussian's σ as a fraction of the image width.
pub const SIGMA_OF_WIDTH: f64 = 0.02;

/// The low-frequency relative error of `test` against `reference` (see the module docs).
/// NaN when the sizes differ or the reference is black.
pub fn low_frequency_error(test: &Image<Vec3>, reference: &Image<Vec3>) -> f64 {
    match low_frequency_difference(test, reference) {
        Some(d) => (d.iter().map(|v| v * v).sum::<f64>() / d.len() as f64).sqrt(),
        None => f64::NAN,
    }
}

/// The signed low-frequency difference of `test` from `reference` per pixel (row-major):
/// (G∗x − G∗m) / mean(G∗m), positive where `test` is brighter; its RMS is
/// [`low_frequency_error`]. `None` when the sizes differ or the reference is black.
pub fn low_frequency_difference(test: &Image<Vec3>, reference: &Image<Vec3>) -> Option<Vec<f64>> {
    let (w, h) = (reference.width as usize, reference.height as usize);
    if (test.width, test.height) != (reference.width, reference.height)
        || test.pixels.len() != w * h
        || reference.pixels.len() != w * h
        || w == 0
    {
        return None;
    }
    let sigma = SIGMA_OF_WIDTH * w as f64;
    let x = blur(&luminance_of(test), w, h, sigma);
    let m = blur(&luminance_of(reference), w, h, sigma);
    let mean = m.iter().sum::<f64>() / m.len() as f64;
    if mean <= 0.0 || mean.is_nan() {
        return None;
    }
    Some(x.iter().zip(&m).map(|(a, b)| (a - b) / mean).collect())
}

/// The colour [`crate::maps`] shows a signed difference `v` in: white at 0, towards red where
/// the candidate is brighter and blue where it is darker, saturated at ±`full`.
pub fn difference_colour(v: f64, full: f64) -> [u8; 3] {
    let t = if full > 0.0 && v.is_finite() {
        (v / full).clamp(-1.0, 1.0)
    } else {
        0.0
    };
    let fade = |x: f64| (255.0 * (1.0 - x) + 0.5) as u8;
    if t >= 0.0 {
        [255, fade(t), fade(t)]
    } else {
        [fade(-t), fade(-t), 255]
    }
}

fn luminance_of(image: &Image<Vec3>) -> Vec<f64> {
    image
        .pixels
        .iter()
        .map(|&c| f64::from(luminance(c)))
        .collect()
}

/// The normalised Gaussian weights for offsets −r..=r, r = ⌈3σ⌉.
fn kernel(sigma: f64) -> Vec<f64> {
    let r = (3.0 * sigma).ceil().max(1.0) as i64;
    let k: Vec<f64> = (-r..=r)
        .map(|i| (-(i * i) as f64 / (2.0 * sigma * sigma)).exp())
        .collect();
    let sum: f64 = k.iter().sum();
    k.into_iter().map(|v| v / sum).collect()
}

/// Separable Gaussian blur of a `w × h` image, the kernel cut and renormalised at the
/// borders.
fn blur(values: &[f64], w: usize, h: usize, sigma: f64) -> Vec<f64> {
    let k = kernel(sigma);
    let rows = blur_axis(values, w, h, &k, 1, w);
    blur_axis(&rows, h, w, &k, w, 1)
}

/// Blurs along one axis: `len` samples `step` apart, `lines` lines `line_step` apart.
fn blur_axis(
    values: &[f64],
    len: usize,
    lines: usize,
    k: &[f64],
    step: usize,
    line_step: usize,
) -> Vec<f64> {
    let r = (k.len() / 2) as isize;
    let mut out = vec![0.0; values.len()];
    for line in 0..lines {
        let base = line * line_step;
        for i in 0..len as isize {
            let (mut sum, mut weight) = (0.0, 0.0);
            for (j, &kv) in k.iter().enumerate() {
                let p = i + j as isize - r;
                if (0..len as isize).contains(&p) {
                    sum += kv * values[base + p as usize * step];
                    weight += kv;
                }
            }
            out[base + i as usize * step] = sum / weight;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A smooth, non-uniform reference: a ramp with a bright window.
    fn reference(w: u32, h: u32) -> Image<Vec3> {
        let pixels = (0..h)
            .flat_map(|y| {
                (0..w).map(move |x| {
                    let window = (40..60).contains(&x) && (10..30).contains(&y);
                    Vec3::splat(0.2 + 0.6 * x as f32 / w as f32 + if window { 2.0 } else { 0.0 })
                })
            })
            .collect();
        Image {
            width: w,
            height: h,
            pixels,
        }
    }

    /// `image` with every pixel replaced by `f(x, y, colour)`.
    fn map_pixels(image: &Image<Vec3>, f: impl Fn(u32, u32, Vec3) -> Vec3) -> Image<Vec3> {
        let w = image.width;
        Image {
            pixels: (0u32..)
                .zip(&image.pixels)
                .map(|(i, &c)| f(i % w, i / w, c))
                .collect(),
            ..image.clone()
        }
    }

    #[test]
    fn a_mean_offset_of_five_percent_scores_five_percent() {
        let r = reference(160, 90);
        let offset = 0.05 * r.mean_luminance() as f32;
        let t = map_pixels(&r, |_, _, c| c + Vec3::splat(offset));
        let e = low_frequency_error(&t, &r);
        assert!((e - 0.05).abs() < 1e-4, "{e}");
        assert!(low_frequency_error(&r, &r).abs() < 1e-12);
    }

    #[test]
    fn pixel_noise_is_blurred_away_and_a_blotch_is_not() {
        let r = reference(160, 90);
        let mean = r.mean_luminance() as f32;
        // ±30 % of the mean per pixel, zero-mean over every 2 × 2 block.
        let noisy = map_pixels(&r, |x, y, c| {
            c + Vec3::splat(if (x + y) % 2 == 0 { 0.3 } else { -0.3 } * mean)
        });
        let per_pixel = plenoptic_trace::metrics::relative_lrms(&noisy, &r);
        let low = low_frequency_error(&noisy, &r);
        assert!(per_pixel > 0.25, "{per_pixel}");
        assert!(low < 0.01, "{low}");
        // A blotch 16 pixels across, 30 % brighter: it stays.
        let blotch = map_pixels(&r, |x, y, c| {
            let inside = (100..116).contains(&x) && (50..66).contains(&y);
            if inside { c * 1.3 } else { c }
        });
        let per_pixel = plenoptic_trace::metrics::relative_lrms(&blotch, &r);
        let low = low_frequency_error(&blotch, &r);
        assert!(low > 0.5 * per_pixel, "{low} against {per_pixel}");
    }

    #[test]
    fn sizes_that_differ_or_a_black_reference_give_nan() {
        let r = reference(160, 90);
        assert!(low_frequency_error(&reference(80, 45), &r).is_nan());
        let black = Image {
            pixels: vec![Vec3::ZERO; r.pixels.len()],
            ..r.clone()
        };
        assert!(low_frequency_error(&r, &black).is_nan());
    }

    #[test]
    fn the_difference_map_is_signed_and_its_rms_is_the_error() {
        let r = reference(160, 90);
        // The left half 10 % brighter, the right half as the reference.
        let x = map_pixels(&r, |x, _, c| if x < 80 { c * 1.1 } else { c });
        let d = low_frequency_difference(&x, &r).unwrap();
        let at = |x: usize, y: usize| d[y * 160 + x];
        assert!(
            at(20, 45) > 0.03 && at(140, 45).abs() < 0.01,
            "{} {}",
            at(20, 45),
            at(140, 45)
        );
        let rms = (d.iter().map(|v| v * v).sum::<f64>() / d.len() as f64).sqrt();
        assert!((rms - low_frequency_error(&x, &r)).abs() < 1e-12);
        assert_eq!(difference_colour(0.0, 0.2), [255, 255, 255]);
        assert_eq!(difference_colour(0.4, 0.2), [255, 0, 0]);
        assert_eq!(difference_colour(-0.2, 0.2), [0, 0, 255]);
        assert_eq!(difference_colour(f64::NAN, 0.2), [255, 255, 255]);
    }
}
