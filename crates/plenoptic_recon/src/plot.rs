//! A small line-plot renderer for the error-along-path figures (thesis figures 6.29 and 6.31):
//! one curve per series, axes with ticks and numbers, a legend; written as PNG. No fonts are
//! needed: labels use a built-in 3×5 pixel font (digits, A–Z, `.`, `-`, `_`, space; other
//! characters print as blanks; lowercase prints as uppercase).

use std::path::Path;

use crate::{Error, Result};

const GLYPHS: &[(char, [u8; 5])] = &[
    ('0', [7, 5, 5, 5, 7]),
    ('1', [2, 6, 2, 2, 7]),
    ('2', [7, 1, 7, 4, 7]),
    ('3', [7, 1, 7, 1, 7]),
    ('4', [5, 5, 7, 1, 1]),
    ('5', [7, 4, 7, 1, 7]),
    ('6', [7, 4, 7, 5, 7]),
    ('7', [7, 1, 1, 2, 2]),
    ('8', [7, 5, 7, 5, 7]),
    ('9', [7, 5, 7, 1, 7]),
    ('.', [0, 0, 0, 0, 2]),
    ('-', [0, 0, 7, 0, 0]),
    ('_', [0, 0, 0, 0, 7]),
    ('A', [2, 5, 7, 5, 5]),
    ('B', [6, 5, 6, 5, 6]),
    ('C', [3, 4, 4, 4, 3]),
    ('D', [6, 5, 5, 5, 6]),
    ('E', [7, 4, 6, 4, 7]),
    ('F', [7, 4, 6, 4, 4]),
    ('G', [3, 4, 5, 5, 3]),
    ('H', [5, 5, 7, 5, 5]),
    ('I', [7, 2, 2, 2, 7]),
    ('J', [1, 1, 1, 5, 2]),
    ('K', [5, 5, 6, 5, 5]),
    ('L', [4, 4, 4, 4, 7]),
    ('M', [5, 7, 7, 5, 5]),
    ('N', [6, 5, 5, 5, 5]),
    ('O', [2, 5, 5, 5, 2]),
    ('P', [6, 5, 6, 4, 4]),
    ('Q', [2, 5, 5, 6, 3]),
    ('R', [6, 5, 6, 5, 5]),
    ('S', [3, 4, 2, 1, 6]),
    ('T', [7, 2, 2, 2, 2]),
    ('U', [5, 5, 5, 5, 7]),
    ('V', [5, 5, 5, 5, 2]),
    ('W', [5, 5, 7, 7, 5]),
    ('X', [5, 5, 2, 5, 5]),
    ('Y', [5, 5, 2, 2, 2]),
    ('Z', [7, 1, 2, 4, 7]),
];

const PALETTE: [[u8; 3]; 6] = [
    [214, 39, 40],
    [31, 119, 180],
    [44, 160, 44],
    [255, 127, 14],
    [148, 103, 189],
    [23, 190, 207],
];

struct Canvas {
    w: usize,
    h: usize,
    px: Vec<u8>,
}

impl Canvas {
    fn set(&mut self, x: i64, y: i64, c: [u8; 3]) {
        if x >= 0 && y >= 0 && (x as usize) < self.w && (y as usize) < self.h {
            let i = 3 * (y as usize * self.w + x as usize);
            self.px[i..i + 3].copy_from_slice(&c);
        }
    }

    fn line(&mut self, (x0, y0): (f32, f32), (x1, y1): (f32, f32), c: [u8; 3], thick: i64) {
        let steps = ((x1 - x0).abs().max((y1 - y0).abs()).ceil() as usize).max(1);
        for s in 0..=steps {
            let f = s as f32 / steps as f32;
            let (x, y) = (
                (x0 + (x1 - x0) * f).round() as i64,
                (y0 + (y1 - y0) * f).round() as i64,
            );
            for dy in 0..thick {
                for dx in 0..thick {
                    self.set(x + dx - thick / 2, y + dy - thick / 2, c);
                }
            }
        }
    }

