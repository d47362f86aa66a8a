//! The quality tools behind the `plenoptic render` and `plenoptic compare` commands
//! (docs/architecture.md, "Measuring"). They need nothing but paths and options.
//!
//! Frame files in a frame directory are named `frame_NNNNN.exr` (linear radiance and depth,
//! see [`crate::frame_io`]) and `frame_NNNNN.png` (tonemapped), `NNNNN` the frame index of the
//! camera path ([`plenoptic_recon::path`]). The reference renderer writes its frames with the
//! same names through [`write_frame_files`], so [`compare`] can pair them.
//!
//! [`compare_with`] takes the reference as two independent halves (`plenoptic reference
//! --halves` writes `DIR` and `DIR_b`) and reports the variance-corrected relative LRMS
//! beside the uncorrected one, the reference's noise floor, PSNR, SSIM and the mean-luminance
//! ratio ([`crate::metrics`]).

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

use glam::Vec3;
use plenoptic_recon::{CameraPath, Mode, Reconstructor, Report};
use plenoptic_trace::Image;

use crate::frame_io::{auto_exposure, read_exr, write_exr, write_png};
use crate::low_frequency::low_frequency_error;
use crate::metrics::{
    CorrectedLrms, corrected_relative_lrms, mean_image, mean_luminance_ratio, psnr, relative_lrms,
    ssim,
};
use crate::{EvalError, Result};

/// Options of [`render_path_with`].
#[derive(Clone, Debug, PartialEq)]
pub struct RenderOptions {
    /// Reconstruction mode.
    pub mode: Mode,
    /// PNG exposure; `None`: [`auto_exposure`] of the first frame, kept for the whole path.
    pub exposure: Option<f32>,
    /// Write `frame_NNNNN.png`.
    pub png: bool,
    /// Write `frame_NNNNN.exr`.
    pub exr: bool,
    /// Print one line per frame to stderr.
    pub progress: bool,
    /// `Some(n)`: `n` frames spread evenly over the whole path ([`CameraPath::spread`], the
    /// tour's results' frames) instead of every frame at the path's frame rate.
    pub frames: Option<usize>,
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            mode: Mode::GeometryAssisted,
            exposure: None,
            png: true,
            exr: true,
            progress: false,
            frames: None,
        }
    }
}

/// What [`render_path`] did.
#[derive(Clone, Debug, Default)]
pub struct RenderSummary {
    /// Frames written.
    pub frames: usize,
    /// Mean milliseconds per frame (reconstruction only, not file writing).
    pub mean_ms: f64,
    /// The exposure used for PNGs.
    pub exposure: f32,
    /// Per-frame reports.
    pub reports: Vec<Report>,
    /// The per-frame report CSV.
    pub report_csv: PathBuf,
}

/// The file name of frame `index` with extension `ext`.
pub fn frame_name(index: usize, ext: &str) -> String {
    format!("frame_{index:05}.{ext}")
}

/// Writes `frame_NNNNN.exr` (linear, with depth if given) and `frame_NNNNN.png` (tonemapped
/// with `exposure`) into `dir`.
pub fn write_frame_files(
    dir: &Path,
    index: usize,
    width: u32,
    height: u32,
    radiance: &[Vec3],
    depth: Option<&[f32]>,
    exposure: f32,
) -> Result<()> {
    write_exr(
        dir.join(frame_name(index, "exr")),
        width,
        height,
        radiance,
        depth,
    )?;
    write_png(
        dir.join(frame_name(index, "png")),
        width,
        height,
        radiance,
        exposure,
    )
}

/// Renders every frame of the camera path file `camera_path` from the pack `pack` in `mode`
/// into `out_dir` (created if needed): EXR + PNG per frame and `report.csv`.
pub fn render_path(
    pack: &Path,
    camera_path: &Path,
    mode: Mode,
    out_dir: &Path,
    progress: bool,
) -> Result<RenderSummary> {
    let path = CameraPath::load(camera_path)?;
    let rec = Reconstructor::open(pack)?;
    render_path_with(
        &rec,
        &path,
        out_dir,
        &RenderOptions {
            mode,
            progress,
            ..RenderOptions::default()
        },
    )
}

