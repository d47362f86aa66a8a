//! Temporal volumes at time t (thesis chapter 7, §7.4: reconstruction from the (x, y, t)
//! samples of a base view).
//!
//! Only the buckets overlapping `t ± tε` are read. Samples with `|t_s − t| ≤ tε` take part with
//! the tent filter `τ = 1 − |t_s − t|/tε`.
//!
//! - *Volume mode*: per cube face, the samples are projected to the face's plane (including
//!   those a little beyond its edges, so that seams interpolate), triangulated (2D Delaunay,
//!   spade), and every texel interpolates its triangle's samples with weights
//!   `barycentric · τ`; distance and object id come from the heaviest corner. The cube at t is
//!   then warped like a range image ([`crate::warp`]). Views without temporal volumes use their
//!   range images instead.
//! - *Volume mode with the baked complex*: when the pack holds the VolumeConnectivity chunk of
//!   the block of `bucket_of(t)`, the cube at t is instead the slice of that block's (x, y, t)
//!   Delaunay complex ([`crate::delaunay3`], coordinates [`complex_point`]) at t
//!   ([`slice_to_cube`]): every texel's direction is mapped to octahedral (x, y), located in
//!   the slice triangles, and radiance and distance are interpolated barycentrically (object id
//!   from the nearest corner). A tetrahedron spans only its own block's samples, so no tent
//!   filter is applied. A missing, unreadable or inconsistent complex falls back to the
//!   per-face triangulation (the unreadable one is reported); [`Report::volume_complex_blocks`]
//!   counts the cubes built from the complex.
//! - *Geometry-assisted fallback* ([`VolumeIndex`]): samples binned by direction so that a
//!   pixel's point can find the samples of its object near its direction.

use std::sync::Arc;

use glam::Vec3;
use plenoptic_pack::{ChunkKind, CubeImage, VolumeBlock, VolumeSample, cube};
use rayon::prelude::*;
use spade::{DelaunayTriangulation, HasPosition, Point2, PositionInTriangulation, Triangulation};

use crate::camera::Camera;
use crate::delaunay3::{DelaunayError, Interpolate, SliceTriangle, slice_at};
use crate::frame::{Frame, Report};
use crate::reconstructor::Reconstructor;
use crate::shading::Channel;
use crate::warp::{ViewCubes, Warped, warp_view};
use crate::{Error, Result};

/// Radiance, distance and object-id cubes.
pub type Cubes = (CubeImage<Vec3>, CubeImage<f32>, CubeImage<u32>);

/// Face size of the direction bins of a [`VolumeIndex`].
const BIN_FACE: u32 = 16;

/// The samples of one base view around time t, binned by direction: the blocks overlapping
/// t ± tε, each binned once and cached by the [`Reconstructor`]; the tent
/// filter is applied at lookup.
#[derive(Clone, Debug)]
pub struct VolumeIndex {
    blocks: Vec<Arc<BlockBins>>,
    /// Which of a sample's colours a lookup returns.
    channel: Channel,
    t: f32,
    eps: f32,
}

/// One volume block's samples binned by direction (cube of face size `BIN_FACE`), stable in
/// the stored order.
#[derive(Debug)]
pub(crate) struct BlockBins {
    pub(crate) block: Arc<VolumeBlock>,
    offsets: Vec<u32>,
    order: Vec<u32>,
}

impl BlockBins {
    pub(crate) fn new(block: Arc<VolumeBlock>) -> Self {
        let bins = 6 * (BIN_FACE * BIN_FACE) as usize;
        let bin: Vec<usize> = block
            .samples
            .iter()
            .map(|s| cube::direction_to_texel(BIN_FACE, s.direction))
            .collect();
        let mut offsets = vec![0u32; bins + 1];
        for &b in &bin {
            offsets[b + 1] += 1;
        }
        for i in 0..bins {
            offsets[i + 1] += offsets[i];
        }
        let mut fill = offsets.clone();
        let mut order = vec![0u32; bin.len()];
        for (i, &b) in bin.iter().enumerate() {
            order[fill[b] as usize] = i as u32;
            fill[b] += 1;
        }
        BlockBins {
            block,
            offsets,
            order,
        }
    }

