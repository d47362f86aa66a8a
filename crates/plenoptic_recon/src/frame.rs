//! Reconstructed frames and what their reconstruction reports.

use glam::Vec3;
use serde::{Deserialize, Serialize};

/// A reconstructed frame: linear HDR radiance, depth (distance from the eye along each pixel's
/// ray, metres; ∞ where nothing was reconstructed) so that an engine can composite other
/// geometry with it, and the object id per pixel (the pack's ids; 0: none).
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// Width, pixels.
    pub width: u32,
    /// Height, pixels.
    pub height: u32,
    /// Linear radiance, row-major from the top row.
    pub radiance: Vec<Vec3>,
    /// Distance from the eye along the pixel's ray.
    pub depth: Vec<f32>,
    /// Object id.
    pub object: Vec<u32>,
}

impl Frame {
    /// A black, empty frame.
    pub fn new(width: u32, height: u32) -> Self {
        let n = width as usize * height as usize;
        Frame {
            width,
            height,
            radiance: vec![Vec3::ZERO; n],
            depth: vec![f32::INFINITY; n],
            object: vec![0; n],
        }
    }
}

/// `fine`, a frame of n × n samples per pixel, filtered to one value per pixel: the mean
/// radiance over each pixel's samples (a box filter over its area), and the depth and object
/// id of the sample nearest its centre. `fine`'s size must be a multiple of n.
pub(crate) fn box_filter(fine: &Frame, n: u32) -> Frame {
    let (w, h) = (fine.width / n, fine.height / n);
    let mut out = Frame::new(w, h);
    let centre = (n / 2) as usize;
    let n = n as usize;
    let scale = 1.0 / (n * n) as f32;
    let fw = fine.width as usize;
    for y in 0..h as usize {
        for x in 0..w as usize {
            let mut sum = Vec3::ZERO;
            for sy in 0..n {
                let row = (y * n + sy) * fw + x * n;
                sum += fine.radiance[row..row + n].iter().copied().sum::<Vec3>();
            }
            let i = y * w as usize + x;
            let c = (y * n + centre) * fw + x * n + centre;
            out.radiance[i] = sum * scale;
            out.depth[i] = fine.depth[c];
            out.object[i] = fine.object[c];
        }
    }
    out
}

/// The reconstruction modes (docs/architecture.md, "Reconstruction").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Mode {
    /// Range images blended in time (A.1), warped by depth (A.2): the thesis's first system.
    Image,
    /// Temporal volumes filtered and triangulated at t, warped by depth: its second system.
    Volume,
    /// Geometry mask + lookups through the objects' motion (thesis §8.2.3): the default.
    #[default]
    GeometryAssisted,
}

impl Mode {
    /// Every mode.
    pub const ALL: [Mode; 3] = [Mode::Image, Mode::Volume, Mode::GeometryAssisted];

    /// A short lowercase name (`image`, `volume`, `geometry`).
    pub fn name(self) -> &'static str {
        match self {
            Mode::Image => "image",
            Mode::Volume => "volume",
            Mode::GeometryAssisted => "geometry",
        }
    }

    /// Parses [`Mode::name`] (also `geometry_assisted`).
    pub fn parse(s: &str) -> Option<Self> {
        match s.to_ascii_lowercase().as_str() {
            "image" => Some(Mode::Image),
            "volume" => Some(Mode::Volume),
            "geometry" | "geometry_assisted" | "geometry-assisted" => Some(Mode::GeometryAssisted),
            _ => None,
        }
    }
}

/// Fractions of the frame's pixels (summing to 1) by how they were reconstructed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct FallbackReport {
    /// From range images: accepted lookups (geometry-assisted) or splats (image, volume).
    pub direct: f32,
    /// From temporal-volume samples (geometry-assisted fallback; all covered pixels in volume
    /// mode).
    pub volume: f32,
    /// Filled from neighbours: same-object fill in screen space, then the object's own texels
    /// around the lookups (geometry-assisted), or background fill (image, volume).
    pub hole_fill: f32,
    /// Nothing matched: the nearest base view's cube along the pixel's direction, or black.
    pub background: f32,
    /// Pixels where the geometry mask shows no proxy geometry (environment lookups).
    pub no_geometry: f32,
}

impl FallbackReport {
    /// Fractions from pixel counts.
    pub fn from_counts(
        direct: usize,
        volume: usize,
        hole_fill: usize,
        background: usize,
        no_geometry: usize,
    ) -> Self {
        let n = (direct + volume + hole_fill + background + no_geometry).max(1) as f32;
        FallbackReport {
            direct: direct as f32 / n,
            volume: volume as f32 / n,
            hole_fill: hole_fill as f32 / n,
            background: background as f32 / n,
            no_geometry: no_geometry as f32 / n,
        }
    }
}

/// What a frame's reconstruction did and what it lacked.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Report {
    /// The mode asked for.
    pub mode: Mode,
    /// The mode actually used (e.g. image mode when the pack has no proxy geometry).
    pub used_mode: Mode,
    /// How pixels were reconstructed.
    pub fallback: FallbackReport,
    /// Base views used and their view-space weights.
    pub base_views: Vec<(usize, f32)>,
    /// Every chunk that was needed but missing or unreadable, with the reason.
    pub missing: Vec<String>,
    /// Volume mode: how many base views' cubes were sliced from the baked (x, y, t) complex
    /// (the others were triangulated per cube face at t, or came from range images).
    #[serde(default)]
    pub volume_complex_blocks: usize,
    /// Geometry-assisted mode: pixels where see-through glazing was composited over what
    /// lies behind it (`plenoptic_recon`'s glazing module).
    #[serde(default)]
    pub glazing_pixels: usize,
    /// Geometry-assisted mode: pixels whose specular reflection was marched for the camera
    /// (`plenoptic_recon::specular`), and of those, how many no base view could answer
    /// (they show the baked non-diffuse radiance).
    #[serde(default)]
    pub reflections: (usize, usize),
    /// Geometry-assisted mode with materials: pixels whose lighting was interpolated between
    /// the lookups around them instead of looked up (`ReconSettings::sparse_lighting`).
    #[serde(default)]
    pub interpolated_pixels: usize,
    /// Wall-clock milliseconds of the stages of the reconstruction (diagnostics).
    pub stage_ms: Vec<(String, f64)>,
}

impl Report {
    /// True when something needed was missing.
    pub fn degraded(&self) -> bool {
        !self.missing.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_filter_averages_each_pixels_samples_and_keeps_the_centre_sample_id() {
        // 4 × 2 samples, 2 × 2 per pixel: a bright edge covering a quarter of the left pixel.
        let mut fine = Frame::new(4, 2);
        fine.radiance[0] = Vec3::splat(8.0);
        for (i, (d, o)) in fine.depth.iter_mut().zip(&mut fine.object).enumerate() {
            *d = i as f32;
            *o = i as u32 + 10;
        }
        fine.radiance[2] = Vec3::new(1.0, 2.0, 3.0);
        fine.radiance[7] = Vec3::new(3.0, 2.0, 1.0);
        let out = box_filter(&fine, 2);
        assert_eq!((out.width, out.height), (2, 1));
        assert!((out.radiance[0] - Vec3::splat(2.0)).abs().max_element() < 1e-6);
        assert!((out.radiance[1] - Vec3::splat(1.0)).abs().max_element() < 1e-6);
        // The sample nearest each pixel's centre: (1, 1) of the 2 × 2 block.
        assert_eq!(out.object, vec![15, 17]);
        assert_eq!(out.depth, vec![5.0, 7.0]);
    }
}
