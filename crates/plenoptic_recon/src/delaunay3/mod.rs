//! The (x, y, t) Delaunay complex of a temporal volume, and its slices at t = const.
//!
//! Nimeroff's thesis (1997, ch. 7, "temporal volumes") stores the radiance seen through a
//! region over a span of time as scattered samples in (x, y, t): x, y a 2D parametrisation of
//! direction (octahedral or cube-face coordinates), t the (scaled) time. A frame at time t is
//! reconstructed by slicing the 3D Delaunay complex of the samples with the plane t = const and
//! interpolating linearly over the resulting triangles. This module builds that complex
//! ([`tetrahedralize`]) and slices it ([`slice_at`]); the complex is stored as tetrahedra of
//! sample indices (`[u32; 4]`).
//!
//! # Algorithm
//!
//! Incremental Bowyer–Watson insertion (A. Bowyer, "Computing Dirichlet tessellations", and
//! D. F. Watson, "Computing the n-dimensional Delaunay tessellation with application to Voronoi
//! polytopes", both The Computer Journal 24(2), 1981):
//!
//! * the points are inserted in a *biased randomised insertion order* (BRIO: random rounds of
//!   doubling size, each round sorted along a 3D Hilbert curve), so that consecutive points are
//!   close and the expected work stays near linear;
//! * each point is located by a visibility walk (with `orient3d`) from the last created
//!   tetrahedron;
//! * the cavity (all tetrahedra whose open circumball contains the point) is grown by a
//!   breadth-first search over neighbours with `insphere`, removed, and its boundary is joined
//!   to the point; face adjacency is maintained throughout.
//!
//! Instead of a finite super-tetrahedron (which can leave the result short of the convex hull),
//! the triangulation is closed by a symbolic *vertex at infinity*: every convex-hull facet carries
//! a "ghost" tetrahedron. A point conflicts with a ghost when it lies strictly outside that hull
//! facet, or in its plane and strictly inside its circumcircle (tested exactly as `insphere`
//! against the facet and the finite tetrahedron behind it, whose circumsphere cuts the facet's
//! plane in exactly that circle). The output therefore covers the convex hull exactly.
//!
//! All geometric decisions use Shewchuk's adaptive exact predicates (J. R. Shewchuk, "Adaptive
//! Precision Floating-Point Arithmetic and Fast Robust Geometric Predicates", Discrete Comput.
//! Geom. 18, 1997) from the `robust` crate. Cospherical ties (`insphere == 0`) count as *no*
//! conflict, consistently; the result is then one valid Delaunay tetrahedralization among
//! several (every tetrahedron still has an empty open circumball). The whole computation is
//! deterministic: the same input gives the same output, bit for bit.
//!
//! # Conventions
//!
//! A tetrahedron `[a, b, c, d]` is *positively oriented*: its signed volume
//! `(b − a) · ((c − a) × (d − a)) / 6` is positive (right-handed; equivalently
//! `robust::orient3d(a, b, c, d) < 0` in Shewchuk's sign convention). See [`signed_volume`].

use robust::Coord3D;
use thiserror::Error;

mod order;
mod slice;
mod validate;

pub use slice::{Interpolate, SliceTriangle, slice_at};
pub use validate::validate;

/// Marks a hull face in [`Tetrahedralization::neighbours`]: no tetrahedron lies across it.
pub const NO_NEIGHBOUR: u32 = u32::MAX;

/// The symbolic vertex at infinity (internal).
const INF: u32 = u32::MAX;

/// `FACE[i]`: the face opposite vertex `i`, ordered so that vertex `i` lies on its positive
/// side (`(FACE[i], i)` is an even permutation of `(0, 1, 2, 3)`).
const FACE: [[usize; 3]; 4] = [[1, 3, 2], [0, 2, 3], [0, 3, 1], [0, 1, 2]];