    /// Bytes held, the block included.
    pub(crate) fn bytes(&self) -> usize {
        (self.offsets.len() + self.order.len()) * 4
            + self.block.samples.len() * std::mem::size_of::<VolumeSample>()
    }
}

/// The samples of `view` with |t_s − t| ≤ tε and their tent weights; `None` if the view has no
/// readable block overlapping the window.
pub(crate) fn filtered_samples(
    rec: &Reconstructor,
    view: usize,
    t: f32,
    missing: &mut Vec<String>,
) -> Option<Vec<(VolumeSample, f32)>> {
    let m = rec.pack().manifest();
    let eps = rec.time_epsilon();
    let (b0, b1) = (m.bucket_of(t - eps), m.bucket_of(t + eps));
    let mut out = Vec::new();
    let mut any = false;
    for b in b0..=b1.min(b0.saturating_add(64)) {
        let Some(block) = rec.volume_block(view, b, missing) else {
            continue;
        };
        any = true;
        for s in &block.samples {
            let dt = (s.t - t).abs();
            if dt <= eps {
                out.push((*s, 1.0 - dt / eps));
            }
        }
    }
    any.then_some(out)
}

impl VolumeIndex {
    /// The binned samples of `view` around `t`; `None` if no readable block overlaps the
    /// window.
    pub(crate) fn build(
        rec: &Reconstructor,
        view: usize,
        t: f32,
        channel: Channel,
        missing: &mut Vec<String>,
    ) -> Option<Self> {
        let m = rec.pack().manifest();
        let eps = rec.time_epsilon();
        let (b0, b1) = (m.bucket_of(t - eps), m.bucket_of(t + eps));
        let mut blocks = Vec::new();
        for b in b0..=b1.min(b0.saturating_add(64)) {
            if let Some(bins) = rec.block_bins(view, b, missing)
                && !bins.block.samples.is_empty()
            {
                blocks.push(bins);
            }
        }
        (!blocks.is_empty()).then_some(VolumeIndex {
            blocks,
            channel,
            t,
            eps,
        })
    }

    /// Number of samples in the window.
    pub fn len(&self) -> usize {
        self.blocks
            .iter()
            .flat_map(|b| &b.block.samples)
            .filter(|s| (s.t - self.t).abs() <= self.eps)
            .count()
    }

    /// True if the window has no samples.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The filtered colour (radiance, or the index's channel) of object `object`'s samples
    /// whose cone contains direction `d`
    /// (from the base view; its length is the expected distance) and whose distance agrees
    /// within `tol` (relative): `(radiance, total weight)`. Samples weigh by the tent filter
    /// `1 − |t_s − t|/tε` times their cone's falloff.
    pub fn lookup(&self, d: Vec3, object: u32, tol: f32) -> Option<(Vec3, f32)> {
        self.lookup_pair(d, object, tol, None, Vec3::ZERO)
            .map(|(c, _, w)| (c, w))
    }