    fn text(&mut self, x: i64, y: i64, s: &str, scale: i64, c: [u8; 3]) {
        for (k, ch) in s.chars().enumerate() {
            let ch = ch.to_ascii_uppercase();
            let Some((_, rows)) = GLYPHS.iter().find(|g| g.0 == ch) else {
                continue;
            };
            for (r, bits) in rows.iter().enumerate() {
                for col in 0..3 {
                    if bits & (4 >> col) != 0 {
                        for sy in 0..scale {
                            for sx in 0..scale {
                                self.set(
                                    x + (k as i64 * 4 + col) * scale + sx,
                                    y + r as i64 * scale + sy,
                                    c,
                                );
                            }
                        }
                    }
                }
            }
        }
    }
}

fn fmt_tick(v: f64) -> String {
    if v == 0.0 {
        "0".into()
    } else if v.abs() >= 10.0 {
        format!("{v:.0}")
    } else if v.abs() >= 1.0 {
        format!("{v:.1}")
    } else {
        format!("{v:.3}")
    }
}

/// Plots `series` (label, y per x = 0, 1, 2, …; non-finite values are gaps) with axis titles
/// and writes a `width × height` PNG.
pub fn line_plot(
    path: impl AsRef<Path>,
    series: &[(String, Vec<f64>)],
    x_title: &str,
    y_title: &str,
    width: u32,
    height: u32,
) -> Result<()> {
    let path = path.as_ref();
    let (w, h) = (width.max(200) as usize, height.max(150) as usize);
    let mut cv = Canvas {
        w,
        h,
        px: vec![255; w * h * 3],
    };
    let (left, right, top, bottom) = (70.0f32, 20.0f32, 20.0f32, 50.0f32);
    let (pw, ph) = (w as f32 - left - right, h as f32 - top - bottom);
    let n = series.iter().map(|s| s.1.len()).max().unwrap_or(0).max(2);
    let ymax = series
        .iter()
        .flat_map(|s| s.1.iter())
        .copied()
        .filter(|v| v.is_finite())
        .fold(0.0f64, f64::max);
    let ymax = if ymax > 0.0 { ymax * 1.1 } else { 1.0 };
    let map = |i: usize, v: f64| {
        (
            left + pw * i as f32 / (n - 1) as f32,
            top + ph * (1.0 - (v / ymax) as f32),
        )
    };
    let black = [0, 0, 0];
    let grey = [200, 200, 200];
    for k in 0..=5 {
        let v = ymax * k as f64 / 5.0;
        let (_, y) = map(0, v);
        cv.line((left, y), (left + pw, y), grey, 1);
        cv.line((left - 5.0, y), (left, y), black, 1);
        cv.text(4, y as i64 - 5, &fmt_tick(v), 2, black);
    }
    let xticks = (n - 1).clamp(1, 10);
    for k in 0..=xticks {
        let i = (n - 1) * k / xticks;
        let (x, _) = map(i, 0.0);
        cv.line((x, top + ph), (x, top + ph + 5.0), black, 1);
        cv.text(
            x as i64 - 4,
            (top + ph + 9.0) as i64,
            &i.to_string(),
            2,
            black,
        );
    }
    cv.line((left, top), (left, top + ph), black, 2);
    cv.line((left, top + ph), (left + pw, top + ph), black, 2);
    cv.text(
        (left + pw / 2.0) as i64 - 4 * x_title.len() as i64,
        h as i64 - 16,
        x_title,
        2,
        black,
    );
    cv.text(left as i64 + 6, 4, y_title, 2, black);
    let longest = series.iter().map(|s| s.0.len()).max().unwrap_or(4).max(4) as i64;
    for (s, (label, ys)) in series.iter().enumerate() {
        let c = PALETTE[s % PALETTE.len()];
        for i in 1..ys.len() {
            if ys[i - 1].is_finite() && ys[i].is_finite() {
                cv.line(map(i - 1, ys[i - 1]), map(i, ys[i]), c, 2);
            }
        }
        let ly = top as i64 + 14 + 16 * s as i64;
        let lx = (left + pw) as i64 - 8 * longest - 44;
        cv.line(
            (lx as f32, ly as f32 + 4.0),
            (lx as f32 + 24.0, ly as f32 + 4.0),
            c,
            3,
        );
        cv.text(lx + 30, ly, label, 2, black);
    }
    image::save_buffer(
        path,
        &cv.px,
        w as u32,
        h as u32,
        image::ExtendedColorType::Rgb8,
    )
    .map_err(|e| Error::Io(format!("{}: {e}", path.display())))
}
