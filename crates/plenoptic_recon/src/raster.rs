//! A CPU rasterizer of the proxy triangles for the geometry mask.
//!
//! Triangles are placed by their object's transform at t, clipped against the near plane,
//! projected, and scan-converted with edge functions at pixel centres (both windings: proxy
//! geometry is double-sided like the ray-cast mask). Depth is interpolated as 1/z (affine in
//! screen space), so every covered pixel gets the camera-space depth of the surface through
//! its centre; the hit point is the eye plus the pixel's ray direction times the ray distance.
//! The image is split into bands of rows rasterized in parallel.

use glam::{Affine3A, Vec3, Vec4};
use rayon::prelude::*;

use crate::camera::{Camera, CameraBasis};
use crate::proxy::{GeometryMask, TriangleMesh};

const NEAR: f32 = 1e-3;
const BAND: usize = 16;

/// A projected triangle: screen x, y and 1/z per vertex, with its object.
#[derive(Clone, Copy)]
struct Tri {
    x: [f32; 3],
    y: [f32; 3],
    iz: [f32; 3],
    object: u32,
    /// Index into [`Projected::sources`].
    source: u32,
    ymin: f32,
    ymax: f32,
}

/// Triangles of `objects` (pack id, object-to-world transform, mesh) placed, clipped against
/// the near plane and projected for `camera`: what [`raster_band`] scan-converts.
pub(crate) struct Projected {
    tris: Vec<Tri>,
    /// Per projected triangle: (index into the projected objects, triangle index in its
    /// mesh). A triangle clipped into two shares its source.
    pub sources: Vec<(u32, u32)>,
    /// Per source: the triangle's unit normal in camera space (either side; zero when
    /// degenerate).
    pub normals: Vec<Vec3>,
}

impl Projected {
    /// The world-space normal (either side; zero for no triangle or a degenerate one) of
    /// the triangle `prim` that [`raster_band`] wrote for a pixel, for the camera basis `b` the
    /// triangles were projected with.
    pub(crate) fn world_normal(&self, b: &CameraBasis, prim: u32) -> Vec3 {
        let c = self.normals.get(prim as usize).copied().unwrap_or_default();
        b.right * c.x + b.up * c.y + b.forward * c.z
    }
}

/// Places, clips and projects `objects` for `camera`.
pub(crate) fn project(camera: &Camera, objects: &[(u32, Affine3A, &TriangleMesh)]) -> Projected {
    let b = camera.basis();
    let (sx, sy) = (0.5 * b.width / b.tan_x, 0.5 * b.height / b.tan_y);
    let mut tris = Vec::new();
    let mut sources = Vec::new();
    let mut normals = Vec::new();
    let mut cam: Vec<Vec3> = Vec::new();
    for (oi, &(object, xf, mesh)) in objects.iter().enumerate() {
        cam.clear();
        cam.extend(mesh.positions.iter().map(|&p| {
            let d = xf.transform_point3(p) - b.position;
            Vec3::new(d.dot(b.right), d.dot(b.up), d.dot(b.forward))
        }));
        for (ti, t) in mesh.triangles.iter().enumerate() {
            let [Some(v0), Some(v1), Some(v2)] = t.map(|i| cam.get(i as usize).copied()) else {
                continue;
            };
            let v = [v0, v1, v2];
            // Clip against z ≥ NEAR (Sutherland–Hodgman on one plane).
            let mut poly = [Vec3::ZERO; 4];
            let mut len = 0;
            for k in 0..3 {
                let (a, c) = (v[k], v[(k + 1) % 3]);
                if a.z >= NEAR {
                    poly[len] = a;
                    len += 1;
                }
                if (a.z >= NEAR) != (c.z >= NEAR) {
                    let f = (NEAR - a.z) / (c.z - a.z);
                    poly[len] = a + (c - a) * f;
                    len += 1;
                }
            }
            let proj = |p: Vec3| {
                (
                    0.5 * b.width + sx * p.x / p.z,
                    0.5 * b.height - sy * p.y / p.z,
                    1.0 / p.z,
                )
            };
            let source = sources.len() as u32;
            let mut used = false;
            for k in 1..len.saturating_sub(1) {
                let (p0, p1, p2) = (proj(poly[0]), proj(poly[k]), proj(poly[k + 1]));
                let x = [p0.0, p1.0, p2.0];
                let y = [p0.1, p1.1, p2.1];
                if !(x.iter().chain(&y).all(|c| c.is_finite())) {
                    continue;
                }
                let ymin = y[0].min(y[1]).min(y[2]);
                let ymax = y[0].max(y[1]).max(y[2]);
                if ymax < 0.0
                    || ymin > b.height
                    || x.iter().all(|&c| c < 0.0)
                    || x.iter().all(|&c| c > b.width)
                {
                    continue;
                }
                tris.push(Tri {
                    x,
                    y,
                    iz: [p0.2, p1.2, p2.2],
                    object,
                    source,
                    ymin,
                    ymax,
                });
                used = true;
            }
            if used {
                sources.push((oi as u32, ti as u32));
                normals.push((v1 - v0).cross(v2 - v0).normalize_or_zero());
            }
        }
    }
    Projected {
        tris,
        sources,
        normals,
    }
}

