//! The ambient field: indirect irradiance at sparse points of a simplified scene, stored per
//! object in object space (thesis §5.3: simplification by a quality parameter; §5.3.4:
//! ambient field reconstruction by barycentric interpolation).
//!
//! Simplification, for quality q ∈ (0, 1] and scene diagonal L (at the start of the
//! animation): the cell size is h = L / (4 + 60 q); triangles are **tessellated** into a
//! regular barycentric grid of k² sub-triangles with k = ⌈√(area / (h²/2))⌉ (at most 64), so
//! every sub-triangle is under h²/2; triangles smaller than h²/32 are **pruned**: they get no
//! grid of their own and their vertices are **merged** into clusters (one per cell of size h
//! and normal direction, 26 bins), each with one gather point. Grid vertices that coincide
//! (shared edges, same normal) share one point.
//!
//! Gathering at time t: at each point, `rays` cosine-distributed rays; the radiance a ray
//! finds is what its hit surface reflects diffusely of direct light (next-event estimation,
//! one shadow sample) plus, from the second pass on, of the previous pass's field — so pass
//! p holds light that bounced 1..=p times. Emission seen directly is excluded: that is direct
//! light, computed per sample by the renderer.

use glam::{Vec2, Vec3};
use plenoptic_scene::{ObjectId, Scene};
use rayon::prelude::*;
use std::collections::HashMap;
use std::f32::consts::PI;
use std::sync::Arc;

use crate::accel::{PlacedScene, Ray};
use crate::light::estimate_direct;
use crate::material::{Bsdf, Lobes, SurfaceProps};
use crate::sampling::{Frame, Sampler, cosine_hemisphere};
use crate::{Result, TraceError};

/// Settings of the ambient field.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AmbientSettings {
    /// Quality q ∈ (0, 1]: finer tessellation and less pruning as it grows; the number of
    /// points (and the gathering time) grows about as q².
    pub quality: f32,
    /// Gather rays per point and pass; noise of the field falls as 1/√rays.
    pub rays_per_point: u32,
    /// Gathering passes = bounces of indirect light carried (each pass costs one gathering).
    pub passes: u32,
    /// Seed of the random streams.
    pub seed: u64,
    /// Whether to add the light of the bounces beyond the last pass, assuming they fall off
    /// geometrically (the "ambient term" of progressive radiosity, Cohen et al. 1988): with
    /// increments Δ_p between passes and r = |Δ_P| / |Δ_(P−1)|, the field is scaled by
    /// 1 + (r/(1−r))·|Δ_P|/|E_P| (|·| = summed luminance over points). Exact for a furnace;
    /// needs two passes or more. Costs nothing.
    pub extrapolate: bool,
}

impl AmbientSettings {
    /// Coarse and quick: for previews and tests.
    pub const fn low() -> Self {
        Self {
            quality: 0.2,
            rays_per_point: 64,
            passes: 2,
            seed: 0,
            extrapolate: true,
        }
    }

    /// The default trade-off.
    pub const fn medium() -> Self {
        Self {
            quality: 0.5,
            rays_per_point: 128,
            passes: 3,
            seed: 0,
            extrapolate: true,
        }
    }

    /// Fine and slow.
    pub const fn high() -> Self {
        Self {
            quality: 1.0,
            rays_per_point: 256,
            passes: 4,
            seed: 0,
            extrapolate: true,
        }
    }
}

impl Default for AmbientSettings {
    fn default() -> Self {
        Self::medium()
    }
}

/// A gather point in object space.
#[derive(Debug, Clone, Copy, PartialEq)]
struct GatherPoint {
    position: Vec3,
    normal: Vec3,
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
struct ObjectLayout {
    triangles: Vec<TriangleEntry>,
    grid: Vec<u32>,
    points: Vec<GatherPoint>,
}

/// The simplified scene: where the field has points, per object, in object space. Depends
/// only on the scene and the quality, so fields computed at different times share it.
#[derive(Debug, Clone, PartialEq)]
pub struct FieldLayout {
    objects: Vec<ObjectLayout>,
    quality: f32,
}

fn grid_index(k: u32, i: u32, j: u32) -> u32 {
    i * (k + 1) - i * i.saturating_sub(1) / 2 + j
}

fn normal_bin(n: Vec3) -> [i8; 3] {
    let q = (n * 1.5).round();
    [q.x as i8, q.y as i8, q.z as i8]
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
        let max_area = h * h * 0.5;
        let min_area = max_area / 16.0;
        let objects = (0..scene.objects.len())
            .into_par_iter()
            .map(|id| Self::object_layout(scene, id as ObjectId, t0, h, max_area, min_area))
            .collect();
        Ok(Self { objects, quality })
    }

