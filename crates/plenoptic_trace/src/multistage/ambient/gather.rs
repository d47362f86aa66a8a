//! Gathering the ambient field: every gather ray is traced once, and the bounces of indirect
//! light are iterated over the stored rays until they converge (thesis §5.3.3, the ambient
//! computation, built as a fixed-point iteration E = D + K·E on the simplified scene).
//!
//! Per gather point i, `rays` cosine-distributed rays leave the surface. Each ray follows
//! delta bounces (mirrors, clear glass, with their throughput) up to `max_delta_depth`, so
//! light reaches a room through glazing as in the path tracer, and stops at the first surface
//! with a non-delta lobe. There it contributes:
//!
//! - to D_i, the light that surface reflects of direct light (next-event estimation, one
//!   shadow sample towards the lights; emission is added only behind a delta bounce: seen
//!   directly it is direct light, which the renderer computes per sample), plus the
//!   environment where the ray leaves the scene, straight or through delta bounces. The sky
//!   is in the field as a source: the renderer does not sample it for diffuse reflection, and
//!   at gather hits it is not sampled either, since the hit's own field value holds it;
//! - to row i of the sparse matrix K, the surface's one-sample non-delta albedo times the
//!   field's interpolation weights at the hit (those it can see, `super::visibility`): its
//!   share of the hit's own indirect light.
//!
//! E_1 = D carries one bounce; E_(p+1) = D + K·E_p carries p + 1. The product reuses the same
//! rays, so increments are noise-free and the iteration converges like the true bounce series
//! (a furnace of albedo a: E_p = E·(1 + a + … + a^(p−1))). It stops when the remaining tail,
//! estimated geometrically from the last two increments (r/(1−r)·|ΔE|), falls below
//! `tolerance` of |E|, or after `max_bounces`.
//!
//! A **final gather** ([`final_gather`], `AmbientField::irradiance_gathered`) traces the same
//! rays from a point that is not in the layout (a pixel's or a texel's first hit) and reads
//! the converged field where they end: D + K·E for that point alone.
//!
//! A ray that meets the back face of a single-sided opaque surface has entered a closed solid
//! and carries no light (the field is shared by both sides of a triangle, so reading it there
//! would leak the lit side's light through the wall). Transmissive surfaces are exempt: a glass
//! balustrade modelled as one single-sided panel is seen from behind through open air, and a
//! glass case's inner faces through its glass. Treated as solids, the tour's glass balustrade
//! would be a black wall for every gather ray that met its back, and the atrium's indirect
//! light about 12 % low (docs/bake-accuracy.md, cause 5). Points that lie inside a solid — more
//! than an eighth of their gather rays first meet such a back face, as on a box face running
//! under a wall — are **invalid**: their own gather is dropped, and at every iteration they
//! take the mean of their valid (or already filled) neighbours on the same surface, so
//! interpolation next to a wall does not pull in the darkness inside it.

use glam::Vec3;
use plenoptic_scene::ObjectId;
use rayon::prelude::*;

use super::AmbientSettings;
use super::layout::FieldLayout;
use super::visibility::{Blocked, blocked_edges, visible_weights};
use crate::accel::{PlacedScene, Ray};
use crate::image::luminance;
use crate::light::{Competing, LightSamples, estimate_direct};
use crate::material::{Bsdf, Lobes, SurfaceProps};
use crate::sampling::{Frame, Sampler, cosine_hemisphere, power_heuristic};

/// A point is inside a solid when more than 1/`INSIDE_FRACTION` of its rays first meet the
/// back face of a single-sided surface. A point in the open meets none (rays hit the front
/// faces of whatever surrounds it); one on the line where a box runs under a wall meets
/// about half.
const INSIDE_FRACTION: u32 = 8;

/// Direct light at gather hits, one sample each: lights and emitters, not the environment,
/// which reaches the hit's own field point (E of the hit includes it) and so enters through K.
const LIGHTS_ONLY: LightSamples<'static> = LightSamples {
    lobes: Lobes::All,
    competing: Competing {
        emissive: &[],
        environment: None,
    },
    count: 1,
};

/// What one gather point's rays found.
struct PointGather {
    /// Light reflected of direct light towards the point: E_1.
    direct: Vec3,
    /// Row of K: (flat point index, RGB coefficient), sorted by index, merged.
    row: Vec<(u32, Vec3)>,
    /// Whether the point lies inside a solid.
    invalid: bool,
}

/// The converged field in the layout's flat point order, and how it was reached.
pub(super) struct Gathered {
    pub(super) irradiance: Vec<Vec3>,
    pub(super) bounces: u32,
    pub(super) invalid: usize,
    /// Points with a blocked grid edge (`super::visibility`).
    pub(super) guarded: Vec<bool>,
}

