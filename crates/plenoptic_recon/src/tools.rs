//! The quality tools behind the `plenoptic render` and `plenoptic compare` commands
//! (design.md, "Measuring"). They need nothing but paths and options.
//!
//! Frame files in a frame directory are named `frame_NNNNN.exr` (linear radiance and depth,
//! see [`crate::frame_io`]) and `frame_NNNNN.png` (tonemapped), `NNNNN` the frame index of the
//! camera path ([`crate::path`]). The reference renderer writes its frames with the same names
//! through [`write_frame_files`], so [`compare`] can pair them.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

use glam::Vec3;
use plenoptic_trace::Image;
use plenoptic_trace::metrics::{psnr, relative_lrms};

use crate::frame::{Mode, Report};
use crate::frame_io::{auto_exposure, read_exr, write_exr, write_png};
use crate::path::CameraPath;
use crate::reconstructor::Reconstructor;
use crate::{Error, Result};

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
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            mode: Mode::GeometryAssisted,
            exposure: None,
            png: true,
            exr: true,
            progress: false,
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
    std::fs::create_dir_all(out_dir)
        .map_err(|e| Error::Io(format!("{}: {e}", out_dir.display())))?;
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
    let count = path.frame_count();
    for s in path.frames() {
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
    std::fs::write(&csv_path, csv)
        .map_err(|e| Error::Io(format!("{}: {e}", csv_path.display())))?;
    Ok(summary)
}

/// Per-frame metrics of one candidate.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CandidateMetrics {
    /// The candidate's label.
    pub label: String,
    /// Relative LRMS per reference frame (NaN where the candidate frame is missing).
    pub relative_lrms: Vec<f64>,
    /// PSNR (dB) per reference frame.
    pub psnr: Vec<f64>,
}

impl CandidateMetrics {
    /// Mean relative LRMS over the frames present.
    pub fn mean_lrms(&self) -> f64 {
        let v: Vec<f64> = self
            .relative_lrms
            .iter()
            .copied()
            .filter(|x| x.is_finite())
            .collect();
        v.iter().sum::<f64>() / v.len().max(1) as f64
    }
}

fn exr_frames(dir: &Path) -> Result<Vec<(usize, PathBuf)>> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).map_err(|e| Error::Io(format!("{}: {e}", dir.display())))? {
        let p = e.map_err(|e| Error::Io(e.to_string()))?.path();
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

/// Compares each candidate frame directory with the reference directory frame by frame:
/// relative LRMS and PSNR ([`plenoptic_trace::metrics`]) per frame into `out_csv` (columns
/// `frame`, then `<label>_lrms`, `<label>_psnr` per candidate) and an error-along-path plot
/// (relative LRMS per frame, one curve per candidate) into `out_png`.
pub fn compare(
    reference_dir: &Path,
    candidates: &[(String, PathBuf)],
    out_csv: &Path,
    out_png: &Path,
) -> Result<Vec<CandidateMetrics>> {
    let refs = exr_frames(reference_dir)?;
    if refs.is_empty() {
        return Err(Error::Io(format!(
            "{}: no frame_NNNNN.exr files",
            reference_dir.display()
        )));
    }
    let mut metrics: Vec<CandidateMetrics> = candidates
        .iter()
        .map(|(l, _)| CandidateMetrics {
            label: l.clone(),
            ..Default::default()
        })
        .collect();
    for (idx, rpath) in &refs {
        let (w, h, rp) = read_exr(rpath)?;
        let reference = Image {
            width: w,
            height: h,
            pixels: rp,
        };
        for ((_, dir), m) in candidates.iter().zip(&mut metrics) {
            let cpath = dir.join(frame_name(*idx, "exr"));
            let (l, p) = match read_exr(&cpath) {
                Ok((cw, ch, cp)) => {
                    let img = Image {
                        width: cw,
                        height: ch,
                        pixels: cp,
                    };
                    (relative_lrms(&img, &reference), psnr(&img, &reference))
                }
                Err(_) => (f64::NAN, f64::NAN),
            };
            m.relative_lrms.push(l);
            m.psnr.push(p);
        }
    }
    write_metrics_csv(
        out_csv,
        &refs.iter().map(|r| r.0).collect::<Vec<_>>(),
        &metrics,
    )?;
    let series: Vec<(String, Vec<f64>)> = metrics
        .iter()
        .map(|m| (m.label.clone(), m.relative_lrms.clone()))
        .collect();
    crate::plot::line_plot(out_png, &series, "FRAME", "RELATIVE LRMS", 900, 480)?;
    Ok(metrics)
}

/// Writes per-frame metrics as CSV (`frame`, then `<label>_lrms`, `<label>_psnr` per
/// candidate).
pub fn write_metrics_csv(
    path: &Path,
    frames: &[usize],
    metrics: &[CandidateMetrics],
) -> Result<()> {
    let err = |e: std::io::Error| Error::Io(format!("{}: {e}", path.display()));
    let mut f = std::io::BufWriter::new(std::fs::File::create(path).map_err(err)?);
    let mut head = String::from("frame");
    for m in metrics {
        head.push_str(&format!(",{0}_lrms,{0}_psnr", m.label));
    }
    writeln!(f, "{head}").map_err(err)?;
    for (i, idx) in frames.iter().enumerate() {
        let mut row = idx.to_string();
        for m in metrics {
            row.push_str(&format!(",{:.6},{:.3}", m.relative_lrms[i], m.psnr[i]));
        }
        writeln!(f, "{row}").map_err(err)?;
    }
    f.flush().map_err(err)
}
