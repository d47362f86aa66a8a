//! Seam-aware addressing of a cube's texels for the denoiser ([`super`]): the texel at an
//! offset `(di, dj)` from another, found through its direction when the offset leaves the
//! face, so that a filter footprint continues onto the neighbouring face instead of being
//! clamped at the border (docs/architecture.md, pack v2: "continuous across cube seams").
//!
//! Addressing follows [`plenoptic_pack::cube`]: faces in KTX2 order, texel `(i, j)` of face
//! `f` at index `f·n² + j·n + i`, centre at `u = (i + ½)/n`, `v = (j + ½)/n`. An offset texel
//! outside the face is the point `(u, v)` on the face's plane extended past its edge; its
//! direction falls in the adjacent face (or, past a corner, in one of the two or three faces
//! that meet there), and the texel holding that direction is the neighbour. Across an edge the
//! texel grid of the next face is continuous in direction but rotated, so the neighbourhood
//! there is the same set of surface points a single larger face would have had, up to the
//! perspective stretch of the extended plane (small for the offsets of a denoiser: at most a
//! quarter face).

use glam::Vec3;
use plenoptic_pack::cube::{direction_to_texel, face_uv_to_direction, texel_direction};

/// A cube of face size `n`, with its texel directions.
#[derive(Debug, Clone)]
pub struct CubeGrid {
    n: usize,
    directions: Vec<Vec3>,
}

impl CubeGrid {
    /// The grid of a cube with `face_size` texels per edge (at least 1).
    pub fn new(face_size: u32) -> Self {
        let face_size = face_size.max(1);
        let n = face_size as usize;
        Self {
            n,
            directions: (0..6 * n * n)
                .map(|i| texel_direction(face_size, i))
                .collect(),
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

    /// The texel `(di, dj)` texels away from `(face, i, j)`: on the same face while the offset
    /// stays on it, else through the direction of the extended face plane (see the module doc).
    pub fn offset(&self, face: usize, i: usize, j: usize, di: i32, dj: i32) -> usize {
        let n = self.n as i64;
        let (ii, jj) = (i as i64 + i64::from(di), j as i64 + i64::from(dj));
        if (0..n).contains(&ii) && (0..n).contains(&jj) {
            return face * self.n * self.n + jj as usize * self.n + ii as usize;
        }
        let u = (ii as f32 + 0.5) / n as f32;
        let v = (jj as f32 + 0.5) / n as f32;
        direction_to_texel(self.n as u32, face_uv_to_direction(face, u, v))
    }
}
