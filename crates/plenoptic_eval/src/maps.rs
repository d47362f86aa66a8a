//! Pictures of where a candidate's error lies, per frame.
//!
//! - **Low-frequency maps** ([`write_low_frequency_maps`], [`crate::low_frequency`]): the
//!   signed difference (G∗x − G∗m) / mean(G∗m) of the candidate's blurred luminance from the
//!   reference's, red where the candidate is brighter, blue where it is darker, saturated at
//!   ±[`MAP_FULL_SCALE`]. Blotches, halos and dim patches show as coloured areas; the
//!   reference's pixel noise is blurred away, so the map shows the candidate's error, not the
//!   reference's.
//! - **Error maps** ([`write_error_maps`]): each pixel's variance-corrected squared error
//!   ([`crate::metrics::corrected_squared_errors`], the terms the corrected relative LRMS
//!   averages), over mean(m)², averaged over 3 × 3 pixels, red at [`ERROR_FULL_SCALE`]. The
//!   corrected LRMS weighs a pixel by its squared error, so a few bright pixels (a lamp, the
//!   sky in a window) can hold most of a frame's figure: the map and the frame's
//!   [`Concentration`] show where.

use std::path::{Path, PathBuf};

use glam::Vec3;
use plenoptic_trace::Image;

use crate::low_frequency::{difference_colour, low_frequency_difference};
use crate::metrics::{corrected_squared_errors, mean_image};
use crate::tools::{exr_frames, frame_name, read_image};
use crate::{EvalError, Result};

/// The relative difference a low-frequency map shows at full colour: 20 % of the frame's mean.
pub const MAP_FULL_SCALE: f64 = 0.2;

/// The squared error an error map shows at full red: the frame's mean luminance squared (a
/// pixel off by the frame's mean).
pub const ERROR_FULL_SCALE: f64 = 1.0;

/// The side, in pixels, of the tiles [`Concentration`] compares.
pub const TILE: u32 = 8;

/// How much of a frame's corrected squared error lies in its worst [`TILE`] × [`TILE`] tile.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Concentration {
    /// The tile's share of the frame's summed corrected squared error (1 and more where the
    /// rest of the frame is below the reference's noise).
    pub share: f64,
    /// The tile's top-left pixel.
    pub x: u32,
    /// The tile's top-left pixel.
    pub y: u32,
}

/// One candidate frame beside its reference: the label, the frame index, the candidate's
/// path and image, and the reference halves (the second where given).
struct Pair<'a> {
    label: &'a str,
    index: usize,
    path: PathBuf,
    candidate: Image<Vec3>,
    a: &'a Image<Vec3>,
    b: Option<&'a Image<Vec3>>,
}