    /// [`VolumeIndex::lookup`], with the samples' `second` colour filtered with the same
    /// weights in the same walk (black without one): `(colour, second colour, total weight)`.
    /// With a surface `normal` (facing the eye; zero: no test) only samples that face as the
    /// surface does count ([`crate::lookup::SAME_FACE_COS`], the lookups' face test): the lit
    /// top of a lamp, a few millimetres from its side, is not answered by the side's samples.
    pub(crate) fn lookup_pair(
        &self,
        d: Vec3,
        object: u32,
        tol: f32,
        second: Option<Channel>,
        normal: Vec3,
    ) -> Option<(Vec3, Vec3, f32)> {
        let dist = d.length();
        if dist.is_nan() || dist <= 1e-6 {
            return None;
        }
        let dir = d / dist;
        let b = cube::direction_to_texel(BIN_FACE, dir);
        let bin_angle = 2.0 / BIN_FACE as f32;
        let (mut sum, mut sum2, mut ws) = (Vec3::ZERO, Vec3::ZERO, 0.0);
        for bins in &self.blocks {
            let range = bins.offsets[b] as usize..bins.offsets[b + 1] as usize;
            for &i in &bins.order[range] {
                let s = &bins.block.samples[i as usize];
                let dt = (s.t - self.t).abs();
                if dt > self.eps
                    || s.object_id != object
                    || (s.distance - dist).abs() > tol * dist
                    || (normal != Vec3::ZERO && s.normal.dot(normal) < crate::lookup::SAME_FACE_COS)
                {
                    continue;
                }
                let tw = 1.0 - dt / self.eps;
                let angle = s.direction.dot(dir).clamp(-1.0, 1.0).acos();
                let r = s.radius.max(bin_angle * 0.5);
                if angle < r {
                    let w = tw * (1.0 - angle / r).max(1e-3);
                    sum += self.channel.of_sample(s) * w;
                    if let Some(c) = second {
                        sum2 += c.of_sample(s) * w;
                    }
                    ws += w;
                }
            }
        }
        (ws > 0.0).then(|| (sum / ws, sum2 / ws, ws))
    }
}

#[derive(Clone, Copy, Debug)]
struct Site {
    p: Point2<f64>,
    sample: u32,
}

impl HasPosition for Site {
    type Scalar = f64;
    fn position(&self) -> Point2<f64> {
        self.p
    }
}

/// Face `f`'s centre direction and unit axes (u grows with columns, v with rows), derived from
/// the pack's cube convention.
fn face_frame(f: usize) -> (Vec3, Vec3, Vec3) {
    let c = cube::face_uv_to_direction(f, 0.5, 0.5);
    let u = cube::face_uv_to_direction(f, 1.0, 0.5) * std::f32::consts::SQRT_2 - c;
    let v = cube::face_uv_to_direction(f, 0.5, 1.0) * std::f32::consts::SQRT_2 - c;
    (c, u, v)
}

/// Reconstructs radiance, distance and object-id cubes of face size `n` from filtered samples.
pub fn samples_to_cube(samples: &[(VolumeSample, f32)], n: u32) -> Cubes {
    let nn = (n * n) as usize;
    let faces: Vec<(Vec<Vec3>, Vec<f32>, Vec<u32>)> = (0..6)
        .into_par_iter()
        .map(|f| {
            let mut rad = vec![Vec3::ZERO; nn];
            let mut dist = vec![f32::INFINITY; nn];
            let mut ids = vec![0u32; nn];
            let (c, u, v) = face_frame(f);
            let mut tri = DelaunayTriangulation::<Site>::new();
            for (i, (s, _)) in samples.iter().enumerate() {
                let m = s.direction.dot(c);
                if m <= 0.2 {
                    continue;
                }
                let p = s.direction / m;
                let (x, y) = (p.dot(u), p.dot(v));
                if x.abs() <= 1.3 && y.abs() <= 1.3 {
                    let _ = tri.insert(Site {
                        p: Point2::new(x as f64, y as f64),
                        sample: i as u32,
                    });
                }
            }
            if tri.num_vertices() == 0 {
                return (rad, dist, ids);
            }
            for j in 0..n as usize {
                for i in 0..n as usize {
                    let x = 2.0 * (i as f64 + 0.5) / n as f64 - 1.0;
                    let y = 2.0 * (j as f64 + 0.5) / n as f64 - 1.0;
                    let q = Point2::new(x, y);
                    let corners: Vec<(u32, f64)> = match tri.locate(q) {
                        PositionInTriangulation::OnFace(fh) => {
                            let face = tri.face(fh);
                            let b = face.barycentric_interpolation(q);
                            let vs = face.vertices();
                            (0..3)
                                .map(|k| (vs[k].data().sample, b[k].max(0.0)))
                                .collect()
                        }
                        PositionInTriangulation::OnVertex(vh) => {
                            vec![(tri.vertex(vh).data().sample, 1.0)]
                        }
                        PositionInTriangulation::OnEdge(e) => {
                            let e = tri.directed_edge(e);
                            vec![(e.from().data().sample, 0.5), (e.to().data().sample, 0.5)]
                        }
                        _ => match tri.nearest_neighbor(q) {
                            Some(vh) => vec![(vh.data().sample, 1.0)],
                            None => continue,
                        },
                    };
                    let (mut sum, mut ws, mut best) = (Vec3::ZERO, 0.0f32, (0.0f32, 0u32));
                    for (k, b) in corners {
                        let (s, tw) = &samples[k as usize];
                        let w = b as f32 * tw.max(1e-3);
                        sum += s.radiance * w;
                        ws += w;
                        if w > best.0 {
                            best = (w, k);
                        }
                    }
                    if ws > 0.0 {
                        let t = j * n as usize + i;
                        rad[t] = sum / ws;
                        let s = &samples[best.1 as usize].0;
                        dist[t] = s.distance;
                        ids[t] = s.object_id;
                    }
                }
            }
            (rad, dist, ids)
        })
        .collect();
    let mut r = CubeImage::filled(n, Vec3::ZERO);
    let mut d = CubeImage::filled(n, f32::INFINITY);
    let mut o = CubeImage::filled(n, 0u32);
    for (f, (fr, fd, fo)) in faces.into_iter().enumerate() {
        r.texels[f * nn..(f + 1) * nn].copy_from_slice(&fr);
        d.texels[f * nn..(f + 1) * nn].copy_from_slice(&fd);
        o.texels[f * nn..(f + 1) * nn].copy_from_slice(&fo);
    }
    (r, d, o)
}

