//! Depth reprojection of base-view cubes into the camera (thesis appendix A.2 and §6.7).
//!
//! Every texel of a base view's cube with a finite distance is a world point
//! `base + direction · distance`; it is projected into the camera and written through a
//! z-buffer as a square *splat* (foreground fill) whose size is the texel's footprint: a
//! texel spans `2/n` in face coordinates, so at distance `d` along a direction whose largest
//! component is `m` it covers about `2 d m / n` metres across (surface slant is ignored),
//! i.e. `2 d m f / (n z)` pixels at camera depth `z` with focal length `f` pixels. Splats are
//! capped at [`ReconSettings::max_splat_px`] pixels. A splat in front (by more than
//! [`ReconSettings::same_surface`], relative) wins; among splats of the same surface the one whose centre is nearer the pixel wins.
//!
//! Warped views are blended per pixel over the views whose depth is within a relative
//! tolerance of the nearest ([`blend_warped`]), and the remaining holes are filled from the
//! farthest filled neighbour, repeatedly ([`background_fill`]): disocclusions reveal what is
//! behind, so the background, not the occluder, is extended into them.

use glam::Vec3;
use plenoptic_pack::{CubeImage, cube};
use rayon::prelude::*;

use crate::ReconSettings;
use crate::camera::CameraBasis;

/// One base view warped into the camera.
#[derive(Clone, Debug)]
pub struct Warped {
    /// Radiance per pixel.
    pub radiance: Vec<Vec3>,
    /// Camera depth (along the viewing direction) per pixel, ∞ where nothing landed.
    pub z: Vec<f32>,
    /// Object id per pixel.
    pub object: Vec<u32>,
}

/// The cubes of one base view at time t, ready to warp.
#[derive(Clone, Copy, Debug)]
pub struct ViewCubes<'a> {
    /// Base view position.
    pub position: Vec3,
    /// Radiance at t.
    pub radiance: &'a CubeImage<Vec3>,
    /// Distance (from the nearest key).
    pub distance: &'a CubeImage<f32>,
    /// Object id (from the nearest key).
    pub object: &'a CubeImage<u32>,
}

/// Warps one view's cubes into a `width × height` camera, with the splats of `settings`.
pub fn warp_view(
    view: &ViewCubes<'_>,
    cam: &CameraBasis,
    width: u32,
    height: u32,
    settings: &ReconSettings,
) -> Warped {
    let (same_surface, max_splat_px) = (settings.same_surface, settings.max_splat_px);
    let (w, h) = (width as usize, height as usize);
    let mut out = Warped {
        radiance: vec![Vec3::ZERO; w * h],
        z: vec![f32::INFINITY; w * h],
        object: vec![0; w * h],
    };
    let mut key = vec![f32::INFINITY; w * h];
    let n = view.distance.face_size;
    let texels = view
        .distance
        .texels
        .len()
        .min(view.radiance.texels.len())
        .min(view.object.texels.len());
    if view.radiance.face_size != n || view.object.face_size != n {
        return out;
    }
    for i in 0..texels {
        let d = view.distance.texels[i];
        if !(d.is_finite() && d > 0.0) {
            continue;
        }
        let dir = cube::texel_direction(n, i);
        let world = view.position + dir * d;
        let Some((px, py, z)) = cam.project(world) else {
            continue;
        };
        let m = dir.abs().max_element();
        let size = (2.0 * d * m * cam.focal_px / (n as f32 * z)).min(max_splat_px);
        let half = (size * 0.5).max(0.5);
        let (x0, x1) = (
            (px - half).floor().max(0.0),
            (px + half).floor().min(w as f32 - 1.0),
        );
        let (y0, y1) = (
            (py - half).floor().max(0.0),
            (py + half).floor().min(h as f32 - 1.0),
        );
        if x0 > x1 || y0 > y1 {
            continue;
        }
        let (c, o) = (view.radiance.texels[i], view.object.texels[i]);
        for y in y0 as usize..=y1 as usize {
            let dy = y as f32 + 0.5 - py;
            for x in x0 as usize..=x1 as usize {
                let dx = x as f32 + 0.5 - px;
                let r2 = dx * dx + dy * dy;
                let j = y * w + x;
                let cur = out.z[j];
                // Clearly in front: wins. Same surface (within the tolerance): the nearer
                // splat centre wins. Behind: loses.
                if z < cur * (1.0 - same_surface)
                    || (z <= cur * (1.0 + same_surface) && r2 < key[j])
                {
                    key[j] = r2;
                    out.z[j] = z;
                    out.radiance[j] = c;
                    out.object[j] = o;
                }
            }
        }
    }
    out
}