/// [`render_path`] with an open reconstructor, a parsed path and options.
pub fn render_path_with(
    rec: &Reconstructor,
    path: &CameraPath,
    out_dir: &Path,
    options: &RenderOptions,
) -> Result<RenderSummary> {
    std::fs::create_dir_all(out_dir).map_err(|e| EvalError::io(out_dir, e))?;
    let csv_path = out_dir.join("report.csv");
    let mut csv = String::from(
        "frame,path_time,scene_time,ms,direct,volume,hole_fill,background,no_geometry,missing\n",
    );
    let mut summary = RenderSummary {
        report_csv: csv_path.clone(),
        ..RenderSummary::default()
    };
    let mut total_ms = 0.0;
    let mut exposure = options.exposure;
    let samples: Vec<_> = match options.frames {
        Some(n) => path.spread(n),
        None => path.frames().collect(),
    };
    let count = samples.len();
    for s in samples {
        let start = Instant::now();
        let (frame, report) = rec.render(&s.camera, s.scene_time, options.mode)?;
        let ms = start.elapsed().as_secs_f64() * 1e3;
        total_ms += ms;
        let e = *exposure.get_or_insert_with(|| auto_exposure(&frame.radiance));
        if options.exr {
            write_exr(
                out_dir.join(frame_name(s.index, "exr")),
                frame.width,
                frame.height,
                &frame.radiance,
                Some(&frame.depth),
            )?;
        }
        if options.png {
            write_png(
                out_dir.join(frame_name(s.index, "png")),
                frame.width,
                frame.height,
                &frame.radiance,
                e,
            )?;
        }
        let f = report.fallback;
        csv.push_str(&format!(
            "{},{},{},{ms:.3},{},{},{},{},{},{}\n",
            s.index,
            s.path_time,
            s.scene_time,
            f.direct,
            f.volume,
            f.hole_fill,
            f.background,
            f.no_geometry,
            report.missing.len()
        ));
        if options.progress {
            #[expect(clippy::print_stderr, reason = "progress output was asked for")]
            {
                eprintln!(
                    "frame {}/{count}: {ms:.1} ms, direct {:.1}%{}",
                    s.index + 1,
                    f.direct * 100.0,
                    if report.degraded() { " (degraded)" } else { "" }
                );
            }
        }
        summary.reports.push(report);
        summary.frames += 1;
    }
    summary.mean_ms = total_ms / summary.frames.max(1) as f64;
    summary.exposure = exposure.unwrap_or(1.0);
    std::fs::write(&csv_path, csv).map_err(|e| EvalError::io(&csv_path, e))?;
    Ok(summary)
}

/// Per-frame metrics of one candidate (NaN where the candidate frame is missing or does not
/// match the reference's size).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CandidateMetrics {
    /// The candidate's label.
    pub label: String,
    /// Relative LRMS per reference frame, uncorrected (against the mean of the halves when
    /// the reference has two).
    pub relative_lrms: Vec<f64>,
    /// Variance-corrected relative LRMS per frame (empty without a second reference half).
    pub corrected_lrms: Vec<f64>,
    /// PSNR (dB) per reference frame.
    pub psnr: Vec<f64>,
    /// Mean luminance of the candidate over the reference's, per frame.
    pub mean_ratio: Vec<f64>,
    /// SSIM of the displayed frames per reference frame ([`ssim`], at the reference frame's
    /// [`auto_exposure`]).
    pub ssim: Vec<f64>,
    /// Low-frequency relative error per frame ([`low_frequency_error`]: both luminances
    /// blurred with a Gaussian of σ = 2 % of the width), against the reference's mean.
    pub low_frequency: Vec<f64>,
}

fn finite_mean(v: &[f64]) -> f64 {
    let f: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    if f.is_empty() {
        f64::NAN
    } else {
        f.iter().sum::<f64>() / f.len() as f64
    }
}

