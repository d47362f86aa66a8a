//! The simplified scene the ambient field lives on (thesis §5.3: simplification by a quality
//! parameter): gather points per object, in object space.
//!
//! For quality q ∈ (0, 1] and scene diagonal L (at the start of the animation) the cell size
//! is h = L / (4 + 60 q). Each triangle is **tessellated** into a regular barycentric grid of
//! k² sub-triangles, k = max(⌈√(area / (h²/2))⌉, ⌈longest edge / h⌉) (at most 64): every
//! sub-triangle is under h²/2 *and* no grid edge is longer than about h, so a thin, long
//! triangle (a 0.1 × 5.9 m column face) gets points along its length instead of one at each
//! end. Triangles that are small in both senses (area under h²/32, longest edge under h) are
//! **pruned**: they get no grid of their own and their vertices are **merged** into clusters
//! (one per cell of size h and normal direction, 26 bins), each with one gather point. Grid
//! vertices that coincide (shared edges, same normal) share one point.
//!
//! The layout also records which points are neighbours (they share a sub-triangle, or a
//! pruned triangle): a point that lies inside a solid (a box face running under a wall) gets
//! its value from its neighbours on the same surface instead of from its own gather
//! (`super::gather`).

use glam::{Vec2, Vec3};
use plenoptic_scene::{ObjectId, Scene};
use rayon::prelude::*;
use std::collections::HashMap;

use crate::{Result, TraceError};

/// A gather point in object space.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct GatherPoint {
    pub(super) position: Vec3,
    pub(super) normal: Vec3,
}

/// How one original triangle maps to field points.
#[derive(Debug, Clone, Copy, PartialEq)]
struct TriangleEntry {
    /// Grid resolution; 0 for a pruned triangle (three cluster points at its corners).
    k: u32,
    /// Offset into `ObjectLayout::grid`.
    offset: u32,
}

#[derive(Debug, Clone, PartialEq, Default)]
pub(super) struct ObjectLayout {
    triangles: Vec<TriangleEntry>,
    grid: Vec<u32>,
    pub(super) points: Vec<GatherPoint>,
    /// Neighbours of point i (object-local indices): `neighbours[starts[i]..starts[i + 1]]`.
    starts: Vec<u32>,
    neighbours: Vec<u32>,
}

impl ObjectLayout {
    /// Neighbours of point `i` (object-local indices).
    pub(super) fn neighbours(&self, i: usize) -> &[u32] {
        &self.neighbours[self.starts[i] as usize..self.starts[i + 1] as usize]
    }
}

/// The simplified scene: where the field has points, per object, in object space. Depends
/// only on the scene and the quality, so fields computed at different times share it.
#[derive(Debug, Clone, PartialEq)]
pub struct FieldLayout {
    pub(super) objects: Vec<ObjectLayout>,
    /// Index of each object's first point in the field's flat point order.
    pub(super) offsets: Vec<usize>,
    quality: f32,
}

fn grid_index(k: u32, i: u32, j: u32) -> u32 {
    i * (k + 1) - i * i.saturating_sub(1) / 2 + j
}

fn normal_bin(n: Vec3) -> [i8; 3] {
    let q = (n * 1.5).round();
    [q.x as i8, q.y as i8, q.z as i8]
}

/// Grid resolution of a triangle with world-space `area` and `longest` edge (0 = pruned).
fn resolution(area: f32, longest: f32, h: f32, max_area: f32, min_area: f32) -> u32 {
    if area < min_area && longest < h {
        return 0;
    }
    let by_area = (area / max_area).sqrt().ceil();
    let by_edge = (longest / h).ceil();
    by_area.max(by_edge).clamp(1.0, 64.0) as u32
}

impl FieldLayout {
    /// Simplifies `scene` for quality `quality` (see the module doc).
    pub fn new(scene: &Scene, quality: f32) -> Result<Self> {
        if !(quality > 0.0 && quality <= 1.0) {
            return Err(TraceError::InvalidSettings(format!(
                "ambient quality {quality} is outside (0, 1]"
            )));
        }
        let t0 = scene.animation_range().0;
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for (id, o) in scene.objects.iter().enumerate() {
            let m = scene.object_transform(id as ObjectId, t0);
            for p in &scene.meshes[o.mesh].positions {
                let w = m.transform_point3(*p);
                lo = lo.min(w);
                hi = hi.max(w);
            }
        }
        let diag = if lo.x.is_finite() {
            (hi - lo).length()
        } else {
            1.0
        };
        let h = diag / (4.0 + 60.0 * quality);
        let objects: Vec<ObjectLayout> = (0..scene.objects.len())
            .into_par_iter()
            .map(|id| Self::object_layout(scene, id as ObjectId, t0, h))
            .collect();
        let mut offsets = Vec::with_capacity(objects.len());
        let mut total = 0;
        for o in &objects {
            offsets.push(total);
            total += o.points.len();
        }
        Ok(Self {
            objects,
            offsets,
            quality,
        })
    }

