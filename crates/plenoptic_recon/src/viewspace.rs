//! Blending weights of base views by the camera's position in the view space (thesis §6.7:
//! view interpolation between the base views around the camera; docs/architecture.md, "Reconstruction").
//!
//! - segment: the base views are ordered by their parameter along the segment; the camera's
//!   parameter picks the bracketing pair, weighted linearly;
//! - rectangle (2D): the base views are projected to the rectangle's plane and triangulated
//!   (Delaunay, spade); the camera's barycentric coordinates in its triangle are the weights;
//!   outside the hull, the nearest views by inverse distance;
//! - box (3D) and every degenerate case: the (up to) four nearest views by inverse distance.

use glam::{Vec2, Vec3};
use plenoptic_pack::{BaseView, ViewSpace};
use spade::{DelaunayTriangulation, HasPosition, Point2, PositionInTriangulation, Triangulation};

#[derive(Clone, Copy, Debug)]
struct Site {
    p: Point2<f64>,
    view: usize,
}

impl HasPosition for Site {
    type Scalar = f64;
    fn position(&self) -> Point2<f64> {
        self.p
    }
}

enum Kind {
    Segment {
        a: Vec3,
        dir: Vec3,
        order: Vec<(f32, usize)>,
    },
    Plane {
        origin: Vec3,
        u: Vec3,
        v: Vec3,
        tri: Box<DelaunayTriangulation<Site>>,
    },
    Nearest,
}

/// Computes base-view weights for camera positions.
pub struct ViewWeights {
    positions: Vec<Vec3>,
    kind: Kind,
}

impl std::fmt::Debug for ViewWeights {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ViewWeights")
            .field("positions", &self.positions)
            .finish()
    }
}

impl ViewWeights {
    /// Prepares the weights for `views` in `space`. Only views with `usable[i]` take part
    /// (pass all `true` to use every view).
    pub fn new(space: &ViewSpace, views: &[BaseView], usable: &[bool]) -> Self {
        let positions: Vec<Vec3> = views.iter().map(|v| v.position).collect();
        let ok = |i: usize| usable.get(i).copied().unwrap_or(true);
        let kind = match space {
            ViewSpace::Segment { a, b } if (*b - *a).length() > 1e-6 => {
                let dir = (*b - *a).normalize();
                let mut order: Vec<(f32, usize)> = (0..views.len())
                    .filter(|&i| ok(i))
                    .map(|i| ((positions[i] - *a).dot(dir), i))
                    .collect();
                order.sort_by(|x, y| x.0.total_cmp(&y.0));
                Kind::Segment { a: *a, dir, order }
            }
            ViewSpace::Rectangle { corners } => {
                let origin = corners[0];
                let u = (corners[1] - corners[0]).normalize_or_zero();
                let n = u.cross(corners[3] - corners[0]);
                let v = n.cross(u).normalize_or_zero();
                let mut tri = DelaunayTriangulation::<Site>::new();
                for i in (0..views.len()).filter(|&i| ok(i)) {
                    let d = positions[i] - origin;
                    let _ = tri.insert(Site {
                        p: Point2::new(d.dot(u) as f64, d.dot(v) as f64),
                        view: i,
                    });
                }
                if u == Vec3::ZERO || v == Vec3::ZERO || tri.num_inner_faces() == 0 {
                    Kind::Nearest
                } else {
                    Kind::Plane {
                        origin,
                        u,
                        v,
                        tri: Box::new(tri),
                    }
                }
            }
            _ => Kind::Nearest,
        };
        let positions = positions
            .into_iter()
            .enumerate()
            .map(|(i, p)| if ok(i) { p } else { Vec3::splat(f32::INFINITY) })
            .collect();
        ViewWeights { positions, kind }
    }

    /// `(base view index, weight)` pairs with positive weights summing to 1 (empty only if no
    /// view is usable), largest weight first.
    pub fn weights(&self, camera: Vec3) -> Vec<(usize, f32)> {
        let mut w = match &self.kind {
            Kind::Segment { a, dir, order } => segment(order, (camera - *a).dot(*dir)),
            Kind::Plane { origin, u, v, tri } => {
                let d = camera - *origin;
                let q = Vec2::new(d.dot(*u), d.dot(*v));
                plane(tri, q).unwrap_or_else(|| self.nearest(camera, 3))
            }
            Kind::Nearest => self.nearest(camera, 4),
        };
        w.retain(|&(_, x)| x > 1e-6);
        let sum: f32 = w.iter().map(|x| x.1).sum();
        if sum > 0.0 {
            for x in &mut w {
                x.1 /= sum;
            }
        }
        w.sort_by(|a, b| b.1.total_cmp(&a.1));
        w
    }

