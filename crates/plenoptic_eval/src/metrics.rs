//! Image metrics: the thesis's relative LRMS and PSNR ([`plenoptic_trace::metrics`],
//! re-exported), the mean-luminance ratio, SSIM of the displayed frames ([`ssim`]), and the
//! relative LRMS corrected for the noise of a path-traced reference (docs/architecture.md,
//! "Measuring against a noisy reference").
//!
//! # Variance correction
//!
//! Render the reference as two independent halves A and B (each with half the samples, from
//! different random sequences) and use their mean M = (A + B)/2 as the reference. Per pixel,
//! with luminances a, b, m and true luminance s: if each half has variance σ²_half, then
//!
//! - Var(m) = σ²_half / 2 (the mean of two independent estimates), and
//! - E((a − b)²) = Var(a) + Var(b) = 2 σ²_half,
//!
//! so (a − b)²/4 is an unbiased estimate of Var(m). For a test image x independent of the
//! reference's noise, E((x − m)²) = (x − s)² + Var(m): the squared error against a noisy
//! reference overstates the true squared error by the reference's variance. The corrected
//! mean squared error is therefore
//!
//! ```text
//! MSE_c = max(0, mean (x − m)² − mean (a − b)²/4)
//! ```
//!
//! and the corrected relative LRMS is √MSE_c / mean(m). The reference's *noise floor* is the
//! relative LRMS of that noise alone, √(mean (a − b)²/4) / mean(m): what a perfect image
//! scores uncorrected. The correction removes the floor in expectation; what remains is the
//! estimate's own scatter (its standard deviation is about √(2/N) of the floor's square for
//! N pixels), so corrected errors well below the floor are not resolved. The mean-luminance
//! ratio mean(x)/mean(m) shows a bias that noise would otherwise hide.

use glam::Vec3;
use plenoptic_trace::Image;
pub use plenoptic_trace::image::luminance;
pub use plenoptic_trace::metrics::{psnr, relative_lrms};

/// Mean luminance of `test` over mean luminance of `reference` (NaN for a black reference
/// or images of different sizes).
pub fn mean_luminance_ratio(test: &Image<Vec3>, reference: &Image<Vec3>) -> f64 {
    if (test.width, test.height) != (reference.width, reference.height) {
        return f64::NAN;
    }
    let r = reference.mean_luminance();
    if r > 0.0 {
        test.mean_luminance() / r
    } else {
        f64::NAN
    }
}

/// The mean (A + B)/2 of two reference halves (None for different sizes).
pub fn mean_image(a: &Image<Vec3>, b: &Image<Vec3>) -> Option<Image<Vec3>> {
    ((a.width, a.height) == (b.width, b.height)).then(|| Image {
        width: a.width,
        height: a.height,
        pixels: a
            .pixels
            .iter()
            .zip(&b.pixels)
            .map(|(&x, &y)| 0.5 * (x + y))
            .collect(),
    })
}

/// What [`corrected_relative_lrms`] measures.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CorrectedLrms {
    /// √max(0, mean (x − m)² − mean (a − b)²/4) / mean(m).
    pub corrected: f64,
    /// √mean (x − m)² / mean(m): the relative LRMS against the mean of the halves.
    pub uncorrected: f64,
    /// √(mean (a − b)²/4) / mean(m): the relative LRMS of the reference's own noise.
    pub noise_floor: f64,
    /// mean(x) / mean(m).
    pub mean_ratio: f64,
}

impl CorrectedLrms {
    /// Every field NaN (a missing or mismatched frame).
    pub const NAN: Self = CorrectedLrms {
        corrected: f64::NAN,
        uncorrected: f64::NAN,
        noise_floor: f64::NAN,
        mean_ratio: f64::NAN,
    };
}

/// Running sums of a test image's squared error against two reference halves, over any
/// set of pixels (luminance): [`corrected_relative_lrms`] over a whole frame, or a region of
/// one (a band along a shadow edge against the rest of a floor) with
/// [`ErrorSums::corrected_rms`] relative to a mean of one's choosing.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ErrorSums {
    /// Pixels added.
    pub count: usize,
    /// Σ (x − m)².
    pub squared_error: f64,
    /// Σ (a − b)²/4: the reference mean's variance, estimated.
    pub variance: f64,
    /// Σ m.
    pub reference: f64,
    /// Σ x.
    pub test: f64,
}