/// Where a gather point sits and how its rays are traced.
pub(super) struct Origin<'a> {
    /// World position of the point.
    pub(super) p: Vec3,
    /// Unit world normal of the side the rays leave from.
    pub(super) n: Vec3,
    /// Rays traced from the point (their estimates are scaled by it).
    pub(super) rays: u32,
    /// Delta bounces a ray follows.
    pub(super) max_delta_depth: u32,
    /// Points whose lookups test visibility (`super::visibility`).
    pub(super) guarded: &'a [bool],
}

/// Where one gather ray ended.
enum RayEnd {
    /// The ray left the scene or was absorbed.
    Open,
    /// It met the back face of a single-sided opaque surface leaving the point: the point
    /// may be inside a solid.
    BackFace,
    /// It ended on a non-delta surface whose field points `weights` it sees, times the
    /// coefficient (throughput × one-sample non-delta albedo / rays).
    Field(Vec3, [(usize, f32); 3]),
}

/// What one gather ray found.
struct Traced {
    /// Light found: the environment sampled by its own distribution from the point, and
    /// along the cosine ray the environment where it leaves the scene, emission behind a
    /// delta bounce and direct light at its end; in units of the cosine rays' sum, to be
    /// scaled by π / rays.
    light: Vec3,
    end: RayEnd,
}

/// Traces one cosine-distributed gather ray from `o` (module doc).
fn trace_ray(
    placed: &PlacedScene<'_>,
    layout: &FieldLayout,
    o: &Origin<'_>,
    s: &mut Sampler,
) -> Traced {
    let (p, n) = (o.p, o.n);
    let mut out = Traced {
        light: Vec3::ZERO,
        end: RayEnd::Open,
    };
    let frame = Frame::from_normal(n);
    let eps = 1e-4 * (1.0 + p.abs().max_element());
    let scene = placed.scene();
    let env = placed.lights().environment();
    let sample_env = env.can_sample();
    let d = frame.to_world(cosine_hemisphere(s.next_2d()));
    if sample_env {
        // The environment seen straight from the point, by its own distribution, weighted
        // against the cosine rays (power heuristic); in units of the cosine rays' sum.
        if let Some(e) = env.sample(s.next_2d()) {
            let cos = e.wi.dot(n);
            if cos > 0.0
                && e.radiance != Vec3::ZERO
                && !placed.occluded(&Ray::new(p + n * eps, e.wi))
            {
                let w = power_heuristic(e.pdf, cos / std::f32::consts::PI);
                out.light += e.radiance * (cos * w / (e.pdf * std::f32::consts::PI));
            }
        }
    }
    let mut ray = Ray::new(p + n * eps, d);
    let mut throughput = Vec3::ONE;
    for depth in 0..=o.max_delta_depth {
        let Some(hit) = placed.intersect(&ray) else {
            // The environment: the field holds its light (seen straight or through delta
            // bounces), which the renderer does not sample for the diffuse lobe. Straight
            // from the point it competes with the sample above.
            let w = if depth == 0 && sample_env {
                power_heuristic(
                    ray.direction.dot(n) / std::f32::consts::PI,
                    env.pdf(ray.direction),
                )
            } else {
                1.0
            };
            out.light += throughput * env.radiance(ray.direction) * w;
            return out;
        };
        let props = SurfaceProps::at(scene, &hit);
        // Transmissive surfaces are exempt: light reaches a pane's or a glass case's
        // inner side through the glass, and the path tracer shades it there.
        if !hit.front_face && !props.double_sided && props.transmission <= 0.0 {
            // The inside of a closed solid: no light there. From the point itself it
            // means the point is embedded in that solid.
            if depth == 0 {
                out.end = RayEnd::BackFace;
            }
            return out;
        }
        if depth > 0 {
            out.light += throughput * props.emission(&hit);
        }
        let bsdf = Bsdf::new(&props, &hit, -ray.direction);
        if !bsdf.has(Lobes::All) {
            return out;
        }
        if !bsdf.is_delta(Lobes::All) {
            out.light += throughput * estimate_direct(placed, &hit, &bsdf, LIGHTS_ONLY, s);
        }
        // One sample of the whole BSDF: a delta lobe carries the ray on; a non-delta lobe
        // ends it, its weight being a one-sample estimate of the non-delta albedo that
        // turns the hit's irradiance into radiance (as if it were diffuse).
        let u_lobe = s.next_f32();
        let Some(bs) = bsdf.sample(u_lobe, s.next_2d(), Lobes::All) else {
            return out;
        };
        if bs.delta {
            throughput *= bs.weight;
            if throughput.max_element() <= 0.0 {
                return out;
            }
            ray = Ray::new(hit.offset_origin(bs.wi), bs.wi);
            continue;
        }
        // E_i = π · mean(L) under cosine sampling, L = albedo · E_hit / π.
        let c = throughput * bs.weight / o.rays as f32;
        if let Some(w) = visible_weights(placed, layout, o.guarded, &hit, -ray.direction) {
            out.end = RayEnd::Field(c, w);
        }
        return out;
    }
    out
}