/// The (x, y, t) coordinates of a volume sample in its block's Delaunay complex (thesis
/// §7.4.2): x, y the octahedral coordinates ([`cube::oct_encode`]) of `direction` in [−1, 1]²,
/// t the position of `t` in the block's span `[t_start, t_end]` ([`complex_time`]). The baker
/// builds the stored complex over these coordinates of the *stored* (quantized) samples, and
/// reconstruction slices it with them: this is the one definition both use.
pub fn complex_point(direction: Vec3, t: f32, t_start: f32, t_end: f32) -> [f64; 3] {
    let o = cube::oct_encode(direction);
    [
        f64::from(o.x),
        f64::from(o.y),
        complex_time(t, t_start, t_end),
    ]
}

/// The t coordinate of time `t` in the complex of a block spanning `[t_start, t_end]`:
/// `(t − t_start)/(t_end − t_start)`, in [0, 1] inside the span (see [`complex_point`]).
pub fn complex_time(t: f32, t_start: f32, t_end: f32) -> f64 {
    let span = (t_end - t_start).max(f32::MIN_POSITIVE);
    f64::from((t - t_start) / span)
}

/// What a slice corner carries: radiance and distance interpolate linearly; the object id is
/// the nearer edge end's.
#[derive(Clone, Copy, Debug)]
struct Corner {
    radiance: Vec3,
    distance: f32,
    id: u32,
}

impl Interpolate for Corner {
    fn lerp(&self, other: &Self, s: f64) -> Self {
        Corner {
            radiance: Interpolate::lerp(&self.radiance, &other.radiance, s),
            distance: Interpolate::lerp(&self.distance, &other.distance, s),
            id: if s <= 0.5 { self.id } else { other.id },
        }
    }
}

/// Barycentric coordinates of `q` in triangle `xy` (`None` when it is degenerate).
fn barycentric(xy: &[[f64; 2]; 3], q: [f64; 2]) -> Option<[f64; 3]> {
    let [a, b, c] = *xy;
    let det = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
    if det.abs() <= 1e-300 {
        return None;
    }
    let l1 = ((q[0] - a[0]) * (c[1] - a[1]) - (q[1] - a[1]) * (c[0] - a[0])) / det;
    let l2 = ((b[0] - a[0]) * (q[1] - a[1]) - (b[1] - a[1]) * (q[0] - a[0])) / det;
    Some([1.0 - l1 - l2, l1, l2])
}

