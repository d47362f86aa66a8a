//! Pictures of where a candidate's low-frequency error lies ([`crate::low_frequency`]): per
//! frame, the signed difference (G∗x − G∗m) / mean(G∗m) of its blurred luminance from the
//! reference's, red where the candidate is brighter, blue where it is darker, saturated at
//! ±[`MAP_FULL_SCALE`]. Blotches, halos and dim patches show as coloured areas; the
//! reference's pixel noise is blurred away, so the map shows the candidate's error, not the
//! reference's.

use std::path::{Path, PathBuf};

use crate::low_frequency::{difference_colour, low_frequency_difference};
use crate::metrics::mean_image;
use crate::tools::{exr_frames, frame_name, read_image};
use crate::{EvalError, Result};

/// The relative difference a map shows at full colour: 20 % of the frame's mean.
pub const MAP_FULL_SCALE: f64 = 0.2;

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
    for (idx, apath) in exr_frames(reference_a)? {
        let a = read_image(&apath)?;
        let reference = match reference_b {
            Some(dir) => {
                let b = read_image(&dir.join(frame_name(idx, "exr")))?;
                mean_image(&a, &b)
                    .ok_or_else(|| EvalError::invalid(&apath, "its second half differs in size"))?
            }
            None => a,
        };
        for (label, dir) in candidates {
            let cpath = dir.join(frame_name(idx, "exr"));
            if !cpath.exists() {
                continue;
            }
            let c = read_image(&cpath)?;
            let d = low_frequency_difference(&c, &reference).ok_or_else(|| {
                EvalError::invalid(
                    &cpath,
                    format!(
                        "{}×{}, the reference {}×{} (or the reference is black)",
                        c.width, c.height, reference.width, reference.height
                    ),
                )
            })?;
            let bytes: Vec<u8> = d
                .iter()
                .flat_map(|&v| difference_colour(v, MAP_FULL_SCALE))
                .collect();
            let path = out.join(format!("{label}_{}", frame_name(idx, "png")));
            image::save_buffer(
                &path,
                &bytes,
                c.width,
                c.height,
                image::ExtendedColorType::Rgb8,
            )
            .map_err(|e| EvalError::Png {
                path: path.clone(),
                message: e.to_string(),
            })?;
            written += 1;
        }
    }
    Ok(written)
}