/// Why a point set could not be tetrahedralized (or a slice not taken).
#[derive(Debug, Clone, PartialEq, Error)]
pub enum DelaunayError {
    /// A coordinate is NaN or infinite.
    #[error("point {index} has a non-finite coordinate: {point:?}")]
    NonFinite {
        /// Index of the offending point in the input.
        index: usize,
        /// Its coordinates.
        point: [f64; 3],
    },
    /// More points than `u32` indices can address.
    #[error("{0} points: at most {max} are supported", max = u32::MAX - 1)]
    TooManyPoints(usize),
    /// Fewer than four distinct points.
    #[error("only {distinct} distinct points: a tetrahedralization needs at least 4")]
    TooFewPoints {
        /// Number of distinct input points.
        distinct: usize,
    },
    /// All distinct points lie on one line.
    #[error("all points are collinear: no tetrahedron exists")]
    Collinear,
    /// All distinct points lie in one plane (e.g. every sample has the same time).
    #[error("all points are coplanar: no tetrahedron exists")]
    Coplanar,
    /// A slice was asked with a value array shorter than the point array.
    #[error("{values} values for {points} points")]
    ValueCount {
        /// Number of values given.
        values: usize,
        /// Number of points.
        points: usize,
    },
    /// A tetrahedron refers to a point that does not exist.
    #[error("tetrahedron {tet} refers to point {index}, but there are only {points} points")]
    IndexOutOfRange {
        /// Index of the tetrahedron.
        tet: usize,
        /// The bad point index.
        index: u32,
        /// Number of points.
        points: usize,
    },
    /// An internal invariant broke (a bug; please report with the input).
    #[error("internal error: {0}")]
    Internal(String),
}

/// A Delaunay tetrahedralization of a point set, as produced by [`tetrahedralize`].
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Tetrahedralization {
    /// The tetrahedra, as indices into the input points, each positively oriented (positive
    /// [`signed_volume`]). Together they cover the convex hull of the input exactly.
    pub tets: Vec<[u32; 4]>,
    /// `neighbours[t][i]`: the tetrahedron across the face opposite `tets[t][i]`, or
    /// [`NO_NEIGHBOUR`] on the convex hull.
    pub neighbours: Vec<[u32; 4]>,
    /// Indices of input points that were not inserted because they repeat an earlier point
    /// exactly (ascending).
    pub skipped: Vec<u32>,
    /// For each entry of `skipped`, the index of the point it duplicates (the lowest index with
    /// the same coordinates; that one is a vertex of the complex).
    pub duplicate_of: Vec<u32>,
}

impl Tetrahedralization {
    /// Slices this complex with the plane z = `t`; see [`slice_at`].
    pub fn slice<V: Interpolate>(
        &self,
        points: &[[f64; 3]],
        values: &[V],
        t: f64,
    ) -> Result<Vec<SliceTriangle<V>>, DelaunayError> {
        slice_at(points, &self.tets, values, t)
    }
}

/// Signed volume of tetrahedron `tet` (positive for the orientation used by this module).
/// Plain floating point; the exact sign is `-robust::orient3d(a, b, c, d)`.
pub fn signed_volume(points: &[[f64; 3]], tet: [u32; 4]) -> f64 {
    let [a, b, c, d] = tet.map(|i| points[i as usize]);
    let u = sub(b, a);
    let v = sub(c, a);
    let w = sub(d, a);
    (u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0])
        + u[2] * (v[0] * w[1] - v[1] * w[0]))
        / 6.0
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

// ---------------------------------------------------------------------------------------------
// Exact predicates, in this module's (right-handed) orientation convention.

#[inline]
fn c3(p: [f64; 3]) -> Coord3D<f64> {
    Coord3D {
        x: p[0],
        y: p[1],
        z: p[2],
    }
}

/// Positive when `d` lies on the side of plane `abc` that `(b − a) × (c − a)` points to.
#[inline]
fn orient(a: [f64; 3], b: [f64; 3], c: [f64; 3], d: [f64; 3]) -> f64 {
    -robust::orient3d(c3(a), c3(b), c3(c), c3(d))
}

/// For positively oriented `abcd`: positive when `e` is strictly inside the circumsphere.
#[inline]
fn insphere(a: [f64; 3], b: [f64; 3], c: [f64; 3], d: [f64; 3], e: [f64; 3]) -> f64 {
    robust::insphere(c3(b), c3(a), c3(c), c3(d), c3(e))
}

fn collinear(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> bool {
    let o = |i: usize, j: usize| {
        robust::orient2d(
            robust::Coord { x: a[i], y: a[j] },
            robust::Coord { x: b[i], y: b[j] },
            robust::Coord { x: c[i], y: c[j] },
        )
    };
    o(0, 1) == 0.0 && o(1, 2) == 0.0 && o(2, 0) == 0.0
}

// ---------------------------------------------------------------------------------------------
// The incremental builder.

struct Builder<'a> {
    pts: &'a [[f64; 3]],
    tets: Vec<[u32; 4]>,
    nbrs: Vec<[u32; 4]>,
    alive: Vec<bool>,
    free: Vec<u32>,
    hint: u32,
    rng: u64,
    stamp: Vec<u32>,
    conflict: Vec<bool>,
    epoch: u32,
    stack: Vec<u32>,
    cavity: Vec<u32>,
    boundary: Vec<(u32, u8)>,
    edges: Vec<(u64, u32, u8)>,
}