    fn nearest(&self, camera: Vec3, k: usize) -> Vec<(usize, f32)> {
        let mut d: Vec<(usize, f32)> = self
            .positions
            .iter()
            .enumerate()
            .filter(|(_, p)| p.is_finite())
            .map(|(i, p)| (i, p.distance(camera)))
            .collect();
        d.sort_by(|a, b| a.1.total_cmp(&b.1));
        d.truncate(k);
        if let Some(&(i, dist)) = d.first()
            && dist < 1e-5
        {
            return vec![(i, 1.0)];
        }
        d.into_iter()
            .map(|(i, dist)| (i, 1.0 / (dist * dist)))
            .collect()
    }
}

fn segment(order: &[(f32, usize)], s: f32) -> Vec<(usize, f32)> {
    let Some(first) = order.first() else {
        return Vec::new();
    };
    let last = order[order.len() - 1];
    if s <= first.0 {
        return vec![(first.1, 1.0)];
    }
    if s >= last.0 {
        return vec![(last.1, 1.0)];
    }
    let i = order
        .partition_point(|x| x.0 <= s)
        .saturating_sub(1)
        .min(order.len() - 2);
    let (a, b) = (order[i], order[i + 1]);
    let h = b.0 - a.0;
    if h <= 0.0 {
        return vec![(b.1, 1.0)];
    }
    let f = (s - a.0) / h;
    vec![(a.1, 1.0 - f), (b.1, f)]
}

fn plane(tri: &DelaunayTriangulation<Site>, q: Vec2) -> Option<Vec<(usize, f32)>> {
    if !q.is_finite() {
        return None;
    }
    let p = Point2::new(q.x as f64, q.y as f64);
    match tri.locate(p) {
        PositionInTriangulation::OnVertex(v) => Some(vec![(tri.vertex(v).data().view, 1.0)]),
        PositionInTriangulation::OnEdge(e) => {
            let e = tri.directed_edge(e);
            let (a, b) = (e.from(), e.to());
            let (pa, pb) = (a.position(), b.position());
            let ab = Vec2::new((pb.x - pa.x) as f32, (pb.y - pa.y) as f32);
            let aq = Vec2::new((p.x - pa.x) as f32, (p.y - pa.y) as f32);
            let f = (aq.dot(ab) / ab.length_squared().max(1e-12)).clamp(0.0, 1.0);
            Some(vec![(a.data().view, 1.0 - f), (b.data().view, f)])
        }
        PositionInTriangulation::OnFace(f) => {
            let face = tri.face(f);
            let bary = face.barycentric_interpolation(p);
            let vs = face.vertices();
            Some(
                (0..3)
                    .map(|k| (vs[k].data().view, bary[k].max(0.0) as f32))
                    .collect(),
            )
        }
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn views(ps: &[Vec3]) -> Vec<BaseView> {
        ps.iter()
            .enumerate()
            .map(|(i, &p)| BaseView {
                id: i as u32,
                position: p,
                time_keys: vec![0.0],
            })
            .collect()
    }

    #[test]
    fn segment_plane_and_nearest() {
        let vs = views(&[Vec3::ZERO, Vec3::X * 2.0, Vec3::X]);
        let space = ViewSpace::Segment {
            a: Vec3::ZERO,
            b: Vec3::X * 2.0,
        };
        let w = ViewWeights::new(&space, &vs, &[true; 3]).weights(Vec3::new(1.5, 0.3, 0.0));
        assert_eq!(w, vec![(2, 0.5), (1, 0.5)]);
        let vs = views(&[Vec3::ZERO, Vec3::X, Vec3::new(1.0, 0.0, 1.0), Vec3::Z]);
        let space = ViewSpace::Rectangle {
            corners: [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 0.0, 1.0), Vec3::Z],
        };
        let w = ViewWeights::new(&space, &vs, &[true; 4]).weights(Vec3::new(0.25, 0.0, 0.1));
        let sum: f32 = w.iter().map(|x| x.1).sum();
        assert!((sum - 1.0).abs() < 1e-5 && w.len() == 3);
        let pos: Vec3 = w.iter().map(|&(i, x)| vs[i].position * x).sum();
        assert!(pos.abs_diff_eq(Vec3::new(0.25, 0.0, 0.1), 1e-4));
        let space = ViewSpace::Box {
            min: Vec3::ZERO,
            max: Vec3::ONE,
        };
        let w = ViewWeights::new(&space, &vs, &[true, false, true, true]).weights(Vec3::X);
        assert!(w.iter().all(|x| x.0 != 1));
    }
}