impl ErrorSums {
    /// Adds one pixel: test `x`, reference halves `a` and `b` (luminances).
    pub fn add(&mut self, x: f64, a: f64, b: f64) {
        let (squared_error, variance) = squared_error_terms(x, a, b);
        self.count += 1;
        self.squared_error += squared_error;
        self.variance += variance;
        self.reference += 0.5 * (a + b);
        self.test += x;
    }

    /// Adds one pixel of colours (their luminances).
    pub fn add_colours(&mut self, x: Vec3, a: Vec3, b: Vec3) {
        self.add(
            f64::from(luminance(x)),
            f64::from(luminance(a)),
            f64::from(luminance(b)),
        );
    }

    /// Mean reference luminance (NaN when empty).
    pub fn mean_reference(&self) -> f64 {
        self.reference / self.count as f64
    }

    /// √max(0, mean (x − m)² − mean (a − b)²/4): the RMS error with the reference's noise
    /// removed (NaN when empty).
    pub fn corrected_rms(&self) -> f64 {
        let n = self.count as f64;
        (self.squared_error / n - self.variance / n).max(0.0).sqrt()
    }

    /// √mean (x − m)²: the RMS error against the mean of the halves (NaN when empty).
    pub fn rms(&self) -> f64 {
        (self.squared_error / self.count as f64).sqrt()
    }

    /// √mean (a − b)²/4: the RMS of the reference's own noise (NaN when empty).
    pub fn noise_rms(&self) -> f64 {
        (self.variance / self.count as f64).sqrt()
    }

    /// The sums as [`CorrectedLrms`], relative to their own mean reference luminance (all NaN
    /// when empty or black).
    pub fn relative(&self) -> CorrectedLrms {
        let mean = self.mean_reference();
        if self.count == 0 || mean <= 0.0 || !mean.is_finite() {
            return CorrectedLrms::NAN;
        }
        CorrectedLrms {
            corrected: self.corrected_rms() / mean,
            uncorrected: self.rms() / mean,
            noise_floor: self.noise_rms() / mean,
            mean_ratio: self.test / self.reference,
        }
    }
}

/// One pixel's terms of the corrected error: test `x` against the mean m of halves `a` and
/// `b`, ((x − m)², (a − b)²/4).
#[inline]
fn squared_error_terms(x: f64, a: f64, b: f64) -> (f64, f64) {
    let m = 0.5 * (a + b);
    ((x - m) * (x - m), 0.25 * (a - b) * (a - b))
}

/// Whether `test` and both reference halves have one size and pixel count.
fn same_size(test: &Image<Vec3>, ref_a: &Image<Vec3>, ref_b: &Image<Vec3>) -> bool {
    let size = (test.width, test.height);
    size == (ref_a.width, ref_a.height)
        && size == (ref_b.width, ref_b.height)
        && test.pixels.len() == ref_a.pixels.len()
        && test.pixels.len() == ref_b.pixels.len()
}

/// Each pixel's variance-corrected squared luminance error, (x − m)² − (a − b)²/4: the terms
/// whose mean [`ErrorSums::corrected_rms`] takes the root of (negative where the reference's
/// noise is larger than the error). `None` when the sizes differ.
pub fn corrected_squared_errors(
    test: &Image<Vec3>,
    ref_a: &Image<Vec3>,
    ref_b: &Image<Vec3>,
) -> Option<Vec<f64>> {
    if !same_size(test, ref_a, ref_b) {
        return None;
    }
    let n = test.pixels.len();
    let lum = |c: Vec3| f64::from(luminance(c));
    Some(
        (0..n)
            .map(|i| {
                let (e, v) = squared_error_terms(
                    lum(test.pixels[i]),
                    lum(ref_a.pixels[i]),
                    lum(ref_b.pixels[i]),
                );
                e - v
            })
            .collect(),
    )
}

/// The relative LRMS of `test` against the noisy reference given as two independent halves
/// `ref_a` and `ref_b`, with the reference's variance estimated from |A − B|²/4 and
/// subtracted (see the module docs for the derivation). All NaN when the sizes differ or
/// the reference is black.
pub fn corrected_relative_lrms(
    test: &Image<Vec3>,
    ref_a: &Image<Vec3>,
    ref_b: &Image<Vec3>,
) -> CorrectedLrms {
    if !same_size(test, ref_a, ref_b) {
        return CorrectedLrms::NAN;
    }
    let mut sums = ErrorSums::default();
    for ((&x, &a), &b) in test.pixels.iter().zip(&ref_a.pixels).zip(&ref_b.pixels) {
        sums.add_colours(x, a, b);
    }
    sums.relative()
}