impl<'a> Builder<'a> {
    fn p(&self, v: u32) -> [f64; 3] {
        self.pts[v as usize]
    }

    fn new_tet(&mut self, v: [u32; 4], n: [u32; 4]) -> u32 {
        if let Some(t) = self.free.pop() {
            self.tets[t as usize] = v;
            self.nbrs[t as usize] = n;
            self.alive[t as usize] = true;
            t
        } else {
            self.tets.push(v);
            self.nbrs.push(n);
            self.alive.push(true);
            self.stamp.push(0);
            self.conflict.push(false);
            (self.tets.len() - 1) as u32
        }
    }

    fn next_rand(&mut self) -> u64 {
        self.rng ^= self.rng << 13;
        self.rng ^= self.rng >> 7;
        self.rng ^= self.rng << 17;
        self.rng
    }

    /// Starts from the positively oriented finite tetrahedron `v` and its four ghosts.
    fn start(pts: &'a [[f64; 3]], v: [u32; 4], capacity: usize) -> Result<Self, DelaunayError> {
        let mut b = Builder {
            pts,
            tets: Vec::with_capacity(capacity),
            nbrs: Vec::with_capacity(capacity),
            alive: Vec::with_capacity(capacity),
            free: Vec::new(),
            hint: 0,
            rng: 0x2545_F491_4F6C_DD1D,
            stamp: Vec::with_capacity(capacity),
            conflict: Vec::with_capacity(capacity),
            epoch: 0,
            stack: Vec::new(),
            cavity: Vec::new(),
            boundary: Vec::new(),
            edges: Vec::new(),
        };
        let t0 = b.new_tet(v, [NO_NEIGHBOUR; 4]);
        b.edges.clear();
        for (i, face) in FACE.iter().enumerate() {
            let f = face.map(|k| v[k]);
            // Swapping two face vertices puts the vertex at infinity on the outer side.
            let g = b.new_tet(
                [f[1], f[0], f[2], INF],
                [NO_NEIGHBOUR, NO_NEIGHBOUR, NO_NEIGHBOUR, t0],
            );
            b.nbrs[t0 as usize][i] = g;
            b.push_edges(g);
        }
        b.link_edges()?;
        b.hint = t0;
        Ok(b)
    }

    /// Records the three faces of new tetrahedron `t` that contain its vertex 3, keyed by the
    /// edge they share with the cavity boundary.
    fn push_edges(&mut self, t: u32) {
        let v = self.tets[t as usize];
        for m in 0..3u8 {
            let (a, b) = match m {
                0 => (v[1], v[2]),
                1 => (v[0], v[2]),
                _ => (v[0], v[1]),
            };
            let key = ((a.min(b) as u64) << 32) | a.max(b) as u64;
            self.edges.push((key, t, m));
        }
    }

    fn link_edges(&mut self) -> Result<(), DelaunayError> {
        self.edges.sort_unstable();
        if !self.edges.len().is_multiple_of(2) {
            return Err(DelaunayError::Internal("odd cavity boundary".into()));
        }
        for pair in self.edges.chunks_exact(2) {
            let (k1, t1, m1) = pair[0];
            let (k2, t2, m2) = pair[1];
            if k1 != k2 {
                return Err(DelaunayError::Internal(
                    "cavity boundary is not closed".into(),
                ));
            }
            self.nbrs[t1 as usize][m1 as usize] = t2;
            self.nbrs[t2 as usize][m2 as usize] = t1;
        }
        self.edges.clear();
        Ok(())
    }

    fn in_conflict(&self, t: u32, p: [f64; 3]) -> bool {
        let v = self.tets[t as usize];
        match v.iter().position(|&x| x == INF) {
            None => {
                let [a, b, c, d] = v.map(|i| self.p(i));
                insphere(a, b, c, d, p) > 0.0
            }
            Some(k) => {
                let f = FACE[k].map(|i| v[i]);
                let [a, b, c] = f.map(|i| self.p(i));
                let o = orient(a, b, c, p);
                if o != 0.0 {
                    return o > 0.0;
                }
                // In the hull facet's plane: inside its circumcircle iff inside the
                // circumsphere of the finite tetrahedron behind it.
                let n = self.nbrs[t as usize][k];
                let nv = self.tets[n as usize];
                let Some(j) = self.nbrs[n as usize].iter().position(|&x| x == t) else {
                    return false;
                };
                insphere(b, a, c, self.p(nv[j]), p) > 0.0
            }
        }
    }