impl CandidateMetrics {
    /// Mean uncorrected relative LRMS over the frames present.
    pub fn mean_lrms(&self) -> f64 {
        finite_mean(&self.relative_lrms)
    }

    /// Mean variance-corrected relative LRMS over the frames present (NaN without one).
    pub fn mean_corrected_lrms(&self) -> f64 {
        finite_mean(&self.corrected_lrms)
    }

    /// Mean PSNR over the frames present.
    pub fn mean_psnr(&self) -> f64 {
        finite_mean(&self.psnr)
    }

    /// Mean of the per-frame mean-luminance ratios over the frames present.
    pub fn mean_ratio(&self) -> f64 {
        finite_mean(&self.mean_ratio)
    }

    /// Mean SSIM over the frames present.
    pub fn mean_ssim(&self) -> f64 {
        finite_mean(&self.ssim)
    }

    /// Mean low-frequency relative error over the frames present.
    pub fn mean_low_frequency(&self) -> f64 {
        finite_mean(&self.low_frequency)
    }
}

/// What [`compare_with`] measured.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Comparison {
    /// Frame indices of the reference.
    pub frames: Vec<usize>,
    /// Per candidate, in the order given.
    pub candidates: Vec<CandidateMetrics>,
    /// Relative LRMS of the reference's own noise per frame (√(mean |A − B|²/4) / mean),
    /// with two reference halves.
    pub noise_floor: Option<Vec<f64>>,
    /// SSIM of reference half A against half B per frame, with two halves: how far below 1
    /// the reference's own noise puts SSIM.
    pub halves_ssim: Option<Vec<f64>>,
    /// The plot files written (SVG, PNG).
    pub plots: Vec<PathBuf>,
}

impl Comparison {
    /// Mean noise floor over the frames (NaN without two halves).
    pub fn mean_noise_floor(&self) -> f64 {
        self.noise_floor.as_deref().map_or(f64::NAN, finite_mean)
    }

    /// The comparison as a table (one row per candidate: means over the frames), for
    /// printing.
    pub fn table(&self) -> String {
        let corrected = self.noise_floor.is_some();
        let mut out = String::new();
        if corrected {
            out.push_str(&format!(
                "{:<16} {:>10} {:>12} {:>9} {:>7} {:>10} {:>9}\n",
                "candidate",
                "corrected",
                "uncorrected",
                "PSNR dB",
                "SSIM",
                "mean ratio",
                "low-freq"
            ));
        } else {
            out.push_str(&format!(
                "{:<16} {:>12} {:>9} {:>7} {:>10} {:>9}\n",
                "candidate", "rel. LRMS", "PSNR dB", "SSIM", "mean ratio", "low-freq"
            ));
        }
        for m in &self.candidates {
            if corrected {
                out.push_str(&format!(
                    "{:<16} {:>10.4} {:>12.4} {:>9.2} {:>7.4} {:>10.4} {:>9.4}\n",
                    m.label,
                    m.mean_corrected_lrms(),
                    m.mean_lrms(),
                    m.mean_psnr(),
                    m.mean_ssim(),
                    m.mean_ratio(),
                    m.mean_low_frequency()
                ));
            } else {
                out.push_str(&format!(
                    "{:<16} {:>12.4} {:>9.2} {:>7.4} {:>10.4} {:>9.4}\n",
                    m.label,
                    m.mean_lrms(),
                    m.mean_psnr(),
                    m.mean_ssim(),
                    m.mean_ratio(),
                    m.mean_low_frequency()
                ));
            }
        }
        if corrected {
            out.push_str(&format!(
                "reference noise floor (relative LRMS of (A − B)/2): {:.4}; SSIM of A against B: \
                 {:.4}\n",
                self.mean_noise_floor(),
                self.halves_ssim.as_deref().map_or(f64::NAN, finite_mean)
            ));
        }
        out
    }
}