/// Scan-converts the rows `y0..y0 + zbuf.len() / width` of `tris`: `zbuf` (camera-space depth,
/// ∞ initially) and `obj` (the nearest object) are that band of the image; `prim`, when
/// given, receives the nearest triangle's index into [`Projected::sources`].
///
/// Each triangle row visits only the span where its edge functions can be non-negative
/// (solved in f64, widened by two pixels), and tests every pixel of the span exactly as a
/// full bounding-box scan would: the result is the same, at a cost proportional to the
/// covered area instead of the bounding box.
pub(crate) fn raster_band(
    tris: &Projected,
    width: usize,
    y0: usize,
    zbuf: &mut [f32],
    obj: &mut [u32],
    mut prim: Option<&mut [u32]>,
) {
    let w = width;
    let rows = zbuf.len() / w.max(1);
    for t in &tris.tris {
        if t.ymax < y0 as f32 || t.ymin > (y0 + rows) as f32 {
            continue;
        }
        let area = (t.x[1] - t.x[0]) * (t.y[2] - t.y[0]) - (t.x[2] - t.x[0]) * (t.y[1] - t.y[0]);
        if area.abs() < 1e-12 {
            continue;
        }
        let inv = 1.0 / area;
        let xmin = t.x[0].min(t.x[1]).min(t.x[2]).floor().max(0.0) as usize;
        let xmax = (t.x[0].max(t.x[1]).max(t.x[2]).ceil() as usize).min(w);
        let ylo = (t.ymin.floor().max(y0 as f32) as usize).max(y0);
        let yhi = (t.ymax.ceil() as usize).min(y0 + rows);
        let sign = if inv > 0.0 { 1.0f64 } else { -1.0 };
        for py in ylo..yhi {
            let cy = py as f32 + 0.5;
            // The span of pixel centres where every edge function has the sign of the area.
            let (mut lo, mut hi) = (xmin as f64, xmax as f64);
            let mut empty = false;
            for (i, j) in [(1usize, 2usize), (2, 0), (0, 1)] {
                let (xi, yi) = (t.x[i] as f64, t.y[i] as f64);
                let (dx, dy) = (t.x[j] as f64 - xi, t.y[j] as f64 - yi);
                // e(cx) = dx (cy − yi) − dy (cx − xi) = a + b·cx, to be ≥ 0 after × sign.
                let a = sign * (dx * (cy as f64 - yi) + dy * xi);
                let bb = -sign * dy;
                if bb > 0.0 {
                    lo = lo.max(-a / bb);
                } else if bb < 0.0 {
                    hi = hi.min(-a / bb);
                } else if a < 0.0 {
                    empty = true;
                }
            }
            if empty || lo > hi + 4.0 {
                continue;
            }
            let x0 = ((lo - 0.5).floor() - 2.0).max(xmin as f64) as usize;
            let x1 = (((hi - 0.5).ceil() + 3.0) as usize).min(xmax);
            let row = (py - y0) * w;
            // Per row: e(i, j) = (x_j − x_i)(cy − y_i) − (y_j − y_i)(cx − x_i).
            let a = |i: usize, j: usize| (t.x[j] - t.x[i]) * (cy - t.y[i]);
            let (a12, a20, a01) = (a(1, 2), a(2, 0), a(0, 1));
            let (d12, d20, d01) = (t.y[2] - t.y[1], t.y[0] - t.y[2], t.y[1] - t.y[0]);
            let test = |cx: f32| {
                let b0 = (a12 - d12 * (cx - t.x[1])) * inv;
                let b1 = (a20 - d20 * (cx - t.x[2])) * inv;
                let b2 = (a01 - d01 * (cx - t.x[0])) * inv;
                if b0 < 0.0 || b1 < 0.0 || b2 < 0.0 {
                    return None;
                }
                let iz = b0 * t.iz[0] + b1 * t.iz[1] + b2 * t.iz[2];
                (iz > 0.0).then(|| 1.0 / iz)
            };
            // Four pixels at a time (the same arithmetic lane by lane), then the rest.
            let mut px = x0;
            let (v, lanes) = (Vec4::splat, Vec4::new(0.5, 1.5, 2.5, 3.5));
            while px + 4 <= x1 {
                let cx = v(px as f32) + lanes;
                let b0 = (v(a12) - v(d12) * (cx - v(t.x[1]))) * v(inv);
                let b1 = (v(a20) - v(d20) * (cx - v(t.x[2]))) * v(inv);
                let b2 = (v(a01) - v(d01) * (cx - v(t.x[0]))) * v(inv);
                let iz = b0 * v(t.iz[0]) + b1 * v(t.iz[1]) + b2 * v(t.iz[2]);
                let z = Vec4::ONE / iz;
                let j = row + px;
                let old = Vec4::from_slice(&zbuf[j..j + 4]);
                let zero = Vec4::ZERO;
                let inside = !(b0.cmplt(zero) | b1.cmplt(zero) | b2.cmplt(zero) | iz.cmple(zero));
                let write = inside & z.cmplt(old);
                let bits = write.bitmask();
                if bits != 0 {
                    Vec4::select(write, z, old).write_to_slice(&mut zbuf[j..j + 4]);
                    for i in 0..4 {
                        if bits & (1 << i) != 0 {
                            obj[j + i] = t.object;
                            if let Some(p) = prim.as_deref_mut() {
                                p[j + i] = t.source;
                            }
                        }
                    }
                }
                px += 4;
            }
            for px in px..x1 {
                let Some(z) = test(px as f32 + 0.5) else {
                    continue;
                };
                let j = row + px;
                if z < zbuf[j] {
                    zbuf[j] = z;
                    obj[j] = t.object;
                    if let Some(p) = prim.as_deref_mut() {
                        p[j] = t.source;
                    }
                }
            }
        }
    }
}