/// Blends warped views with `weights` (one per view): per pixel, the views whose depth is
/// within `tolerance` (relative) of the nearest take part. Returns radiance, depth, object and
/// a coverage flag per pixel.
pub fn blend_warped(
    views: &[(Warped, f32)],
    width: u32,
    height: u32,
    tolerance: f32,
) -> (Vec<Vec3>, Vec<f32>, Vec<u32>, Vec<bool>) {
    let n = width as usize * height as usize;
    let mut rad = vec![Vec3::ZERO; n];
    let mut z = vec![f32::INFINITY; n];
    let mut obj = vec![0u32; n];
    let mut cov = vec![false; n];
    rad.par_iter_mut()
        .zip(z.par_iter_mut())
        .zip(obj.par_iter_mut())
        .zip(cov.par_iter_mut())
        .enumerate()
        .for_each(|(j, (((r, zz), o), c))| {
            let zmin = views
                .iter()
                .map(|(v, _)| v.z[j])
                .fold(f32::INFINITY, f32::min);
            if !zmin.is_finite() {
                return;
            }
            let (mut sum, mut ws, mut best) = (Vec3::ZERO, 0.0, (f32::NEG_INFINITY, 0));
            for (v, w) in views {
                if v.z[j] <= zmin * (1.0 + tolerance) {
                    sum += v.radiance[j] * *w;
                    ws += *w;
                    if *w > best.0 {
                        best = (*w, v.object[j]);
                    }
                }
            }
            *r = if ws > 0.0 { sum / ws } else { Vec3::ZERO };
            *zz = zmin;
            *o = best.1;
            *c = true;
        });
    (rad, z, obj, cov)
}

/// Fills holes (`covered == false`) from their farthest covered 8-neighbour, up to `passes`
/// times; returns the number of pixels filled. Filled pixels become covered.
pub fn background_fill(
    width: u32,
    height: u32,
    radiance: &mut [Vec3],
    z: &mut [f32],
    object: &mut [u32],
    covered: &mut [bool],
    passes: u32,
) -> usize {
    let (w, h) = (width as usize, height as usize);
    let mut filled = 0;
    for _ in 0..passes {
        let updates: Vec<(usize, Vec3, f32, u32)> = (0..w * h)
            .into_par_iter()
            .filter(|&j| !covered[j])
            .filter_map(|j| {
                let (x, y) = ((j % w) as i64, (j / w) as i64);
                let mut best: Option<usize> = None;
                for dy in -1..=1 {
                    for dx in -1..=1 {
                        let (nx, ny) = (x + dx, y + dy);
                        if nx < 0 || ny < 0 || nx >= w as i64 || ny >= h as i64 {
                            continue;
                        }
                        let k = ny as usize * w + nx as usize;
                        if covered[k] && best.is_none_or(|b| z[k] > z[b]) {
                            best = Some(k);
                        }
                    }
                }
                best.map(|k| (j, radiance[k], z[k], object[k]))
            })
            .collect();
        if updates.is_empty() {
            break;
        }
        filled += updates.len();
        for (j, r, zz, o) in updates {
            radiance[j] = r;
            z[j] = zz;
            object[j] = o;
            covered[j] = true;
        }
    }
    filled
}