    /// A tetrahedron in conflict with point `pi`, or `None` when `pi` repeats a vertex.
    fn locate(&mut self, pi: u32) -> Option<u32> {
        let p = self.p(pi);
        let mut t = self.hint;
        let mut prev = NO_NEIGHBOUR;
        let cap = 4 * self.tets.len() + 64;
        for _ in 0..cap {
            let v = self.tets[t as usize];
            if v.contains(&INF) {
                // Crossed a hull facet strictly: p is outside it, so this ghost conflicts.
                return Some(t);
            }
            let r = (self.next_rand() >> 32) as usize;
            let mut next = None;
            for k in 0..4 {
                let i = (r + k) & 3;
                let n = self.nbrs[t as usize][i];
                if n == prev {
                    continue;
                }
                let f = FACE[i];
                if orient(self.p(v[f[0]]), self.p(v[f[1]]), self.p(v[f[2]]), p) < 0.0 {
                    next = Some(n);
                    break;
                }
            }
            match next {
                Some(n) => {
                    prev = t;
                    t = n;
                }
                None => {
                    // p lies in the closed tetrahedron: strictly inside its circumball unless
                    // it is one of its vertices.
                    return if v.iter().any(|&x| self.p(x) == p) {
                        None
                    } else {
                        Some(t)
                    };
                }
            }
        }
        // The walk cannot cycle in a Delaunay triangulation; this is only a safety net.
        (0..self.tets.len() as u32).find(|&t| self.alive[t as usize] && self.in_conflict(t, p))
    }

    /// Inserts point `pi`; `Ok(false)` when it repeats a vertex.
    fn insert(&mut self, pi: u32) -> Result<bool, DelaunayError> {
        let Some(seed) = self.locate(pi) else {
            return Ok(false);
        };
        let p = self.p(pi);
        self.epoch = self.epoch.wrapping_add(1);
        if self.epoch == 0 {
            self.stamp.fill(0);
            self.epoch = 1;
        }
        let epoch = self.epoch;
        self.cavity.clear();
        self.boundary.clear();
        self.stack.clear();
        self.stamp[seed as usize] = epoch;
        self.conflict[seed as usize] = true;
        self.stack.push(seed);
        while let Some(t) = self.stack.pop() {
            self.cavity.push(t);
            for i in 0..4 {
                let n = self.nbrs[t as usize][i];
                if self.stamp[n as usize] != epoch {
                    self.stamp[n as usize] = epoch;
                    let c = self.in_conflict(n, p);
                    self.conflict[n as usize] = c;
                    if c {
                        self.stack.push(n);
                        continue;
                    }
                } else if self.conflict[n as usize] {
                    continue;
                }
                self.boundary.push((t, i as u8));
            }
        }
        let mut first_finite = None;
        for bi in 0..self.boundary.len() {
            let (c, i) = self.boundary[bi];
            let v = self.tets[c as usize];
            let n = self.nbrs[c as usize][i as usize];
            let f = FACE[i as usize].map(|k| v[k]);
            let nt = self.new_tet(
                [f[0], f[1], f[2], pi],
                [NO_NEIGHBOUR, NO_NEIGHBOUR, NO_NEIGHBOUR, n],
            );
            let Some(j) = self.nbrs[n as usize].iter().position(|&x| x == c) else {
                return Err(DelaunayError::Internal("asymmetric adjacency".into()));
            };
            self.nbrs[n as usize][j] = nt;
            if first_finite.is_none() && !f.contains(&INF) {
                first_finite = Some(nt);
            }
            self.push_edges(nt);
        }
        self.link_edges()?;
        for &t in &self.cavity {
            self.alive[t as usize] = false;
        }
        self.free.extend_from_slice(&self.cavity);
        match first_finite {
            Some(t) => self.hint = t,
            None if self.alive[self.hint as usize] => {}
            None => {
                self.hint = (0..self.tets.len() as u32)
                    .find(|&t| self.alive[t as usize] && !self.tets[t as usize].contains(&INF))
                    .ok_or_else(|| DelaunayError::Internal("no finite tetrahedron".into()))?;
            }
        }
        Ok(true)
    }

