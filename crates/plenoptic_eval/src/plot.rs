//! Error-along-path plots (thesis figures 6.29 and 6.31) drawn with `plotters`: one curve
//! per series over the frame index, with a grid, written as SVG and as PNG.
//!
//! Fonts: `plotters` is built without its font features (`ttf` reads system fonts through
//! font-kit, `ab_glyph` needs a font file compiled in), so no font file is read or bundled.
//! The SVG backend writes text as SVG `<text>` elements that the viewer lays out, so the SVG
//! (the figure for the README) has axis titles, tick numbers and a legend. The bitmap backend
//! cannot draw text without a font (plotters panics), so the PNG has the same axes, grid and
//! curves (same colours, same order as the SVG legend) but no text; labels in the PNG would
//! need the `ab_glyph` feature and a font file bundled in the repository. The numbers are
//! in the CSV beside every plot.

use std::path::{Path, PathBuf};

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::{EvalError, Result};

/// Curve colours, in series order (the PNG has no legend: the SVG's legend applies).
pub const PALETTE: [(u8, u8, u8); 6] = [
    (214, 39, 40),
    (31, 119, 180),
    (44, 160, 44),
    (255, 127, 14),
    (148, 103, 189),
    (23, 190, 207),
];

/// A line plot: `series` are (label, y per x = 0, 1, 2, …); non-finite values are gaps.
#[derive(Clone, Copy, Debug)]
pub struct LinePlot<'a> {
    /// The curves.
    pub series: &'a [(String, Vec<f64>)],
    /// The x axis title.
    pub x_title: &'a str,
    /// The y axis title.
    pub y_title: &'a str,
    /// Width, pixels.
    pub width: u32,
    /// Height, pixels.
    pub height: u32,
}

impl LinePlot<'_> {
    fn size(&self) -> (u32, u32) {
        (self.width.max(200), self.height.max(150))
    }

    /// The x and y ranges: all frames, and 0 to 1.1 × the largest finite value.
    fn ranges(&self) -> (f64, f64) {
        let n = self.series.iter().map(|s| s.1.len()).max().unwrap_or(0);
        let ymax = self
            .series
            .iter()
            .flat_map(|s| s.1.iter())
            .copied()
            .filter(|v| v.is_finite())
            .fold(0.0f64, f64::max);
        (
            n.saturating_sub(1).max(1) as f64,
            if ymax > 0.0 { ymax * 1.1 } else { 1.0 },
        )
    }

    /// Draws the plot on `root`; with `text`, axis titles, tick labels and the legend.
    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        text: bool,
    ) -> Result<(), String> {
        let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
        root.fill(&WHITE).map_err(e)?;
        let (xmax, ymax) = self.ranges();
        let mut builder = ChartBuilder::on(root);
        builder.margin(16);
        if text {
            // Label areas exist only where text is drawn: without them plotters draws no
            // tick labels (and needs no font).
            builder.x_label_area_size(44).y_label_area_size(64);
        }
        let mut chart = builder
            .build_cartesian_2d(0f64..xmax, 0f64..ymax)
            .map_err(e)?;
        let whole = |x: &f64| format!("{x:.0}");
        let mut mesh = chart.configure_mesh();
        mesh.light_line_style(RGBColor(235, 235, 235))
            .bold_line_style(RGBColor(200, 200, 200))
            .x_labels((xmax as usize + 1).min(11))
            .y_labels(6);
        if text {
            mesh.x_desc(self.x_title)
                .y_desc(self.y_title)
                .x_label_formatter(&whole)
                .axis_desc_style(("sans-serif", 16))
                .label_style(("sans-serif", 13));
        }
        mesh.draw().map_err(e)?;
        if !text {
            let ((x0, y0), (x1, y1)) = (
                chart.backend_coord(&(0.0, ymax)),
                chart.backend_coord(&(xmax, 0.0)),
            );
            root.draw(&Rectangle::new([(x0, y0), (x1, y1)], BLACK.stroke_width(1)))
                .map_err(e)?;
        }
        for (k, (label, ys)) in self.series.iter().enumerate() {
            let (r, g, b) = PALETTE[k % PALETTE.len()];
            let colour = RGBColor(r, g, b);
            // One line per run of finite values.
            let mut runs: Vec<Vec<(f64, f64)>> = vec![Vec::new()];
            for (i, &y) in ys.iter().enumerate() {
                if y.is_finite() {
                    if let Some(run) = runs.last_mut() {
                        run.push((i as f64, y));
                    }
                } else if runs.last().is_some_and(|r| !r.is_empty()) {
                    runs.push(Vec::new());
                }
            }
            for (j, run) in runs.into_iter().filter(|r| !r.is_empty()).enumerate() {
                let points = chart
                    .draw_series(LineSeries::new(run, colour.stroke_width(2)))
                    .map_err(e)?;
                if text && j == 0 {
                    points.label(label.as_str()).legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 24, y)], colour.stroke_width(3))
                    });
                }
            }
        }
        if text && !self.series.is_empty() {
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::UpperRight)
                .background_style(WHITE.mix(0.85))
                .border_style(RGBColor(160, 160, 160))
                .label_font(("sans-serif", 13))
                .draw()
                .map_err(e)?;
        }
        root.present().map_err(e)
    }
}