pub(crate) fn exr_frames(dir: &Path) -> Result<Vec<(usize, PathBuf)>> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).map_err(|e| EvalError::io(dir, e))? {
        let p = e.map_err(|e| EvalError::io(dir, e))?.path();
        let name = p.file_name().and_then(|n| n.to_str()).unwrap_or("");
        if let Some(idx) = name
            .strip_prefix("frame_")
            .and_then(|r| r.strip_suffix(".exr"))
            .and_then(|i| i.parse().ok())
        {
            out.push((idx, p));
        }
    }
    out.sort();
    Ok(out)
}

pub(crate) fn read_image(path: &Path) -> Result<Image<Vec3>> {
    let (width, height, pixels) = read_exr(path)?;
    Ok(Image {
        width,
        height,
        pixels,
    })
}

/// [`compare_with`] against a single reference directory; returns the candidates' metrics.
pub fn compare(
    reference_dir: &Path,
    candidates: &[(String, PathBuf)],
    out_csv: &Path,
    out_plot: &Path,
) -> Result<Vec<CandidateMetrics>> {
    Ok(compare_with(reference_dir, None, candidates, out_csv, out_plot)?.candidates)
}

/// Compares each candidate frame directory with the reference frame by frame.
///
/// The reference is `reference_a`, or with `reference_b` (an independent second half with
/// the same frame names) the mean (A + B)/2, with the variance-corrected relative LRMS
/// ([`corrected_relative_lrms`]) and the noise floor. Writes per-frame metrics to `out_csv`
/// (columns `frame`, `noise_floor`, `halves_ssim`, then per candidate
/// `<label>_lrms_corrected`, `<label>_lrms`, `<label>_psnr`, `<label>_mean_ratio`,
/// `<label>_ssim`, `<label>_low_frequency`; the noise floor, the halves' SSIM and the corrected column only with two
/// halves) and the error-along-path plot (corrected relative LRMS with two halves, plus the
/// noise floor; otherwise uncorrected) as `<out_plot stem>.svg` and `.png`.
pub fn compare_with(
    reference_a: &Path,
    reference_b: Option<&Path>,
    candidates: &[(String, PathBuf)],
    out_csv: &Path,
    out_plot: &Path,
) -> Result<Comparison> {
    let refs = exr_frames(reference_a)?;
    if refs.is_empty() {
        return Err(EvalError::invalid(reference_a, "no frame_NNNNN.exr files"));
    }
    let halves = reference_b.is_some();
    let mut metrics: Vec<CandidateMetrics> = candidates
        .iter()
        .map(|(l, _)| CandidateMetrics {
            label: l.clone(),
            ..Default::default()
        })
        .collect();
    let mut floor = Vec::new();
    let mut halves_ssim = Vec::new();
    for (idx, apath) in &refs {
        let a = read_image(apath)?;
        let b = match reference_b {
            Some(dir) => {
                let bpath = dir.join(frame_name(*idx, "exr"));
                let b = read_image(&bpath)?;
                if (b.width, b.height) != (a.width, a.height) {
                    return Err(EvalError::invalid(
                        &bpath,
                        format!(
                            "{}×{} but the first half {} is {}×{}",
                            b.width,
                            b.height,
                            apath.display(),
                            a.width,
                            a.height
                        ),
                    ));
                }
                Some(b)
            }
            None => None,
        };
        let reference = match &b {
            Some(b) => mean_image(&a, b).unwrap_or_else(|| a.clone()),
            None => a.clone(),
        };
        let exposure = auto_exposure(&reference.pixels);
        let mut frame_floor = f64::NAN;
        for ((_, dir), m) in candidates.iter().zip(&mut metrics) {
            let c = read_image(&dir.join(frame_name(*idx, "exr"))).ok();
            let (l, p, r, q, low) = match &c {
                Some(img) => (
                    relative_lrms(img, &reference),
                    psnr(img, &reference),
                    mean_luminance_ratio(img, &reference),
                    ssim(img, &reference, exposure),
                    low_frequency_error(img, &reference),
                ),
                None => (f64::NAN, f64::NAN, f64::NAN, f64::NAN, f64::NAN),
            };
            m.ssim.push(q);
            m.low_frequency.push(low);
            m.relative_lrms
                .push(if l.is_finite() { l } else { f64::NAN });
            m.psnr.push(if p.is_finite() || p == f64::INFINITY {
                p
            } else {
                f64::NAN
            });
            m.mean_ratio.push(r);
            if let Some(b) = &b {
                let cm = c.as_ref().map_or(CorrectedLrms::NAN, |img| {
                    corrected_relative_lrms(img, &a, b)
                });
                m.corrected_lrms.push(cm.corrected);
                if cm.noise_floor.is_finite() {
                    frame_floor = cm.noise_floor;
                }
            }
        }
        if let Some(b) = &b {
            if !frame_floor.is_finite() {
                // No candidate frame here: the floor from the reference alone.
                frame_floor = corrected_relative_lrms(&reference, &a, b).noise_floor;
            }
            floor.push(frame_floor);
            halves_ssim.push(ssim(&a, b, exposure));
        }
    }
    let comparison = Comparison {
        frames: refs.iter().map(|r| r.0).collect(),
        candidates: metrics,
        noise_floor: halves.then_some(floor),
        halves_ssim: halves.then_some(halves_ssim),
        plots: Vec::new(),
    };
    write_metrics_csv(out_csv, &comparison)?;
    let mut series: Vec<(String, Vec<f64>)> = comparison
        .candidates
        .iter()
        .map(|m| {
            let y = if halves {
                &m.corrected_lrms
            } else {
                &m.relative_lrms
            };
            (m.label.clone(), y.clone())
        })
        .collect();
    if let Some(f) = &comparison.noise_floor {
        series.push(("reference noise floor".into(), f.clone()));
    }
    let y_title = if halves {
        "relative LRMS (variance-corrected)"
    } else {
        "relative LRMS"
    };
    let plot = crate::plot::LinePlot {
        series: &series,
        x_title: "frame",
        y_title,
        width: 900,
        height: 480,
    };
    let plots = crate::plot::write_svg_and_png(out_plot, &plot)?;
    Ok(Comparison {
        plots: plots.to_vec(),
        ..comparison
    })
}