/// Calls `f` for every candidate frame that the reference has (frames a candidate lacks are
/// skipped); a frame that cannot be read is an error naming its file.
fn for_each_pair(
    reference_a: &Path,
    reference_b: Option<&Path>,
    candidates: &[(String, PathBuf)],
    mut f: impl FnMut(Pair<'_>) -> Result<()>,
) -> Result<()> {
    for (index, apath) in exr_frames(reference_a)? {
        let a = read_image(&apath)?;
        let b = match reference_b {
            Some(dir) => Some(read_image(&dir.join(frame_name(index, "exr")))?),
            None => None,
        };
        for (label, dir) in candidates {
            let path = dir.join(frame_name(index, "exr"));
            if !path.exists() {
                continue;
            }
            let candidate = read_image(&path)?;
            f(Pair {
                label,
                index,
                path,
                candidate,
                a: &a,
                b: b.as_ref(),
            })?;
        }
    }
    Ok(())
}

fn size_error(pair: &Pair<'_>) -> EvalError {
    let (c, r) = (&pair.candidate, pair.a);
    EvalError::invalid(
        &pair.path,
        format!(
            "{}×{}, the reference {}×{} (or the reference is black)",
            c.width, c.height, r.width, r.height
        ),
    )
}

fn save_png(path: &Path, bytes: &[u8], width: u32, height: u32) -> Result<()> {
    image::save_buffer(path, bytes, width, height, image::ExtendedColorType::Rgb8).map_err(|e| {
        EvalError::Png {
            path: path.to_path_buf(),
            message: e.to_string(),
        }
    })
}

/// Writes `out/<label>_frame_NNNNN.png`, the low-frequency difference map of each candidate's
/// frame from the reference's (`reference_a`, or the mean of it and `reference_b`). Frames a
/// candidate lacks are skipped; one that cannot be read, or whose size differs from the
/// reference's, is an error naming its file. Returns the number of maps written.
pub fn write_low_frequency_maps(
    reference_a: &Path,
    reference_b: Option<&Path>,
    candidates: &[(String, PathBuf)],
    out: &Path,
) -> Result<usize> {
    std::fs::create_dir_all(out).map_err(|e| EvalError::io(out, e))?;
    let mut written = 0;
    for_each_pair(reference_a, reference_b, candidates, |pair| {
        let reference = match pair.b {
            Some(b) => mean_image(pair.a, b)
                .ok_or_else(|| EvalError::invalid(&pair.path, "the reference's halves differ"))?,
            None => pair.a.clone(),
        };
        let d = low_frequency_difference(&pair.candidate, &reference)
            .ok_or_else(|| size_error(&pair))?;
        let bytes: Vec<u8> = d
            .iter()
            .flat_map(|&v| difference_colour(v, MAP_FULL_SCALE))
            .collect();
        let path = out.join(format!("{}_{}", pair.label, frame_name(pair.index, "png")));
        save_png(&path, &bytes, pair.candidate.width, pair.candidate.height)?;
        written += 1;
        Ok(())
    })?;
    Ok(written)
}

/// Writes `out/<label>_error_frame_NNNNN.png`, the error map of each candidate's frame
/// against the reference's halves (without `reference_b`, half A serves as both, and the
/// map shows the uncorrected squared error). Frames a candidate lacks are skipped; one that
/// cannot be read, or whose size differs, is an error naming its file. Returns, per map
/// written, the candidate's label, the frame index and the frame's [`Concentration`].
pub fn write_error_maps(
    reference_a: &Path,
    reference_b: Option<&Path>,
    candidates: &[(String, PathBuf)],
    out: &Path,
) -> Result<Vec<(String, usize, Concentration)>> {
    std::fs::create_dir_all(out).map_err(|e| EvalError::io(out, e))?;
    let mut written = Vec::new();
    for_each_pair(reference_a, reference_b, candidates, |pair| {
        let (c, a) = (&pair.candidate, pair.a);
        let b = pair.b.unwrap_or(a);
        let errors = corrected_squared_errors(c, a, b).ok_or_else(|| size_error(&pair))?;
        // The mean of the halves' means: the reference mean's mean luminance.
        let mean = 0.5 * (a.mean_luminance() + b.mean_luminance());
        if mean <= 0.0 || !mean.is_finite() {
            return Err(size_error(&pair));
        }
        let scale = 1.0 / (mean * mean);
        let bytes: Vec<u8> = box3(&errors, c.width, c.height)
            .iter()
            .flat_map(|&e| difference_colour(e * scale, ERROR_FULL_SCALE))
            .collect();
        let name = format!("{}_error_{}", pair.label, frame_name(pair.index, "png"));
        save_png(&out.join(name), &bytes, c.width, c.height)?;
        if let Some(worst) = concentration(&errors, c.width, c.height) {
            written.push((pair.label.to_string(), pair.index, worst));
        }
        Ok(())
    })?;
    Ok(written)
}

/// The mean of each pixel's 3 × 3 neighbourhood (clipped at the borders).
fn box3(v: &[f64], width: u32, height: u32) -> Vec<f64> {
    let (w, h) = (width as usize, height as usize);
    let mut out = vec![0.0; v.len()];
    for y in 0..h {
        for x in 0..w {
            let (mut sum, mut n) = (0.0, 0.0);
            for yy in y.saturating_sub(1)..(y + 2).min(h) {
                for xx in x.saturating_sub(1)..(x + 2).min(w) {
                    sum += v[yy * w + xx];
                    n += 1.0;
                }
            }
            out[y * w + x] = sum / n;
        }
    }
    out
}

/// The worst [`TILE`]-pixel tile of `errors` (a `width` × `height` frame) and its share of
/// the sum; `None` where the sum is not positive (no error above the reference's noise).
pub fn concentration(errors: &[f64], width: u32, height: u32) -> Option<Concentration> {
    let total: f64 = errors.iter().sum();
    if total <= 0.0 || errors.len() != width as usize * height as usize {
        return None;
    }
    let mut worst: Option<Concentration> = None;
    for y in (0..height).step_by(TILE as usize) {
        for x in (0..width).step_by(TILE as usize) {
            let sum: f64 = (y..(y + TILE).min(height))
                .flat_map(|yy| (x..(x + TILE).min(width)).map(move |xx| (yy, xx)))
                .map(|(yy, xx)| errors[(yy * width + xx) as usize])
                .sum();
            let share = sum / total;
            if worst.is_none_or(|w| share > w.share) {
                worst = Some(Concentration { share, x, y });
            }
        }
    }
    worst
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_worst_tile_holds_a_spots_share() {
        // A 32 × 16 frame: error 1 everywhere, 61 more on 4 pixels of the tile at (16, 8).
        let (w, h) = (32u32, 16u32);
        let mut e = vec![1.0; (w * h) as usize];
        for (x, y) in [(17, 9), (18, 9), (17, 10), (23, 15)] {
            e[(y * w + x) as usize] += 61.0;
        }
        let c = concentration(&e, w, h).unwrap();
        assert_eq!((c.x, c.y), (16, 8));
        let expected = (64.0 + 4.0 * 61.0) / (512.0 + 4.0 * 61.0);
        assert!((c.share - expected).abs() < 1e-12, "{}", c.share);
        assert!(concentration(&vec![0.0; 512], w, h).is_none());
    }

    #[test]
    fn the_box_filter_keeps_a_constant_and_spreads_a_spike() {
        let b = box3(&[2.0; 12], 4, 3);
        assert!(b.iter().all(|&v| (v - 2.0).abs() < 1e-12));
        let mut v = vec![0.0; 9];
        v[4] = 9.0;
        assert!(box3(&v, 3, 3).iter().all(|&x| x > 0.9));
    }
}