/// SSIM (Wang, Bovik, Sheikh and Simoncelli 2004) of `test` against `reference` as the PNG
/// frames display them ([`crate::frame_io::display`]: `exposure`, ACES, sRGB), reduced to
/// luma with MATLAB's `rgb2gray` weights on 0–255 (not rounded), and compared with MATLAB's
/// `ssim.m` (11 × 11 Gaussian window, σ = 1.5, K₁ = 0.01, K₂ = 0.03, L = 255) through the
/// `blazediff-ssim` crate. SSIM is a structural measure of the picture people see, so it is
/// taken on display values, not on radiance. [`compare_with`](crate::tools::compare_with)
/// passes each reference frame's [`auto_exposure`](crate::frame_io::auto_exposure).
///
/// It is not corrected for the reference's noise: against a noisy reference a perfect
/// image scores below 1. The SSIM of one reference half against the other shows how far.
/// NaN when the sizes differ or the frames are smaller than the window.
pub fn ssim(test: &Image<Vec3>, reference: &Image<Vec3>, exposure: f32) -> f64 {
    if (test.width, test.height) != (reference.width, reference.height)
        || test.pixels.len() != reference.pixels.len()
    {
        return f64::NAN;
    }
    let plane = |img: &Image<Vec3>| blazediff_ssim::Plane {
        samples: img
            .pixels
            .iter()
            .map(|&c| {
                let d = crate::frame_io::display(c, exposure);
                255.0 * (0.298_936 * d.x + 0.587_043 * d.y + 0.114_021 * d.z)
            })
            .collect(),
        width: img.width as usize,
        height: img.height as usize,
    };
    blazediff_ssim::ssim(
        &plane(test),
        &plane(reference),
        &blazediff_ssim::SsimOptions::default(),
    )
    .map_or(f64::NAN, |o| o.score)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Deterministic standard normal samples (xorshift + Box–Muller).
    struct Normal(u64);
    impl Normal {
        fn uniform(&mut self) -> f64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            ((self.0 >> 11) as f64 + 0.5) / (1u64 << 53) as f64
        }
        fn next(&mut self) -> f32 {
            let (u, v) = (self.uniform(), self.uniform());
            ((-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()) as f32
        }
    }

    const W: u32 = 512;
    const H: u32 = 384;

    /// A grey signal from 0.5 to 1.5 (mean 1): luminance = the grey value.
    fn signal() -> Image<Vec3> {
        Image::render(W, H, |x, y| {
            Vec3::splat(0.5 + (x as f32 / W as f32 + y as f32 / H as f32) * 0.5)
        })
    }

    /// `signal` plus independent grey noise of standard deviation `sigma` per pixel.
    fn noisy(signal: &Image<Vec3>, sigma: f32, seed: u64) -> Image<Vec3> {
        let mut n = Normal(seed);
        Image {
            width: signal.width,
            height: signal.height,
            pixels: signal
                .pixels
                .iter()
                .map(|&s| s + Vec3::splat(sigma * n.next()))
                .collect(),
        }
    }

    #[test]
    fn the_noise_of_the_reference_is_removed() {
        let s = signal();
        let sigma_half = 0.3;
        let (a, b) = (noisy(&s, sigma_half, 1), noisy(&s, sigma_half, 2));
        let m = corrected_relative_lrms(&s, &a, &b);
        // The mean of the halves has standard deviation σ/√2 ≈ 0.212 over a mean of 1.
        let floor = f64::from(sigma_half) / 2f64.sqrt();
        assert!((m.noise_floor - floor).abs() < 0.01 * floor, "{m:?}");
        assert!((m.uncorrected - floor).abs() < 0.02 * floor, "{m:?}");
        assert!(m.corrected < 0.04 && m.uncorrected > 0.2, "{m:?}");
        assert!((m.mean_ratio - 1.0).abs() < 0.005, "{m:?}");
        // The uncorrected figure is the tracer's relative LRMS against the mean.
        let mean = mean_image(&a, &b).unwrap();
        assert!((relative_lrms(&s, &mean) - m.uncorrected).abs() < 1e-9);
    }

    #[test]
    fn a_bias_is_given_back_despite_the_noise() {
        let s = signal();
        let (a, b) = (noisy(&s, 0.3, 3), noisy(&s, 0.3, 4));
        // A constant bias of 0.1 over a mean of 1: true relative LRMS 0.1.
        let biased = Image {
            width: W,
            height: H,
            pixels: s.pixels.iter().map(|&c| c + Vec3::splat(0.1)).collect(),
        };
        let m = corrected_relative_lrms(&biased, &a, &b);
        assert!((m.corrected - 0.1).abs() < 0.01, "{m:?}");
        assert!(m.uncorrected > 0.2, "noise dominates uncorrected: {m:?}");
        assert!((m.mean_ratio - 1.1).abs() < 0.005, "{m:?}");
        // A test image as noisy as a third independent half: the correction removes only
        // the reference's share, leaving the test's own noise (σ = 0.3 over mean 1).
        let m = corrected_relative_lrms(&noisy(&s, 0.3, 5), &a, &b);
        assert!((m.corrected - 0.3).abs() < 0.015, "{m:?}");
    }

    #[test]
    fn error_sums_measure_a_region_of_a_frame() {
        let s = signal();
        let (a, b) = (noisy(&s, 0.3, 11), noisy(&s, 0.3, 12));
        // A bias of 0.2 in the left half only: that half's corrected RMS is 0.2, the other's
        // near zero, though both are equally noisy against the reference.
        let (mut left, mut right) = (ErrorSums::default(), ErrorSums::default());
        for (j, ((&x, &pa), &pb)) in s.pixels.iter().zip(&a.pixels).zip(&b.pixels).enumerate() {
            if (j as u32 % W) < W / 2 {
                left.add_colours(x + Vec3::splat(0.2), pa, pb);
            } else {
                right.add_colours(x, pa, pb);
            }
        }
        assert!((left.corrected_rms() - 0.2).abs() < 0.02, "{left:?}");
        assert!(
            right.corrected_rms() < 0.05 && right.rms() > 0.2,
            "{right:?}"
        );
        assert!(
            (right.relative().mean_ratio - 1.0).abs() < 0.01,
            "{right:?}"
        );
        assert!(ErrorSums::default().relative().corrected.is_nan());
    }

    #[test]
    fn ssim_is_one_for_equal_frames_and_falls_with_noise_and_lost_structure() {
        let s = signal();
        let e = crate::frame_io::auto_exposure(&s.pixels);
        assert!((ssim(&s, &s, e) - 1.0).abs() < 1e-9);
        let light = ssim(&noisy(&s, 0.02, 7), &s, e);
        let heavy = ssim(&noisy(&s, 0.2, 8), &s, e);
        assert!(light < 1.0 && heavy < light, "{light} {heavy}");
        assert!(heavy < 0.6 && light > 0.9, "{light} {heavy}");
        // Stripes 4 pixels wide and their mean: equal mean luminance, no structure left.
        // (Wider than 1 pixel: like MATLAB, the crate low-passes and halves frames whose
        // short side is above 384 before comparing.)
        let stripes = Image::render(W, H, |x, _| {
            Vec3::splat(if (x / 4) % 2 == 0 { 0.5 } else { 1.5 })
        });
        let flat = Image::render(W, H, |_, _| Vec3::ONE);
        assert!(
            ssim(
                &flat,
                &stripes,
                crate::frame_io::auto_exposure(&stripes.pixels)
            ) < 0.2
        );
        // Sizes that differ, or a frame smaller than the 11-pixel window.
        let small = Image::render(8, 8, |_, _| Vec3::ONE);
        assert!(ssim(&small, &s, e).is_nan());
        assert!(ssim(&small, &small, 1.0).is_nan());
    }

    #[test]
    fn mismatched_or_black_references_give_nan() {
        let s = signal();
        let small = Image::render(4, 4, |_, _| Vec3::ONE);
        assert!(corrected_relative_lrms(&small, &s, &s).corrected.is_nan());
        let black = Image::render(W, H, |_, _| Vec3::ZERO);
        assert!(
            corrected_relative_lrms(&s, &black, &black)
                .corrected
                .is_nan()
        );
        assert!(mean_luminance_ratio(&s, &black).is_nan());
        assert_eq!(corrected_relative_lrms(&s, &s, &s).corrected, 0.0);
    }
}
