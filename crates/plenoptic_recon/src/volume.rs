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
//!   range images instead. (Slicing the baked (x, y, t) tetrahedral complex at t is not
//!   implemented yet; the per-time triangulation is used when the connectivity is present
//!   too.)
//! - *Geometry-assisted fallback* ([`VolumeIndex`]): samples binned by direction so that a
//!   pixel's point can find the samples of its object near its direction.

use glam::Vec3;
use plenoptic_pack::{CubeImage, VolumeSample, cube};
use rayon::prelude::*;
use spade::{DelaunayTriangulation, HasPosition, Point2, PositionInTriangulation, Triangulation};

use crate::camera::Camera;
use crate::frame::{Frame, Report};
use crate::reconstructor::Reconstructor;
use crate::warp::{ViewCubes, Warped, warp_view};
use crate::{Error, Result};

/// Radiance, distance and object-id cubes.
type Cubes = (CubeImage<Vec3>, CubeImage<f32>, CubeImage<u32>);

/// Face size of the direction bins of a [`VolumeIndex`].
const BIN_FACE: u32 = 16;

/// The filtered samples of one base view around time t, binned by direction.
#[derive(Clone, Debug)]
pub struct VolumeIndex {
    samples: Vec<(VolumeSample, f32)>,
    offsets: Vec<u32>,
    order: Vec<u32>,
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
    /// Reads and bins the samples of `view` around `t`.
    pub(crate) fn build(
        rec: &Reconstructor,
        view: usize,
        t: f32,
        missing: &mut Vec<String>,
    ) -> Option<Self> {
        let samples = filtered_samples(rec, view, t, missing)?;
        if samples.is_empty() {
            return None;
        }
        let bins = 6 * (BIN_FACE * BIN_FACE) as usize;
        let bin: Vec<usize> = samples
            .iter()
            .map(|(s, _)| cube::direction_to_texel(BIN_FACE, s.direction))
            .collect();
        let mut offsets = vec![0u32; bins + 1];
        for &b in &bin {
            offsets[b + 1] += 1;
        }
        for i in 0..bins {
            offsets[i + 1] += offsets[i];
        }
        let mut fill = offsets.clone();
        let mut order = vec![0u32; samples.len()];
        for (i, &b) in bin.iter().enumerate() {
            order[fill[b] as usize] = i as u32;
            fill[b] += 1;
        }
        Some(VolumeIndex {
            samples,
            offsets,
            order,
        })
    }

    /// Number of samples in the window.
    pub fn len(&self) -> usize {
        self.samples.len()
    }

    /// True if the window has no samples.
    pub fn is_empty(&self) -> bool {
        self.samples.is_empty()
    }

    /// The filtered radiance of object `object`'s samples whose cone contains direction `d`
    /// (from the base view; its length is the expected distance) and whose distance agrees
    /// within `tol` (relative): `(radiance, total weight)`.
    pub fn lookup(&self, d: Vec3, object: u32, tol: f32) -> Option<(Vec3, f32)> {
        let dist = d.length();
        if dist.is_nan() || dist <= 1e-6 {
            return None;
        }
        let dir = d / dist;
        let b = cube::direction_to_texel(BIN_FACE, dir);
        let bin_angle = 2.0 / BIN_FACE as f32;
        let (mut sum, mut ws) = (Vec3::ZERO, 0.0);
        for &i in &self.order[self.offsets[b] as usize..self.offsets[b + 1] as usize] {
            let (s, tw) = &self.samples[i as usize];
            if s.object_id != object || (s.distance - dist).abs() > tol * dist {
                continue;
            }
            let angle = s.direction.dot(dir).clamp(-1.0, 1.0).acos();
            let r = s.radius.max(bin_angle * 0.5);
            if angle < r {
                let w = tw * (1.0 - angle / r).max(1e-3);
                sum += s.radiance * w;
                ws += w;
            }
        }
        (ws > 0.0).then(|| (sum / ws, ws))
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
            (warp_view(&view, &basis, camera.width, camera.height), *w)
        })
        .collect();
    Ok(rec.finish_warped(camera, &warped, report, true))
}