/// The cubes (face size `n`) at time `t` sliced from a block's (x, y, t) Delaunay complex
/// `tets` (stored sample indices; coordinates [`complex_point`]): each texel's direction is
/// mapped to octahedral (x, y) and located among the slice triangles; radiance and distance
/// interpolate the triangle's corners barycentrically, the object id is the nearest corner's.
/// Texels outside the slice take the nearest slice corner in their neighbourhood (within a
/// grid cell, about √(triangle count)⁻¹ of the square), or stay empty (distance ∞, id 0).
///
/// Returns `Ok(None)` when `t` is outside the complex's time extent (no triangle).
///
/// # Errors
///
/// [`DelaunayError`] when a tetrahedron names a sample the block does not have.
pub fn slice_to_cube(
    block: &VolumeBlock,
    tets: &[[u32; 4]],
    t: f32,
    n: u32,
) -> Result<Option<Cubes>, DelaunayError> {
    let points: Vec<[f64; 3]> = block
        .samples
        .iter()
        .map(|s| complex_point(s.direction, s.t, block.t_start, block.t_end))
        .collect();
    let values: Vec<Corner> = block
        .samples
        .iter()
        .map(|s| Corner {
            radiance: s.radiance,
            distance: s.distance,
            id: s.object_id,
        })
        .collect();
    let tris = slice_at(
        &points,
        tets,
        &values,
        complex_time(t, block.t_start, block.t_end),
    )?;
    let tris: Vec<SliceTriangle<Corner>> = tris.into_iter().filter(|t| t.area() > 0.0).collect();
    if tris.is_empty() {
        return Ok(None);
    }
    // Uniform grid over [−1, 1]² binning the triangles by bounding box.
    let g = ((tris.len() as f64).sqrt().ceil() as usize).clamp(1, 512);
    let cell = |x: f64| (((x + 1.0) * 0.5 * g as f64).floor().max(0.0) as usize).min(g - 1);
    let mut bins: Vec<Vec<u32>> = vec![Vec::new(); g * g];
    for (k, tri) in tris.iter().enumerate() {
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in &tri.xy {
            for a in 0..2 {
                lo[a] = lo[a].min(p[a]);
                hi[a] = hi[a].max(p[a]);
            }
        }
        for j in cell(lo[1])..=cell(hi[1]) {
            for i in cell(lo[0])..=cell(hi[0]) {
                bins[j * g + i].push(k as u32);
            }
        }
    }
    let texels: Vec<(Vec3, f32, u32)> = (0..6 * (n * n) as usize)
        .into_par_iter()
        .map(|i| {
            let o = cube::oct_encode(cube::texel_direction(n, i));
            let q = [f64::from(o.x), f64::from(o.y)];
            let (ci, cj) = (cell(q[0]), cell(q[1]));
            // The containing triangle: the candidate whose smallest barycentric coordinate is
            // largest (≥ −1e-9 counts as inside, for texels on shared edges).
            let mut best: Option<(f64, u32, [f64; 3])> = None;
            for &k in &bins[cj * g + ci] {
                if let Some(b) = barycentric(&tris[k as usize].xy, q) {
                    let m = b[0].min(b[1]).min(b[2]);
                    if best.is_none_or(|(bm, _, _)| m > bm) {
                        best = Some((m, k, b));
                    }
                }
            }
            if let Some((m, k, b)) = best
                && m >= -1e-9
            {
                let v = &tris[k as usize].values;
                let b = b.map(|x| x.max(0.0));
                let s = b[0] + b[1] + b[2];
                let mut radiance = Vec3::ZERO;
                let mut distance = 0.0f64;
                for c in 0..3 {
                    radiance += v[c].radiance * (b[c] / s) as f32;
                    distance += f64::from(v[c].distance) * b[c] / s;
                }
                let near = (0..3).max_by(|&x, &y| b[x].total_cmp(&b[y])).unwrap_or(0);
                return (radiance, distance as f32, v[near].id);
            }
            // Outside the slice: the nearest corner among the neighbouring cells' triangles.
            let mut nearest: Option<(f64, Corner)> = None;
            for j in cj.saturating_sub(1)..=(cj + 1).min(g - 1) {
                for i in ci.saturating_sub(1)..=(ci + 1).min(g - 1) {
                    for &k in &bins[j * g + i] {
                        let tri = &tris[k as usize];
                        for c in 0..3 {
                            let d = (tri.xy[c][0] - q[0]).powi(2) + (tri.xy[c][1] - q[1]).powi(2);
                            if nearest.is_none_or(|(nd, _)| d < nd) {
                                nearest = Some((d, tri.values[c]));
                            }
                        }
                    }
                }
            }
            match nearest {
                Some((_, c)) => (c.radiance, c.distance, c.id),
                None => (Vec3::ZERO, f32::INFINITY, 0),
            }
        })
        .collect();
    let mut r = CubeImage::filled(n, Vec3::ZERO);
    let mut d = CubeImage::filled(n, f32::INFINITY);
    let mut o = CubeImage::filled(n, 0u32);
    for (i, (rad, dist, id)) in texels.into_iter().enumerate() {
        r.texels[i] = rad;
        d.texels[i] = dist;
        o.texels[i] = id;
    }
    Ok(Some((r, d, o)))
}