/// Writes per-frame metrics as CSV (see [`compare_with`] for the columns).
pub fn write_metrics_csv(path: &Path, comparison: &Comparison) -> Result<()> {
    let err = |e: std::io::Error| EvalError::io(path, e);
    let mut f = std::io::BufWriter::new(std::fs::File::create(path).map_err(err)?);
    let halves = comparison.noise_floor.is_some();
    let mut head = String::from("frame");
    if halves {
        head.push_str(",noise_floor,halves_ssim");
    }
    for m in &comparison.candidates {
        if halves {
            head.push_str(&format!(",{}_lrms_corrected", m.label));
        }
        head.push_str(&format!(
            ",{0}_lrms,{0}_psnr,{0}_mean_ratio,{0}_ssim,{0}_low_frequency",
            m.label
        ));
    }
    writeln!(f, "{head}").map_err(err)?;
    for (i, idx) in comparison.frames.iter().enumerate() {
        let mut row = idx.to_string();
        if let Some(floor) = &comparison.noise_floor {
            let q = comparison.halves_ssim.as_ref().map_or(f64::NAN, |q| q[i]);
            row.push_str(&format!(",{:.6},{q:.4}", floor[i]));
        }
        for m in &comparison.candidates {
            if halves {
                row.push_str(&format!(",{:.6}", m.corrected_lrms[i]));
            }
            row.push_str(&format!(
                ",{:.6},{:.3},{:.6},{:.4},{:.6}",
                m.relative_lrms[i], m.psnr[i], m.mean_ratio[i], m.ssim[i], m.low_frequency[i]
            ));
        }
        writeln!(f, "{row}").map_err(err)?;
    }
    f.flush().map_err(err)
}