fn gather_point(
    placed: &PlacedScene<'_>,
    layout: &FieldLayout,
    guarded: &[bool],
    object: ObjectId,
    point: usize,
    settings: &AmbientSettings,
    s: &mut Sampler,
) -> PointGather {
    let mut out = PointGather {
        direct: Vec3::ZERO,
        row: Vec::new(),
        invalid: false,
    };
    let Some(inst) = placed.instance(object) else {
        return out;
    };
    let gp = layout.objects[object as usize].points[point];
    let o = Origin {
        p: inst.to_world.transform_point3(gp.position),
        n: (inst.normal_matrix * gp.normal).normalize_or(Vec3::Y),
        rays: settings.rays_per_point.max(1),
        max_delta_depth: settings.max_delta_depth,
        guarded,
    };
    let mut back_faces = 0u32;
    for _ in 0..o.rays {
        let t = trace_ray(placed, layout, &o, s);
        out.direct += t.light;
        match t.end {
            RayEnd::Open => {}
            RayEnd::BackFace => back_faces += 1,
            RayEnd::Field(c, w) => {
                for (j, wt) in w {
                    if wt > 0.0 {
                        out.row.push((j as u32, c * wt));
                    }
                }
            }
        }
    }
    // E = ∫ L cos dω ≈ π · mean(L) under cosine-weighted sampling.
    out.direct *= std::f32::consts::PI / o.rays as f32;
    out.invalid = back_faces * INSIDE_FRACTION > o.rays;
    if out.invalid {
        out.direct = Vec3::ZERO;
        out.row.clear();
    }
    out.row.sort_unstable_by_key(|e| e.0);
    out.row.dedup_by(|later, kept| {
        if later.0 == kept.0 {
            kept.1 += later.1;
            true
        } else {
            false
        }
    });
    out.row.shrink_to_fit();
    out
}

/// A final gather at `o` over the converged field `irradiance`: the module doc's
/// E = D + K·E for one point that is not in the layout, each of its rays reading the field
/// where it ends. Rays that meet a back face carry no light.
pub(super) fn final_gather(
    placed: &PlacedScene<'_>,
    layout: &FieldLayout,
    irradiance: &[Vec3],
    o: &Origin<'_>,
    s: &mut Sampler,
) -> Vec3 {
    let mut light = Vec3::ZERO;
    let mut indirect = Vec3::ZERO;
    for _ in 0..o.rays {
        let t = trace_ray(placed, layout, o, s);
        light += t.light;
        if let RayEnd::Field(c, w) = t.end {
            indirect += c * w.iter().map(|&(j, wt)| irradiance[j] * wt).sum::<Vec3>();
        }
    }
    light * (std::f32::consts::PI / o.rays as f32) + indirect
}

/// Fill rounds for invalid points: each round lists (point, the neighbours it averages), all
/// of which are valid or filled in an earlier round (Jacobi order: deterministic).
fn fill_rounds(layout: &FieldLayout, invalid: &[bool]) -> Vec<Vec<(u32, Vec<u32>)>> {
    let mut known: Vec<bool> = invalid.iter().map(|&x| !x).collect();
    let mut pending: Vec<u32> = (0..invalid.len() as u32)
        .filter(|&i| invalid[i as usize])
        .collect();
    let locate = |flat: u32| {
        let o = layout.offsets.partition_point(|&off| off <= flat as usize) - 1;
        (o, flat as usize - layout.offsets[o])
    };
    let mut rounds = Vec::new();
    while !pending.is_empty() {
        let mut round = Vec::new();
        let mut rest = Vec::new();
        for &i in &pending {
            let (o, local) = locate(i);
            let base = layout.offsets[o] as u32;
            let sources: Vec<u32> = layout.objects[o]
                .neighbours(local)
                .iter()
                .map(|&n| base + n)
                .filter(|&n| known[n as usize])
                .collect();
            if sources.is_empty() {
                rest.push(i);
            } else {
                round.push((i, sources));
            }
        }
        if round.is_empty() {
            // The rest have no valid point on their surface: they stay dark.
            break;
        }
        for (i, _) in &round {
            known[*i as usize] = true;
        }
        rounds.push(round);
        pending = rest;
    }
    rounds
}