/// Rasterizes `objects` (pack id, object-to-world transform, mesh) for `camera`.
pub(crate) fn rasterize(
    camera: &Camera,
    objects: &[(u32, Affine3A, &TriangleMesh)],
) -> GeometryMask {
    let b = camera.basis();
    let w = camera.width as usize;
    let tris = project(camera, objects);
    let mut mask = GeometryMask::empty(camera.width, camera.height);
    mask.object
        .par_chunks_mut(w * BAND)
        .zip(mask.depth.par_chunks_mut(w * BAND))
        .zip(mask.position.par_chunks_mut(w * BAND))
        .zip(mask.normal.par_chunks_mut(w * BAND))
        .enumerate()
        .for_each(|(band, (((obj, dep), pos), nrm))| {
            let y0 = band * BAND;
            let mut prim = vec![u32::MAX; dep.len()];
            raster_band(&tris, w, y0, dep, obj, Some(&mut prim));
            for (j, (z, p)) in dep.iter_mut().zip(pos.iter_mut()).enumerate() {
                if z.is_finite() {
                    let (px, py) = ((j % w) as f32 + 0.5, (y0 + j / w) as f32 + 0.5);
                    let dir = b.direction(px, py);
                    let dist = *z / dir.dot(b.forward);
                    *z = dist;
                    *p = b.position + dir * dist;
                    nrm[j] = tris.world_normal(&b, prim[j]);
                }
            }
        });
    mask
}

/// Per pixel of `camera`'s image: the nearest of `tris`' objects (0: none), its triangle's
/// index into [`Projected::sources`] and the distance from the eye along the pixel's ray (∞:
/// none). What the material lookups of [`crate::shading`] need beside the mask.
pub(crate) fn rasterize_sources(
    camera: &Camera,
    tris: &Projected,
) -> (Vec<u32>, Vec<u32>, Vec<f32>) {
    let b = camera.basis();
    let (w, h) = (camera.width as usize, camera.height as usize);
    let mut object = vec![0u32; w * h];
    let mut prim = vec![u32::MAX; w * h];
    let mut depth = vec![f32::INFINITY; w * h];
    object
        .par_chunks_mut(w * BAND)
        .zip(prim.par_chunks_mut(w * BAND))
        .zip(depth.par_chunks_mut(w * BAND))
        .enumerate()
        .for_each(|(band, ((obj, pr), dep))| {
            let y0 = band * BAND;
            raster_band(tris, w, y0, dep, obj, Some(pr));
            for (j, z) in dep.iter_mut().enumerate() {
                if z.is_finite() {
                    let (px, py) = ((j % w) as f32 + 0.5, (y0 + j / w) as f32 + 0.5);
                    *z /= b.direction(px, py).dot(b.forward);
                }
            }
        });
    (object, prim, depth)
}