/// The cube of `view` at `t` sliced from the baked complex of the block of `bucket_of(t)`, if
/// the pack has that block's connectivity and it can be used. An unreadable or inconsistent
/// connectivity chunk is reported in `missing` (the caller falls back to the per-face
/// triangulation, which reports an unreadable block itself).
fn complex_cube(
    rec: &Reconstructor,
    view: usize,
    t: f32,
    missing: &mut Vec<String>,
) -> Option<Cubes> {
    let bucket = rec.pack().manifest().bucket_of(t);
    rec.pack()
        .find(ChunkKind::VolumeConnectivity, view as u32, bucket)?;
    let block = rec.volume_block(view, bucket, &mut Vec::new())?;
    let tets = rec.connectivity(view, bucket, missing)?;
    match slice_to_cube(&block, &tets, t, rec.settings.volume_face_size) {
        Ok(cubes) => cubes,
        Err(e) => {
            missing.push(format!(
                "volume connectivity of base view {view}, bucket {bucket}: {e}: triangulated the samples at t instead"
            ));
            None
        }
    }
}

/// Volume mode: cubes at t from the temporal volumes of the nearest views, warped and blended.
pub(crate) fn render(
    rec: &Reconstructor,
    camera: &Camera,
    t: f32,
    report: &mut Report,
) -> Result<Frame> {
    let views = rec.view_weights(camera.position);
    let mut cubes: Vec<(usize, f32, Cubes)> = Vec::new();
    for &(v, w) in &views {
        if let Some(c) = complex_cube(rec, v, t, &mut report.missing) {
            report.volume_complex_blocks += 1;
            cubes.push((v, w, c));
            continue;
        }
        match filtered_samples(rec, v, t, &mut report.missing) {
            Some(s) if s.len() >= 3 => {
                cubes.push((v, w, samples_to_cube(&s, rec.settings.volume_face_size)))
            }
            _ => {
                if let Some((r, k)) = rec.view_at_time(v, t, &mut report.missing) {
                    report.missing.push(format!(
                        "base view {v} has no temporal volume near t = {t}: used its range images"
                    ));
                    cubes.push((v, w, (r, (*k.distance).clone(), (*k.ids).clone())));
                }
            }
        }
    }
    if cubes.is_empty() {
        return Err(Error::Unusable(format!(
            "no temporal volume or range image near t = {t}: {}",
            report.missing.join("; ")
        )));
    }
    report.base_views = cubes.iter().map(|c| (c.0, c.1)).collect();
    let basis = camera.basis();
    let warped: Vec<(Warped, f32)> = cubes
        .par_iter()
        .map(|(v, w, (r, d, o))| {
            let position = rec.pack().manifest().base_views[*v].position;
            let view = ViewCubes {
                position,
                radiance: r,
                distance: d,
                object: o,
            };
            (
                warp_view(&view, &basis, camera.width, camera.height, &rec.settings),
                *w,
            )
        })
        .collect();
    Ok(rec.finish_warped(camera, &warped, report, true))
}

#[cfg(test)]
#[path = "volume_tests.rs"]
mod tests;