    fn object_layout(scene: &Scene, id: ObjectId, t0: f32, h: f32) -> ObjectLayout {
        let max_area = h * h * 0.5;
        let min_area = max_area / 16.0;
        let object = &scene.objects[id as usize];
        let mesh = &scene.meshes[object.mesh];
        let m = scene.object_transform(id, t0);
        let scale = m.matrix3.determinant().abs().cbrt().max(1e-12);
        let has_normals = mesh.normals.len() == mesh.positions.len();
        let mut layout = ObjectLayout::default();
        let mut dedupe: HashMap<([i32; 3], [i16; 3]), u32> = HashMap::new();
        let quant = h * 1e-3 / scale;
        let mut point = |layout: &mut ObjectLayout, p: Vec3, n: Vec3| -> u32 {
            let kp = (p / quant).round();
            let kn = (n * 500.0).round();
            let key = (
                [kp.x as i32, kp.y as i32, kp.z as i32],
                [kn.x as i16, kn.y as i16, kn.z as i16],
            );
            *dedupe.entry(key).or_insert_with(|| {
                layout.points.push(GatherPoint {
                    position: p,
                    normal: n,
                });
                (layout.points.len() - 1) as u32
            })
        };
        // Clusters of pruned vertices: cell + normal bin → (area-weighted sums, members).
        let mut clusters: HashMap<([i32; 3], [i8; 3]), usize> = HashMap::new();
        let mut cluster_data: Vec<(Vec3, Vec3, f32, Vec<u32>)> = Vec::new();
        let mut pruned_vertex_cluster: HashMap<u32, usize> = HashMap::new();
        let cell = h / scale;
        for tri in &mesh.triangles {
            let [a, b, c] = tri.map(|i| mesh.positions[i as usize]);
            let ng = (b - a).cross(c - a);
            let area = 0.5 * ng.length() * scale * scale;
            let longest = (b - a).length().max((c - b).length()).max((a - c).length()) * scale;
            let ng = ng.normalize_or(Vec3::Z);
            let normal = |i: u32| {
                if has_normals {
                    mesh.normals[i as usize]
                } else {
                    ng
                }
            };
            let k = resolution(area, longest, h, max_area, min_area);
            layout.triangles.push(TriangleEntry {
                k,
                offset: layout.grid.len() as u32,
            });
            if k == 0 {
                for &vi in tri {
                    let p = mesh.positions[vi as usize];
                    let n = normal(vi);
                    let ci = *pruned_vertex_cluster.entry(vi).or_insert_with(|| {
                        let kc = (p / cell).floor();
                        let key = ([kc.x as i32, kc.y as i32, kc.z as i32], normal_bin(n));
                        *clusters.entry(key).or_insert_with(|| {
                            cluster_data.push((Vec3::ZERO, Vec3::ZERO, 0.0, Vec::new()));
                            cluster_data.len() - 1
                        })
                    });
                    let w = area / 3.0 + 1e-12;
                    let cd = &mut cluster_data[ci];
                    cd.0 += p * w;
                    cd.1 += n * w;
                    cd.2 += w;
                    cd.3.push(vi);
                    // Cluster indices are patched to point indices below.
                    layout.grid.push(ci as u32);
                }
                continue;
            }
            let [na, nb, nc] = tri.map(normal);
            for i in 0..=k {
                for j in 0..=(k - i) {
                    let (b1, b2) = (i as f32 / k as f32, j as f32 / k as f32);
                    let b0 = 1.0 - b1 - b2;
                    let p = a * b0 + b * b1 + c * b2;
                    let n = (na * b0 + nb * b1 + nc * b2).normalize_or(ng);
                    let pi = point(&mut layout, p, n);
                    layout.grid.push(pi);
                }
            }
        }
        // One gather point per cluster: the member vertex nearest the weighted centroid (so it
        // lies on the surface), with the weighted mean normal.
        let cluster_points: Vec<u32> = cluster_data
            .iter()
            .map(|(ps, ns, w, members)| {
                let centroid = *ps / *w;
                let best = members
                    .iter()
                    .map(|&v| mesh.positions[v as usize])
                    .min_by(|x, y| {
                        x.distance_squared(centroid)
                            .total_cmp(&y.distance_squared(centroid))
                    })
                    .unwrap_or(centroid);
                layout.points.push(GatherPoint {
                    position: best,
                    normal: ns.normalize_or(Vec3::Z),
                });
                (layout.points.len() - 1) as u32
            })
            .collect();
        for entry in &layout.triangles {
            if entry.k == 0 {
                let o = entry.offset as usize;
                for g in &mut layout.grid[o..o + 3] {
                    *g = cluster_points[*g as usize];
                }
            }
        }
        layout.link_neighbours();
        layout
    }
}

