//! Seam-aware addressing of a cube's texels for the denoiser ([`super`]): the texel at an
//! offset `(di, dj)` from another, found through its direction when the offset leaves the
//! face, so that a filter footprint continues onto the neighbouring face instead of being
//! clamped at the border (docs/architecture.md, pack v2: "continuous across cube seams").
//!
//! Addressing follows [`plenoptic_pack::cube`]: faces in KTX2 order, texel `(i, j)` of face
//! `f` at index `f·n² + j·n + i`, centre at `u = (i + ½)/n`, `v = (j + ½)/n`. An offset is
//! taken in the plane tangent to the sphere at the centre texel's direction, in steps of the
//! centre texel's own size along its `u` and `v` axes (gnomonic around the centre); the
//! direction reached may fall in another face (or, past a corner, in one of the faces that
//! meet there), and the texel holding it is the neighbour. So every texel's footprint is
//! symmetric on the sphere around it, and two texels either side of a seam get footprints of
//! the same shape and size (the face grids meet rotated by a multiple of 90°, which maps a
//! square kernel to itself). Simpler addressings leave a step at the seam (the set-up of the
//! seam test in `denoise::tests`: a smooth gradient across the −Y/+X seam, 64-px faces, 5
//! passes): offsets on the face's texel grid, continued on the face plane extended past its
//! edge, make a step of about 4× the steps beside it (the grid's steps grow towards the face
//! centre and shrink past the edge, so the footprints either side are lopsided in opposite
//! directions); the grid inside the face and tangent steps outside, about 3×; clamping at the
//! border, over 20×.

use glam::Vec3;
use plenoptic_pack::cube::{direction_to_texel, face_uv_to_direction, texel_direction};

/// A cube of face size `n`, with its texel directions.
#[derive(Debug, Clone)]
pub struct CubeGrid {
    n: usize,
    directions: Vec<Vec3>,
    /// Change of the unit direction per texel along `i` and along `j`, at each texel.
    steps: Vec<(Vec3, Vec3)>,
}

impl CubeGrid {
    /// The grid of a cube with `face_size` texels per edge (at least 1).
    pub fn new(face_size: u32) -> Self {
        let face_size = face_size.max(1);
        let n = face_size as usize;
        let h = 0.5 / n as f32;
        let steps = (0..6 * n * n)
            .map(|index| {
                let (face, rem) = (index / (n * n), index % (n * n));
                let u = ((rem % n) as f32 + 0.5) / n as f32;
                let v = ((rem / n) as f32 + 0.5) / n as f32;
                let d = |u: f32, v: f32| face_uv_to_direction(face, u, v);
                (d(u + h, v) - d(u - h, v), d(u, v + h) - d(u, v - h))
            })
            .collect();
        Self {
            n,
            directions: (0..6 * n * n)
                .map(|i| texel_direction(face_size, i))
                .collect(),
            steps,
        }
    }

    /// Texels per face edge.
    pub fn face_size(&self) -> usize {
        self.n
    }

    /// Texels in the cube, `6·n²`.
    pub fn len(&self) -> usize {
        self.directions.len()
    }

    /// Whether the cube has no texels (never: the face size is at least 1).
    pub fn is_empty(&self) -> bool {
        self.directions.is_empty()
    }

    /// Unit direction through the centre of texel `index`.
    pub fn direction(&self, index: usize) -> Vec3 {
        self.directions[index]
    }

    /// `(face, i, j)` of texel `index`.
    pub fn coords(&self, index: usize) -> (usize, usize, usize) {
        let nn = self.n * self.n;
        let (face, rem) = (index / nn, index % nn);
        (face, rem % self.n, rem / self.n)
    }

    /// The texel `(di, dj)` of `(face, i, j)`'s own texel steps away, in the plane tangent at
    /// its direction (see the module doc); the texel itself for `(0, 0)`.
    pub fn offset(&self, face: usize, i: usize, j: usize, di: i32, dj: i32) -> usize {
        let p = face * self.n * self.n + j * self.n + i;
        if di == 0 && dj == 0 {
            return p;
        }
        let (su, sv) = self.steps[p];
        let dir = self.directions[p] + su * di as f32 + sv * dj as f32;
        direction_to_texel(self.n as u32, dir)
    }
}