    fn object_layout(
        scene: &Scene,
        id: ObjectId,
        t0: f32,
        h: f32,
        max_area: f32,
        min_area: f32,
    ) -> ObjectLayout {
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
            let ng = ng.normalize_or(Vec3::Z);
            let normal = |i: u32| {
                if has_normals {
                    mesh.normals[i as usize]
                } else {
                    ng
                }
            };
            if area < min_area {
                layout.triangles.push(TriangleEntry {
                    k: 0,
                    offset: layout.grid.len() as u32,
                });
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
            let k = (area / max_area).sqrt().ceil().clamp(1.0, 64.0) as u32;
            layout.triangles.push(TriangleEntry {
                k,
                offset: layout.grid.len() as u32,
            });
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
        for (ti, entry) in layout.triangles.iter().enumerate() {
            if entry.k == 0 {
                let o = entry.offset as usize;
                for g in &mut layout.grid[o..o + 3] {
                    *g = cluster_points[*g as usize];
                }
                debug_assert!(ti < mesh.triangles.len());
            }
        }
        layout
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
    /// (point index, weight) pairs.
    fn weights(&self, object: ObjectId, triangle: u32, bary: Vec2) -> Option<[(u32, f32); 3]> {
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

/// Indirect irradiance (W/m², linear RGB) at the points of a [`FieldLayout`], for the scene at
/// one time.
#[derive(Debug, Clone, PartialEq)]
pub struct AmbientField {
    layout: Arc<FieldLayout>,
    time: f32,
    irradiance: Vec<Vec<Vec3>>,
}

impl AmbientField {
    /// A field of zeros on `layout`.
    pub fn zero(layout: Arc<FieldLayout>, time: f32) -> Self {
        let irradiance = layout
            .objects
            .iter()
            .map(|o| vec![Vec3::ZERO; o.points.len()])
            .collect();
        Self {
            layout,
            time,
            irradiance,
        }
    }

    /// Simplifies the scene and gathers the field for `placed`.
    pub fn build(placed: &PlacedScene<'_>, settings: &AmbientSettings) -> Result<Self> {
        let layout = Arc::new(FieldLayout::new(placed.scene(), settings.quality)?);
        Ok(Self::compute(placed, layout, settings))
    }

    /// Gathers the field on `layout` for the scene placed at `placed.time()`.
    pub fn compute(
        placed: &PlacedScene<'_>,
        layout: Arc<FieldLayout>,
        settings: &AmbientSettings,
    ) -> Self {
        let mut field = Self::zero(layout, placed.time());
        let jobs: Vec<(usize, usize)> = field
            .layout
            .objects
            .iter()
            .enumerate()
            .flat_map(|(o, l)| (0..l.points.len()).map(move |p| (o, p)))
            .collect();
        let rays = settings.rays_per_point.max(1);
        // Summed luminance of the previous two fields, for the extrapolation.
        let mut sums = [0.0f64; 2];
        let mut increments = [0.0f64; 2];
        for pass in 0..settings.passes.max(1) {
            let values: Vec<Vec3> = jobs
                .par_iter()
                .enumerate()
                .map(|(index, &(o, p))| {
                    let mut s =
                        Sampler::new(settings.seed ^ 0xa3b1_e7c0, index as u64, u64::from(pass));
                    field.gather(placed, o as ObjectId, p, rays, pass > 0, &mut s)
                })
                .collect();
            let mut next = Self::zero(field.layout.clone(), field.time);
            for (&(o, p), v) in jobs.iter().zip(values) {
                next.irradiance[o][p] = v;
            }
            field = next;
            let sum = field.luminance_sum();
            increments = [increments[1], sum - sums[1]];
            sums = [sums[1], sum];
        }
        if settings.extrapolate && settings.passes >= 2 && increments[0] > 0.0 && sums[1] > 0.0 {
            let r = (increments[1] / increments[0]).clamp(0.0, 0.95);
            let scale = 1.0 + r / (1.0 - r) * increments[1].max(0.0) / sums[1];
            for v in field.irradiance.iter_mut().flatten() {
                *v *= scale as f32;
            }
        }
        field
    }

    fn luminance_sum(&self) -> f64 {
        self.irradiance
            .iter()
            .flatten()
            .map(|&v| f64::from(crate::image::luminance(v)))
            .sum()
    }

    fn gather(
        &self,
        placed: &PlacedScene<'_>,
        object: ObjectId,
        point: usize,
        rays: u32,
        bounce: bool,
        s: &mut Sampler,
    ) -> Vec3 {
        let Some(inst) = placed.instance(object) else {
            return Vec3::ZERO;
        };
        let gp = self.layout.objects[object as usize].points[point];
        let p = inst.to_world.transform_point3(gp.position);
        let n = (inst.normal_matrix * gp.normal).normalize_or(Vec3::Y);
        let frame = Frame::from_normal(n);
        let eps = 1e-4 * (1.0 + p.abs().max_element());
        let scene = placed.scene();
        let mut sum = Vec3::ZERO;
        for _ in 0..rays {
            let d = frame.to_world(cosine_hemisphere(s.next_2d()));
            let ray = Ray::new(p + n * eps, d);
            let Some(hit) = placed.intersect(&ray) else {
                continue;
            };
            let props = SurfaceProps::at(scene, &hit);
            let bsdf = Bsdf::new(&props, &hit, -d);
            if !bsdf.has(Lobes::All) {
                continue;
            }
            let mut l = estimate_direct(placed, &hit, &bsdf, Lobes::All, None, 1, s);
            if bounce {
                // One-sample estimate of the directional albedo of the non-delta lobes (diffuse
                // and glossy), applied to the previous pass's irradiance as if it were diffuse.
                let u_lobe = s.next_f32();
                let albedo = match bsdf.sample(u_lobe, s.next_2d(), Lobes::All) {
                    Some(b) if !b.delta => b.weight,
                    _ => Vec3::ZERO,
                };
                l += albedo * self.irradiance_at(hit.object, hit.triangle, hit.barycentrics) / PI;
            }
            sum += l;
        }
        // E = ∫ L cos dω ≈ π · mean(L) under cosine-weighted sampling.
        sum * (PI / rays as f32)
    }

    /// Indirect irradiance at barycentrics (b1, b2) of `triangle` of `object` (zero where the
    /// field has no data).
    pub fn irradiance_at(&self, object: ObjectId, triangle: u32, barycentrics: Vec2) -> Vec3 {
        let Some(w) = self.layout.weights(object, triangle, barycentrics) else {
            return Vec3::ZERO;
        };
        let values = &self.irradiance[object as usize];
        w.iter().map(|&(i, wt)| values[i as usize] * wt).sum()
    }

    /// The layout (simplified scene) the field lives on.
    pub fn layout(&self) -> &Arc<FieldLayout> {
        &self.layout
    }

    /// The time the field was gathered for.
    pub fn time(&self) -> f32 {
        self.time
    }

    /// Linear interpolation `(1 − s)·a + s·b` of two fields on the same layout (fields are in
    /// object space, so this follows moving objects).
    pub fn lerp(a: &Self, b: &Self, s: f32) -> Result<Self> {
        if !Arc::ptr_eq(&a.layout, &b.layout) && a.layout != b.layout {
            return Err(TraceError::FieldMismatch(
                "the two fields were built on different layouts".into(),
            ));
        }
        let irradiance = a
            .irradiance
            .iter()
            .zip(&b.irradiance)
            .map(|(x, y)| x.iter().zip(y).map(|(p, q)| p.lerp(*q, s)).collect())
            .collect();
        Ok(Self {
            layout: a.layout.clone(),
            time: a.time + (b.time - a.time) * s,
            irradiance,
        })
    }

    /// Mean irradiance over all points (a cheap summary for tests and key-time selection).
    pub fn mean_irradiance(&self) -> Vec3 {
        let n = self.layout.point_count().max(1) as f32;
        self.irradiance.iter().flatten().copied().sum::<Vec3>() / n
    }

    /// Relative RMS difference of two fields on the same layout: RMS of the luminance
    /// difference over points divided by the mean luminance of `self` (design.md step 5 picks
    /// ambient key times with it).
    pub fn relative_rms(&self, other: &Self) -> f64 {
        let mut sq = 0.0f64;
        let mut sum = 0.0f64;
        let mut n = 0usize;
        for (x, y) in self
            .irradiance
            .iter()
            .flatten()
            .zip(other.irradiance.iter().flatten())
        {
            let (lx, ly) = (
                crate::image::luminance(*x) as f64,
                crate::image::luminance(*y) as f64,
            );
            sq += (lx - ly).powi(2);
            sum += lx;
            n += 1;
        }
        if n == 0 || sum <= 0.0 {
            return 0.0;
        }
        (sq / n as f64).sqrt() / (sum / n as f64)
    }
}
