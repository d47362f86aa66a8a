//! Images: a width × height grid of any pixel type, parallel rendering over rows, PNG output.

use glam::Vec3;
use rayon::prelude::*;
use std::path::Path;

use crate::{Result, TraceError};

/// A row-major image, row 0 at the top.
#[derive(Debug, Clone, PartialEq)]
pub struct Image<T> {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Pixels row by row from the top.
    pub pixels: Vec<T>,
}

impl<T: Clone> Image<T> {
    /// An image filled with `value`.
    pub fn filled(width: u32, height: u32, value: T) -> Self {
        Self {
            width,
            height,
            pixels: vec![value; width as usize * height as usize],
        }
    }
}

impl<T> Image<T> {
    /// The pixel at column `x`, row `y`.
    pub fn get(&self, x: u32, y: u32) -> &T {
        &self.pixels[y as usize * self.width as usize + x as usize]
    }

    /// Renders every pixel with `f(x, y)`, in parallel over rows. The result does not depend
    /// on the number of threads as long as `f` depends only on its arguments.
    pub fn render<F>(width: u32, height: u32, f: F) -> Self
    where
        T: Send,
        F: Fn(u32, u32) -> T + Sync,
    {
        let pixels = (0..height)
            .into_par_iter()
            .flat_map_iter(|y| (0..width).map(move |x| (x, y)).collect::<Vec<_>>())
            .map(|(x, y)| f(x, y))
            .collect();
        Self {
            width,
            height,
            pixels,
        }
    }

    /// A new image with `f` applied to every pixel.
    pub fn map<U>(&self, f: impl Fn(&T) -> U) -> Image<U> {
        Image {
            width: self.width,
            height: self.height,
            pixels: self.pixels.iter().map(f).collect(),
        }
    }
}

/// Rec. 709 luminance of linear RGB.
pub fn luminance(c: Vec3) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

fn srgb_encode(v: f32) -> u8 {
    let v = v.clamp(0.0, 1.0);
    let s = if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0 + 0.5) as u8
}

impl Image<Vec3> {
    /// The mean luminance.
    pub fn mean_luminance(&self) -> f64 {
        let sum: f64 = self.pixels.iter().map(|&c| f64::from(luminance(c))).sum();
        sum / self.pixels.len().max(1) as f64
    }

    /// 8-bit sRGB RGB bytes of `exposure × radiance`, clamped.
    pub fn to_srgb8(&self, exposure: f32) -> Vec<u8> {
        self.pixels
            .iter()
            .flat_map(|&c| (c * exposure).to_array().map(srgb_encode))
            .collect()
    }

    /// Writes `exposure × radiance` as an 8-bit sRGB PNG.
    pub fn save_png(&self, path: impl AsRef<Path>, exposure: f32) -> Result<()> {
        let path = path.as_ref();
        image::save_buffer(
            path,
            &self.to_srgb8(exposure),
            self.width,
            self.height,
            image::ExtendedColorType::Rgb8,
        )
        .map_err(|e| TraceError::Image {
            path: path.display().to_string(),
            message: e.to_string(),
        })
    }
}
