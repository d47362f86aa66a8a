//! Lighting looked up at a quarter of the pixels (docs/architecture.md, "Pack v2"): the
//! diffuse lighting is stored at cube resolution, so between two pixels it changes by a
//! small part of a texel's change; looking it up at every pixel mostly repeats itself.
//!
//! The *anchors* are the pixels of even row and even column. Their lookups are made as
//! every pixel's would be ([`crate::geometry`]). Every other pixel lies between two or four
//! anchors (its row's, its column's, or its diagonal's) and takes their mean, as a bilinear
//! filter at half resolution would, where that mean stands for its own lookup:
//! - every anchor shows the pixel's object and was answered by the cubes (no fallback);
//! - the anchors' lookups were accepted in the same keys, each with all four of its
//!   bilinear taps (a key's occlusion edge, a cube-face seam or an object's outline in a
//!   base view near them changes the blend abruptly, at that cube's texel edges);
//! - their triangles face the same way, within about 6° (no crease of the object between
//!   them: a box's edge);
//! - the pixel's distance is within half the depth tolerance of the anchors' mean (no
//!   depth step of the object between them).
//!
//! Elsewhere the pixel is looked up itself, so that edges stay at full resolution. The
//! frame differs from the dense one only by that interpolation inside smooth regions
//! (`sparse_lighting_agrees_with_every_pixel` in the tests). This is the lighting pass of
//! materials' frames only: radiance carries the texture and is looked up at every pixel.

use glam::Vec3;
use rayon::prelude::*;

use super::ROWS;
use super::rows::{Rows, lookup_some};
use crate::lookup::{NO_SLOT, Scratch, Shade};
use crate::raster::Projected;

/// One anchor's lookup.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Anchor {
    /// The blended colour and second colour.
    pub colour: Vec3,
    pub second: Vec3,
    /// The object seen, the distance along the anchor's ray and the unit normal of its
    /// triangle (camera space, either side).
    pub object: u32,
    pub distance: f32,
    pub normal: Vec3,
    /// Its keys' acceptance ([`crate::lookup::Scratch::accepted`]; [`UNANSWERED`] where no
    /// key answered or nothing is looked up).
    pub accepted: u32,
}

/// An anchor that no key answered, or with nothing to look up.
pub(crate) const UNANSWERED: u32 = 0;

/// Whether every key that answered an anchor did so with all four bilinear taps: where some
/// were refused (another object or distance in the base view's cube, near its outline there)
/// the blend changes at that cube's texel edges, between anchors too.
fn whole(accepted: u32) -> bool {
    const EVEN: u32 = 0x5555_5555;
    accepted & EVEN == (accepted >> 1) & EVEN
}

/// Anchors whose triangles' normals differ by more than about 6° (cosine below this) lie on
/// both sides of a crease: the lighting may change abruptly between them.
const CREASE: f32 = 0.995;

impl Default for Anchor {
    fn default() -> Self {
        Anchor {
            colour: Vec3::ZERO,
            second: Vec3::ZERO,
            object: 0,
            distance: f32::INFINITY,
            normal: Vec3::ZERO,
            accepted: UNANSWERED,
        }
    }
}

/// The anchors' lookups, at half resolution (anchor `(x, y)` of the frame is `(x/2, y/2)`).
pub(crate) struct Anchors {
    pub width: usize,
    pub height: usize,
    pub cells: Vec<Anchor>,
}

impl Anchors {
    /// The anchors of a `w` × `h` frame, unanswered.
    pub fn new(w: usize, h: usize) -> Self {
        let (width, height) = (w.div_ceil(2), h.div_ceil(2));
        Anchors {
            width,
            height,
            cells: vec![Anchor::default(); width * height],
        }
    }

    /// The colour and second colour of pixel `(x, y)` of object `o` at distance `dist`
    /// from its anchors, where they stand for its own lookup (the module doc; `tol`: the
    /// relative depth tolerance); `None` where it must be looked up.
    #[inline]
    pub fn interpolate(
        &self,
        x: usize,
        y: usize,
        o: u32,
        dist: f32,
        tol: f32,
    ) -> Option<(Vec3, Vec3)> {
        let (ax, ay) = (x / 2, y / 2);
        let (nx, ny) = (1 + x % 2, 1 + y % 2);
        if ax + nx > self.width || ay + ny > self.height {
            return None;
        }
        let first = ay * self.width + ax;
        let (signature, normal) = (self.cells[first].accepted, self.cells[first].normal);
        if signature == UNANSWERED || !whole(signature) {
            return None;
        }
        let (mut c, mut c2, mut d) = (Vec3::ZERO, Vec3::ZERO, 0.0);
        for j in 0..ny {
            for i in 0..nx {
                let a = &self.cells[first + j * self.width + i];
                if a.accepted != signature || a.object != o || a.normal.dot(normal).abs() < CREASE {
                    return None;
                }
                c += a.colour;
                c2 += a.second;
                d += a.distance;
            }
        }
        let k = 1.0 / (nx * ny) as f32;
        ((d * k - dist).abs() <= 0.5 * tol * dist).then_some((c * k, c2 * k))
    }
}

/// The anchors' pass: the mask rasterized band by band with each pixel's triangle, its depths
/// made distances along the rays ([`Rows::distances`]), and the anchors looked up.
pub(super) struct AnchorPass<'a> {
    pub tris: &'a Projected,
    pub rows: &'a Rows<'a>,
    pub shade: &'a Shade<'a>,
    /// Pixels per band of [`ROWS`] rows.
    pub band: usize,
}