impl ObjectLayout {
    /// Fills `starts`/`neighbours` from the triangles' grids.
    fn link_neighbours(&mut self) {
        let mut lists: Vec<Vec<u32>> = vec![Vec::new(); self.points.len()];
        let mut link = |a: u32, b: u32| {
            if a != b {
                lists[a as usize].push(b);
                lists[b as usize].push(a);
            }
        };
        for e in &self.triangles {
            let g = &self.grid[e.offset as usize..];
            if e.k == 0 {
                link(g[0], g[1]);
                link(g[1], g[2]);
                link(g[2], g[0]);
                continue;
            }
            let k = e.k;
            let at = |i, j| g[grid_index(k, i, j) as usize];
            for i in 0..k {
                for j in 0..(k - i) {
                    let (p, q, r) = (at(i, j), at(i + 1, j), at(i, j + 1));
                    link(p, q);
                    link(q, r);
                    link(r, p);
                }
            }
        }
        self.starts = Vec::with_capacity(lists.len() + 1);
        self.starts.push(0);
        for mut l in lists {
            l.sort_unstable();
            l.dedup();
            self.neighbours.extend_from_slice(&l);
            self.starts.push(self.neighbours.len() as u32);
        }
    }
}

impl FieldLayout {
    /// (object, object-local point index) of every point, in the flat order.
    pub(super) fn flat_points(&self) -> Vec<(usize, usize)> {
        self.objects
            .iter()
            .enumerate()
            .flat_map(|(o, l)| (0..l.points.len()).map(move |p| (o, p)))
            .collect()
    }

    /// Total number of gather points.
    pub fn point_count(&self) -> usize {
        self.objects.iter().map(|o| o.points.len()).sum()
    }

    /// The quality it was built for.
    pub fn quality(&self) -> f32 {
        self.quality
    }

    /// Interpolation weights of the field at barycentrics (b1, b2) of `triangle`: three
    /// (object-local point index, weight) pairs.
    pub(super) fn weights(
        &self,
        object: ObjectId,
        triangle: u32,
        bary: Vec2,
    ) -> Option<[(u32, f32); 3]> {
        let o = self.objects.get(object as usize)?;
        let e = *o.triangles.get(triangle as usize)?;
        let g = &o.grid[e.offset as usize..];
        let (b1, b2) = (bary.x.clamp(0.0, 1.0), bary.y.clamp(0.0, 1.0));
        if e.k == 0 {
            return Some([(g[0], (1.0 - b1 - b2).max(0.0)), (g[1], b1), (g[2], b2)]);
        }
        let k = e.k;
        let (x, y) = (b1 * k as f32, b2 * k as f32);
        let i = (x.floor() as u32).min(k - 1);
        let j = (y.floor() as u32).min(k - 1 - i);
        let (u, v) = (x - i as f32, y - j as f32);
        let at = |i, j| g[grid_index(k, i, j) as usize];
        Some(if u + v <= 1.0 || i + j + 2 > k {
            [
                (at(i, j), (1.0 - u - v).max(0.0)),
                (at(i + 1, j), u),
                (at(i, j + 1), v),
            ]
        } else {
            [
                (at(i + 1, j + 1), u + v - 1.0),
                (at(i, j + 1), 1.0 - u),
                (at(i + 1, j), 1.0 - v),
            ]
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thin_long_triangles_get_points_along_their_length() {
        let h = 0.5;
        let (max_area, min_area) = (h * h * 0.5, h * h * 0.5 / 16.0);
        // A 0.1 × 5.9 m column face split in two: each triangle 0.295 m², longest edge ~5.9 m.
        let k = resolution(0.295, 5.9, h, max_area, min_area);
        assert_eq!(k, 12, "points at most h apart along the edge");
        // A compact triangle keeps the area rule.
        assert_eq!(resolution(2.0, 2.1, h, max_area, min_area), 5);
        // Small in both senses: pruned.
        assert_eq!(resolution(0.005, 0.2, h, max_area, min_area), 0);
        // Small in area but long: not pruned.
        assert!(resolution(0.005, 1.2, h, max_area, min_area) >= 3);
    }

    #[test]
    fn grid_neighbours_are_symmetric_and_local() {
        let mut layout = ObjectLayout::default();
        let k = 3;
        layout.triangles.push(TriangleEntry { k, offset: 0 });
        let count = ((k + 1) * (k + 2) / 2) as usize;
        for i in 0..count {
            layout.grid.push(i as u32);
            layout.points.push(GatherPoint {
                position: Vec3::ZERO,
                normal: Vec3::Z,
            });
        }
        layout.link_neighbours();
        for i in 0..count {
            for &n in layout.neighbours(i) {
                assert!(layout.neighbours(n as usize).contains(&(i as u32)));
            }
        }
        // The corner (0, 0) touches (1, 0) and (0, 1) only; an inner vertex has six.
        assert_eq!(layout.neighbours(0).len(), 2);
        let inner = grid_index(k, 1, 1) as usize;
        assert_eq!(layout.neighbours(inner).len(), 6);
    }
}