fn plot_error(path: &Path, message: String) -> EvalError {
    EvalError::Plot {
        path: path.to_path_buf(),
        message,
    }
}

/// Writes the plot as SVG, with axis titles, tick labels and a legend.
pub fn write_svg(path: impl AsRef<Path>, plot: &LinePlot<'_>) -> Result<()> {
    let path = path.as_ref();
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, plot.size()).into_drawing_area();
        plot.draw(&root, true).map_err(|m| plot_error(path, m))?;
    }
    std::fs::write(path, svg).map_err(|e| EvalError::io(path, e))
}

/// Writes the plot as PNG: axes, grid and curves, no text (see the module docs).
pub fn write_png(path: impl AsRef<Path>, plot: &LinePlot<'_>) -> Result<()> {
    let path = path.as_ref();
    let (w, h) = plot.size();
    let mut rgb = vec![255u8; w as usize * h as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
        plot.draw(&root, false).map_err(|m| plot_error(path, m))?;
    }
    image::save_buffer(path, &rgb, w, h, image::ExtendedColorType::Rgb8).map_err(|e| {
        EvalError::Png {
            path: path.to_path_buf(),
            message: e.to_string(),
        }
    })
}

/// Writes the plot next to `path` as `<stem>.svg` and `<stem>.png` (whatever `path`'s
/// extension) and returns both paths, SVG first.
pub fn write_svg_and_png(path: impl AsRef<Path>, plot: &LinePlot<'_>) -> Result<[PathBuf; 2]> {
    let path = path.as_ref();
    let (svg, png) = (path.with_extension("svg"), path.with_extension("png"));
    write_svg(&svg, plot)?;
    write_png(&png, plot)?;
    Ok([svg, png])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn series() -> Vec<(String, Vec<f64>)> {
        vec![
            ("geometry".into(), vec![0.1, 0.2, f64::NAN, 0.15, 0.12]),
            ("image".into(), vec![0.3, 0.35, 0.4, 0.33, 0.31]),
        ]
    }

    #[test]
    fn svg_has_text_and_png_has_the_curves() {
        let dir = tempfile::tempdir().unwrap();
        let s = series();
        let plot = LinePlot {
            series: &s,
            x_title: "frame",
            y_title: "relative LRMS",
            width: 640,
            height: 360,
        };
        let [svg, png] = write_svg_and_png(dir.path().join("error.csv"), &plot).unwrap();
        let text = std::fs::read_to_string(&svg).unwrap();
        assert!(text.starts_with("<svg"), "{}", &text[..80.min(text.len())]);
        for needle in ["relative LRMS", "frame", "geometry", "image", "<polyline"] {
            assert!(text.contains(needle), "{needle} missing from the SVG");
        }
        let img = image::open(&png).unwrap().to_rgb8();
        assert_eq!(img.dimensions(), (640, 360));
        // Both curve colours are drawn.
        for (r, g, b) in &PALETTE[..2] {
            assert!(
                img.pixels().any(|p| p.0 == [*r, *g, *b]),
                "colour ({r}, {g}, {b}) not in the PNG"
            );
        }
    }

    #[test]
    fn empty_and_flat_series_still_plot() {
        let dir = tempfile::tempdir().unwrap();
        let flat = vec![("zero".to_string(), vec![0.0; 3])];
        for s in [&Vec::new(), &flat] {
            let plot = LinePlot {
                series: s,
                x_title: "x",
                y_title: "y",
                width: 10,
                height: 10,
            };
            write_svg_and_png(dir.path().join("p"), &plot).unwrap();
        }
        let e = write_svg(
            dir.path().join("no/such/dir/p.svg"),
            &LinePlot {
                series: &flat,
                x_title: "x",
                y_title: "y",
                width: 300,
                height: 200,
            },
        )
        .unwrap_err();
        assert!(e.to_string().contains("p.svg"), "{e}");
    }
}