impl AnchorPass<'_> {
    /// Fills `depth` (distances), `object` and `prims` (each pixel's triangle: index into
    /// the projected sources, `u32::MAX` where none) for the whole frame, and returns the
    /// anchors.
    pub fn run(&self, depth: &mut [f32], object: &mut [u32], prims: &mut Vec<u32>) -> Anchors {
        let (w, band, tris, rows) = (self.rows.width, self.band, self.tris, self.rows);
        let h = depth.len() / w.max(1);
        let mut anchors = Anchors::new(w, h);
        let aw = anchors.width;
        prims.clear();
        prims.par_extend(rayon::iter::repeat_n(u32::MAX, depth.len()));
        depth
            .par_chunks_mut(band)
            .zip(object.par_chunks_mut(band))
            .zip(prims.par_chunks_mut(band))
            .zip(anchors.cells.par_chunks_mut((aw * ROWS / 2).max(1)))
            .enumerate()
            .for_each_init(
                || (Scratch::default(), Scratch::default(), Vec::new()),
                |(s, packed, xs), (i, (((dep, obj), prim), cells))| {
                    let y0 = i * ROWS;
                    crate::raster::raster_band(tris, w, y0, dep, obj, Some(prim));
                    let lines = dep.chunks_mut(w).zip(obj.chunks_mut(w));
                    for (r, (dep, obj)) in lines.enumerate() {
                        rows.distances(y0 + r, dep, obj);
                        if r % 2 == 1 {
                            continue;
                        }
                        s.slot.resize(w, NO_SLOT);
                        rows.slots(&mut s.slot, y0 + r, obj, None);
                        let line = &mut cells[(r / 2) * aw..][..aw];
                        for (ax, cell) in line.iter_mut().enumerate() {
                            let x = 2 * ax;
                            cell.object = obj[x];
                            cell.distance = dep[x];
                            if obj[x] != 0 {
                                let t = prim[r * w + x] as usize;
                                cell.normal = tris.normals.get(t).copied().unwrap_or_default();
                            }
                        }
                        xs.clear();
                        xs.extend((0..w).step_by(2).filter(|&x| s.slot[x] != NO_SLOT));
                        packed.gather_rays(rows.basis, y0 + r, xs, dep, &s.slot);
                        rows.normals(packed, y0 + r, Some(xs), &prim[r * w..(r + 1) * w]);
                        lookup_some(self.shade, packed, true, xs, obj, |accepted, x, c, c2| {
                            if c.w > 0.0 {
                                let cell = &mut line[x / 2];
                                cell.colour = c.truncate() / c.w;
                                cell.second = c2 / c.w;
                                cell.accepted = accepted;
                            }
                        });
                    }
                },
            );
        anchors
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn anchors() -> Anchors {
        let mut a = Anchors::new(5, 4);
        for j in 0..a.height {
            for i in 0..a.width {
                a.cells[j * a.width + i] = Anchor {
                    colour: Vec3::splat((i + 10 * j) as f32),
                    second: Vec3::ONE,
                    object: 7,
                    distance: 2.0,
                    normal: Vec3::Y,
                    accepted: 0b1111,
                };
            }
        }
        a
    }

    #[test]
    fn pixels_between_agreeing_anchors_take_their_mean() {
        let a = anchors();
        assert_eq!((a.width, a.height), (3, 2));
        // An anchor itself, a pixel between two in a row, in a column, and between four.
        let at = |x, y| a.interpolate(x, y, 7, 2.0, 0.03).map(|c| c.0.x);
        assert_eq!(at(2, 2), Some(11.0));
        assert_eq!(at(1, 0), Some(0.5));
        assert_eq!(at(2, 1), Some(6.0));
        assert_eq!(at(3, 1), Some(6.5));
        // Past the last anchor of a row or column.
        assert_eq!(at(1, 3), None);
        assert_eq!(a.interpolate(1, 0, 7, 2.0, 0.03).unwrap().1, Vec3::ONE);
    }

    #[test]
    fn disagreeing_anchors_refuse() {
        let a = anchors();
        // Another object, a depth step, another acceptance, an unanswered anchor, another
        // object's anchor, a crease.
        assert!(a.interpolate(1, 1, 8, 2.0, 0.03).is_none());
        assert!(a.interpolate(1, 1, 7, 2.2, 0.03).is_none());
        let mut b = anchors();
        b.cells[4].accepted = 0b0011;
        // A key that answered with part of its taps.
        let mut e = anchors();
        e.cells[0].accepted = 0b0111;
        e.cells[1].accepted = 0b0111;
        assert!(e.interpolate(1, 0, 7, 2.0, 0.03).is_none());
        assert!(b.interpolate(3, 1, 7, 2.0, 0.03).is_none());
        assert!(b.interpolate(1, 1, 7, 2.0, 0.03).is_none());
        assert!(b.interpolate(0, 1, 7, 2.0, 0.03).is_some());
        b.cells[0].accepted = UNANSWERED;
        assert!(b.interpolate(0, 0, 7, 2.0, 0.03).is_none());
        let mut c = anchors();
        c.cells[1].object = 3;
        assert!(c.interpolate(2, 1, 7, 2.0, 0.03).is_none());
        assert!(c.interpolate(0, 1, 7, 2.0, 0.03).is_some());
        // A crease.
        let mut d = anchors();
        d.cells[1].normal = Vec3::new(0.0, 0.9, 0.43).normalize();
        assert!(d.interpolate(1, 0, 7, 2.0, 0.03).is_none());
        assert!(d.interpolate(3, 0, 7, 2.0, 0.03).is_none());
        assert!(d.interpolate(4, 0, 7, 2.0, 0.03).is_some());
    }
}
