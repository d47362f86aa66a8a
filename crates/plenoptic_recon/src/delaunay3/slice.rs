//! Slicing the complex with the plane t = const (thesis ch. 7: a frame of a temporal volume).

use super::DelaunayError;

/// Values that can be interpolated linearly along a tetrahedron edge.
pub trait Interpolate: Clone {
    /// `self + s · (other − self)`, for `s` in [0, 1].
    fn lerp(&self, other: &Self, s: f64) -> Self;
}

impl Interpolate for f64 {
    fn lerp(&self, other: &Self, s: f64) -> Self {
        self + s * (other - self)
    }
}

impl Interpolate for f32 {
    fn lerp(&self, other: &Self, s: f64) -> Self {
        (*self as f64 + s * (*other as f64 - *self as f64)) as f32
    }
}

impl<T: Interpolate + Copy, const N: usize> Interpolate for [T; N] {
    fn lerp(&self, other: &Self, s: f64) -> Self {
        std::array::from_fn(|i| self[i].lerp(&other[i], s))
    }
}

impl Interpolate for glam::Vec3 {
    fn lerp(&self, other: &Self, s: f64) -> Self {
        glam::Vec3::lerp(*self, *other, s as f32)
    }
}

impl Interpolate for glam::Vec4 {
    fn lerp(&self, other: &Self, s: f64) -> Self {
        glam::Vec4::lerp(*self, *other, s as f32)
    }
}

/// One triangle of a slice: its corners in (x, y), counter-clockwise, and the interpolated
/// values there.
#[derive(Debug, Clone, PartialEq)]
pub struct SliceTriangle<V> {
    /// The tetrahedron it was cut from (index into the `tets` given to [`slice_at`]).
    pub tet: u32,
    /// Corners (x, y), counter-clockwise (non-negative signed area).
    pub xy: [[f64; 2]; 3],
    /// Values at the corners, linearly interpolated along the cut edges.
    pub values: [V; 3],
}

impl<V> SliceTriangle<V> {
    /// Signed area in (x, y) (non-negative).
    pub fn area(&self) -> f64 {
        let [a, b, c] = self.xy;
        0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))
    }
}

/// Cuts the tetrahedra `tets` (over `points` in (x, y, t)) with the plane z = `t`, returning
/// triangles in (x, y) whose corner values interpolate `values` (one per point) linearly — the
/// reconstruction of a temporal volume's frame at time `t` (thesis ch. 7).
///
/// * A tetrahedron with vertices strictly on both sides gives one triangle (1 | 3 split, or
///   with vertices on the plane) or a quadrilateral cut into two triangles (2 | 2 split).
///   Crossing points are computed from the edge's lower endpoint, so neighbours agree bitwise.
/// * A face lying in the plane is returned once (not once per adjacent tetrahedron), attributed
///   to the lowest-indexed tetrahedron holding it; this includes hull faces, so slicing at the
///   first or last sample time still covers the hull's cross-section.
/// * Tetrahedra touching the plane only in an edge or a vertex contribute nothing.
///
/// The triangles of a Delaunay complex tile the cross-section of its convex hull without
/// overlap. Values of a function linear in (x, y, t) are reproduced exactly (up to rounding).
///
/// # Errors
///
/// [`DelaunayError::ValueCount`] when `values` is shorter than `points`,
/// [`DelaunayError::IndexOutOfRange`] when a tetrahedron names a missing point.
pub fn slice_at<V: Interpolate>(
    points: &[[f64; 3]],
    tets: &[[u32; 4]],
    values: &[V],
    t: f64,
) -> Result<Vec<SliceTriangle<V>>, DelaunayError> {
    if values.len() < points.len() {
        return Err(DelaunayError::ValueCount {
            values: values.len(),
            points: points.len(),
        });
    }
    let mut out = Vec::new();
    let mut planar: Vec<([u32; 3], u32)> = Vec::new();
    for (ti, tet) in tets.iter().enumerate() {
        if let Some(&index) = tet.iter().find(|&&i| i as usize >= points.len()) {
            return Err(DelaunayError::IndexOutOfRange {
                tet: ti,
                index,
                points: points.len(),
            });
        }
        let z = tet.map(|i| points[i as usize][2]);
        let below = z.iter().filter(|&&z| z < t).count();
        let above = z.iter().filter(|&&z| z > t).count();
        let on = 4 - below - above;
        if below == 0 || above == 0 {
            if on == 3 {
                let mut f: [u32; 3] = [0; 3];
                let mut k = 0;
                for (j, &zj) in z.iter().enumerate() {
                    if zj == t {
                        f[k] = tet[j];
                        k += 1;
                    }
                }
                f.sort_unstable();
                planar.push((f, ti as u32));
            }
            continue;
        }
        // Corners of the cut polygon, as (x, y, value).
        let mut corners: Vec<([f64; 2], V)> = Vec::with_capacity(4);
        let vertex = |i: u32| {
            let p = points[i as usize];
            ([p[0], p[1]], values[i as usize].clone())
        };
        for j in 0..4 {
            if z[j] == t {
                corners.push(vertex(tet[j]));
            }
        }
        // Crossing edges in cyclic order for the 2 | 2 case: (l0,h0), (l0,h1), (l1,h1), (l1,h0).
        let lows: Vec<usize> = (0..4).filter(|&j| z[j] < t).collect();
        let highs: Vec<usize> = (0..4).filter(|&j| z[j] > t).collect();
        let mut edges = Vec::with_capacity(4);
        match (lows.len(), highs.len()) {
            (2, 2) => {
                edges.extend([
                    (lows[0], highs[0]),
                    (lows[0], highs[1]),
                    (lows[1], highs[1]),
                    (lows[1], highs[0]),
                ]);
            }
            _ => {
                for &l in &lows {
                    for &h in &highs {
                        edges.push((l, h));
                    }
                }
            }
        }
        for (l, h) in edges {
            let (a, b) = (points[tet[l] as usize], points[tet[h] as usize]);
            let s = (t - a[2]) / (b[2] - a[2]);
            let xy = [a[0] + s * (b[0] - a[0]), a[1] + s * (b[1] - a[1])];
            let v = values[tet[l] as usize].lerp(&values[tet[h] as usize], s);
            corners.push((xy, v));
        }
        let tri = |a: usize, b: usize, c: usize| {
            ccw(
                ti as u32,
                [corners[a].0, corners[b].0, corners[c].0],
                [
                    corners[a].1.clone(),
                    corners[b].1.clone(),
                    corners[c].1.clone(),
                ],
            )
        };
        if corners.len() == 4 {
            out.push(tri(0, 1, 2));
            out.push(tri(0, 2, 3));
        } else {
            out.push(tri(0, 1, 2));
        }
    }
    planar.sort_unstable();
    planar.dedup_by_key(|(f, _)| *f);
    for (f, ti) in planar {
        let xy = f.map(|i| {
            let p = points[i as usize];
            [p[0], p[1]]
        });
        out.push(ccw(ti, xy, f.map(|i| values[i as usize].clone())));
    }
    Ok(out)
}

fn ccw<V>(tet: u32, mut xy: [[f64; 2]; 3], mut values: [V; 3]) -> SliceTriangle<V> {
    let [a, b, c] = xy;
    if (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]) < 0.0 {
        xy.swap(1, 2);
        values.swap(1, 2);
    }
    SliceTriangle { tet, xy, values }
}