fn apply_fill(values: &mut [Vec3], rounds: &[Vec<(u32, Vec<u32>)>]) {
    for round in rounds {
        let filled: Vec<Vec3> = round
            .iter()
            .map(|(_, src)| {
                src.iter().map(|&j| values[j as usize]).sum::<Vec3>() / src.len() as f32
            })
            .collect();
        for ((i, _), v) in round.iter().zip(filled) {
            values[*i as usize] = v;
        }
    }
}

/// One pass of edge-aware averaging: each valid point becomes the mean of itself and its
/// valid neighbours on the same surface whose grid edge is free and whose normal agrees
/// (within about 25°), so the filter neither crosses walls nor creases.
fn smooth(layout: &FieldLayout, values: &[Vec3], invalid: &[bool], blocked: &Blocked) -> Vec<Vec3> {
    let mut out = values.to_vec();
    for (o, l) in layout.objects.iter().enumerate() {
        let base = layout.offsets[o];
        for i in 0..l.points.len() {
            let fi = base + i;
            if invalid[fi] {
                continue;
            }
            let ni = l.points[i].normal;
            let (mut sum, mut count) = (values[fi], 1.0f32);
            for &j in l.neighbours(i) {
                let fj = base + j as usize;
                if !invalid[fj]
                    && l.points[j as usize].normal.dot(ni) > 0.9
                    && blocked.edge_clear(fi as u32, fj as u32)
                {
                    sum += values[fj];
                    count += 1.0;
                }
            }
            out[fi] = sum / count;
        }
    }
    out
}

fn luminance_sum(values: &[Vec3]) -> f64 {
    values.iter().map(|&v| f64::from(luminance(v))).sum()
}

/// Traces the gather rays of every point of `layout` and iterates the bounces.
pub(super) fn gather(
    placed: &PlacedScene<'_>,
    layout: &FieldLayout,
    settings: &AmbientSettings,
) -> Gathered {
    let jobs = layout.flat_points();
    let blocked = blocked_edges(placed, layout);
    let guarded = &blocked.guarded;
    let points: Vec<PointGather> = jobs
        .par_iter()
        .enumerate()
        .map(|(index, &(o, p))| {
            let mut s = Sampler::new(settings.seed ^ 0xa3b1_e7c0, index as u64, 0);
            gather_point(placed, layout, guarded, o as ObjectId, p, settings, &mut s)
        })
        .collect();
    let invalid_flags: Vec<bool> = points.iter().map(|g| g.invalid).collect();
    let invalid = invalid_flags.iter().filter(|&&x| x).count();
    let rounds = fill_rounds(layout, &invalid_flags);

    let mut values: Vec<Vec3> = points.iter().map(|g| g.direct).collect();
    apply_fill(&mut values, &rounds);
    let mut bounces = 1;
    let mut previous_increment = f64::INFINITY;
    while bounces < settings.max_bounces.max(1) {
        let next: Vec<Vec3> = points
            .par_iter()
            .map(|g| {
                g.direct
                    + g.row
                        .iter()
                        .map(|&(j, c)| c * values[j as usize])
                        .sum::<Vec3>()
            })
            .collect();
        let mut next = next;
        apply_fill(&mut next, &rounds);
        // The increment relative to each point's own value, averaged: a bright exterior lit
        // by the sky must not declare a dim interior converged.
        let total = luminance_sum(&next);
        let floor = 1e-3 * total / next.len().max(1) as f64;
        let increment: f64 = next
            .iter()
            .zip(&values)
            .map(|(a, b)| {
                let d = f64::from(luminance(*a - *b)).abs();
                d / f64::from(luminance(*a)).max(floor).max(f64::MIN_POSITIVE)
            })
            .sum::<f64>()
            / next.len().max(1) as f64;
        values = next;
        bounces += 1;
        if total <= 0.0 || increment <= 0.0 {
            break;
        }
        // The rest of the series, assuming it falls off geometrically from here.
        // Needs two increments for the ratio.
        let r = (increment / previous_increment).clamp(0.0, 0.99);
        let tail = increment * r / (1.0 - r);
        let first = !previous_increment.is_finite();
        previous_increment = increment;
        if !first && tail <= f64::from(settings.tolerance) {
            break;
        }
    }
    for _ in 0..settings.smoothing {
        values = smooth(layout, &values, &invalid_flags, &blocked);
        apply_fill(&mut values, &rounds);
    }
    Gathered {
        irradiance: values,
        bounces,
        invalid,
        guarded: blocked.guarded,
    }
}