    fn finish(self, skipped: Vec<u32>, duplicate_of: Vec<u32>) -> Tetrahedralization {
        let mut map = vec![NO_NEIGHBOUR; self.tets.len()];
        let mut tets = Vec::new();
        for (t, v) in self.tets.iter().enumerate() {
            if self.alive[t] && !v.contains(&INF) {
                map[t] = tets.len() as u32;
                tets.push(*v);
            }
        }
        let neighbours = (0..self.tets.len())
            .filter(|&t| map[t] != NO_NEIGHBOUR)
            .map(|t| self.nbrs[t].map(|n| map[n as usize]))
            .collect();
        Tetrahedralization {
            tets,
            neighbours,
            skipped,
            duplicate_of,
        }
    }
}

/// The 3D Delaunay tetrahedralization of `points` (Bowyer–Watson on exact predicates; see the
/// module documentation).
///
/// Points that repeat an earlier point exactly are skipped and reported in
/// [`Tetrahedralization::skipped`]. Every other point is a vertex of the result, which covers
/// the convex hull of the input; every tetrahedron is positively oriented and has an empty open
/// circumball. Cospherical configurations are resolved deterministically.
///
/// # Errors
///
/// [`DelaunayError::NonFinite`] (naming the first bad index), [`DelaunayError::TooManyPoints`],
/// and for degenerate input — fewer than four distinct points, or all points collinear or
/// coplanar — [`DelaunayError::TooFewPoints`], [`DelaunayError::Collinear`] or
/// [`DelaunayError::Coplanar`] (there is no tetrahedron to return). Coordinates must also stay
/// far from overflow (|x| well below 1e60) for the predicates to be exact.
pub fn tetrahedralize(points: &[[f64; 3]]) -> Result<Tetrahedralization, DelaunayError> {
    if points.len() >= u32::MAX as usize - 1 {
        return Err(DelaunayError::TooManyPoints(points.len()));
    }
    if let Some(index) = points.iter().position(|p| p.iter().any(|c| !c.is_finite())) {
        return Err(DelaunayError::NonFinite {
            index,
            point: points[index],
        });
    }
    // Exact duplicates (with −0 == +0): keep the lowest index of each run.
    let norm = |i: u32| points[i as usize].map(|c| c + 0.0);
    let mut sorted: Vec<u32> = (0..points.len() as u32).collect();
    sorted.sort_unstable_by(|&a, &b| {
        let (pa, pb) = (norm(a), norm(b));
        pa[0]
            .total_cmp(&pb[0])
            .then(pa[1].total_cmp(&pb[1]))
            .then(pa[2].total_cmp(&pb[2]))
            .then(a.cmp(&b))
    });
    let mut dup_pairs = Vec::new();
    let mut ids = Vec::with_capacity(points.len());
    let mut run_first = None;
    for &i in &sorted {
        match run_first {
            Some(f) if points[f as usize] == points[i as usize] => dup_pairs.push((i, f)),
            _ => {
                run_first = Some(i);
                ids.push(i);
            }
        }
    }
    dup_pairs.sort_unstable();
    let (mut skipped, mut duplicate_of): (Vec<u32>, Vec<u32>) = dup_pairs.into_iter().unzip();
    if ids.len() < 4 {
        return Err(DelaunayError::TooFewPoints {
            distinct: ids.len(),
        });
    }
    order::insertion_order(points, &mut ids);

    // The first non-degenerate tetrahedron in insertion order.
    let p = |i: u32| points[i as usize];
    let (a, b) = (ids[0], ids[1]);
    let c = ids[2..]
        .iter()
        .position(|&c| !collinear(p(a), p(b), p(c)))
        .ok_or(DelaunayError::Collinear)?
        + 2;
    let d = ids[c + 1..]
        .iter()
        .position(|&d| orient(p(a), p(b), p(ids[c]), p(d)) != 0.0)
        .ok_or(DelaunayError::Coplanar)?
        + c
        + 1;
    let (c_id, d_id) = (ids[c], ids[d]);
    let first = if orient(p(a), p(b), p(c_id), p(d_id)) > 0.0 {
        [a, b, c_id, d_id]
    } else {
        [b, a, c_id, d_id]
    };
    ids.remove(d);
    ids.remove(c);
    let mut builder = Builder::start(points, first, 7 * ids.len() + 16)?;
    for &i in &ids[2..] {
        if !builder.insert(i)? {
            // Unreachable after the exact de-duplication above, but harmless.
            let k = skipped.partition_point(|&s| s < i);
            let of = (0..points.len() as u32)
                .find(|&j| points[j as usize] == points[i as usize])
                .unwrap_or(i);
            skipped.insert(k, i);
            duplicate_of.insert(k, of);
        }
    }
    Ok(builder.finish(skipped, duplicate_of))
}
