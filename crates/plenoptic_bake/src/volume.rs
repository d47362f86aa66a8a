//! Temporal volumes (thesis ch. 7, §7.2 "directional and temporal sampling"; docs/architecture.md Baking
//! step 7).
//!
//! The (direction, t) domain of one base view is cut into cells: the six cube faces in an
//! `m × m` grid each, times `k` time slices. A quarter of the budget goes to one jittered
//! random sample per cell (§7.2.1, stratified random sampling). Cells whose sample disagrees
//! with a neighbour's (same face, adjacent in u, v or t) in object id or in luminance by more
//! than `1 − q` are split into 2 × 2 × 2 children (2 × 2 for a static range), each sampled
//! once (§7.2.2, uniform adaptive sampling); a child is split again when it disagrees with a
//! sibling or its parent. Splitting goes level by level in cell order until the budget is
//! spent, so the result is deterministic.
//!
//! Each sample's validity radius is the angular half-diagonal of its cell: the cone of
//! directions it stands for (the thesis estimates it from the jittered supersamples; a cell
//! bound is the same quantity without the extra rays).

use glam::Vec3;
use plenoptic_pack::VolumeSample;
use plenoptic_trace::RadianceSample;
use plenoptic_trace::sampling::Sampler;

use crate::render::{BakeRenderer, disagree, face_direction, pack_object_id, par_map, seed_of};

#[derive(Debug, Clone, Copy)]
struct Cell {
    face: usize,
    u: [f32; 2],
    v: [f32; 2],
    t: [f32; 2],
}

impl Cell {
    fn radius(&self) -> f32 {
        let c = face_direction(
            self.face,
            0.5 * (self.u[0] + self.u[1]),
            0.5 * (self.v[0] + self.v[1]),
        );
        let mut r = 0.0f32;
        for u in self.u {
            for v in self.v {
                r = r.max(
                    c.dot(face_direction(self.face, u, v))
                        .clamp(-1.0, 1.0)
                        .acos(),
                );
            }
        }
        r
    }

    fn children(&self, split_time: bool) -> Vec<Cell> {
        let um = 0.5 * (self.u[0] + self.u[1]);
        let vm = 0.5 * (self.v[0] + self.v[1]);
        let tm = 0.5 * (self.t[0] + self.t[1]);
        let ts: Vec<[f32; 2]> = if split_time {
            vec![[self.t[0], tm], [tm, self.t[1]]]
        } else {
            vec![self.t]
        };
        let mut out = Vec::with_capacity(8);
        for t in ts {
            for v in [[self.v[0], vm], [vm, self.v[1]]] {
                for u in [[self.u[0], um], [um, self.u[1]]] {
                    out.push(Cell {
                        face: self.face,
                        u,
                        v,
                        t,
                    });
                }
            }
        }
        out
    }
}

struct Sampled {
    cell: Cell,
    sample: RadianceSample,
    /// Each declared light group's (lighting, non-diffuse radiance).
    groups: Vec<(u32, [Vec3; 2])>,
    dir: Vec3,
    t: f32,
}

fn evaluate(r: &BakeRenderer<'_>, bv: usize, cells: &[(u64, Cell)]) -> Vec<Sampled> {
    let base = seed_of(&[r.plan.seed, 3, bv as u64]);
    par_map(cells, |&(serial, cell)| {
        let mut s = Sampler::new(base, serial, 0);
        let j = s.next_2d();
        let jt = s.next_f32();
        let u = cell.u[0] + (cell.u[1] - cell.u[0]) * j.x;
        let v = cell.v[0] + (cell.v[1] - cell.v[0]) * j.y;
        let t = cell.t[0] + (cell.t[1] - cell.t[0]) * jt;
        let dir = face_direction(cell.face, u, v);
        let layered = r.sample(bv, dir, t, serial);
        Sampled {
            cell,
            sample: layered.total,
            groups: layered.groups,
            dir,
            t,
        }
    })
}

/// A base view's volume samples, and each declared light group's values of them.
#[derive(Debug, Clone, Default)]
pub struct LayeredVolume {
    /// The samples (their lighting the sum of the groups').
    pub samples: Vec<VolumeSample>,
    /// Per declared group, in group order: `(group, [lighting, non-diffuse] per sample)`.
    pub groups: Vec<(u32, Vec<[Vec3; 2]>)>,
}

/// Samples the temporal volume of base view `bv` with `budget` samples (see the module doc).
pub fn sample_volume(r: &BakeRenderer<'_>, bv: usize, budget: usize) -> LayeredVolume {
    let plan = r.plan;
    let (start, end) = (plan.start, plan.end);
    let split_time = end > start;
    let tolerance = (1.0 - plan.quality.q).clamp(0.01, 1.0);
    // Level 0: k time slices, m × m cells per face, about a quarter of the budget.
    let frames = ((end - start) * plan.frame_rate).round().max(1.0) as usize;
    let k = if split_time {
        (frames / 2).clamp(1, 32)
    } else {
        1
    };
    let m = (((budget / 4).max(6) as f64 / (6 * k) as f64).sqrt().floor() as usize).max(1);
    let dt = (end - start) / k as f32;
    let mut cells = Vec::with_capacity(6 * m * m * k);
    for ti in 0..k {
        for face in 0..6 {
            for j in 0..m {
                for i in 0..m {
                    cells.push(Cell {
                        face,
                        u: [i as f32 / m as f32, (i + 1) as f32 / m as f32],
                        v: [j as f32 / m as f32, (j + 1) as f32 / m as f32],
                        t: [start + dt * ti as f32, start + dt * (ti + 1) as f32],
                    });
                }
            }
        }
    }
    cells.truncate(budget);
    let mut serial = 0u64;
    let mut numbered = |cs: Vec<Cell>| -> Vec<(u64, Cell)> {
        cs.into_iter()
            .map(|c| {
                serial += 1;
                (serial, c)
            })
            .collect()
    };
    let level0 = evaluate(r, bv, &numbered(cells));
    let idx = |ti: usize, face: usize, j: usize, i: usize| ((ti * 6 + face) * m + j) * m + i;
    let mut to_split: Vec<usize> = Vec::new();
    for (n, s) in level0.iter().enumerate() {
        let (i, j, face, ti) = (n % m, (n / m) % m, (n / (m * m)) % 6, n / (6 * m * m));
        let mut neighbours = Vec::with_capacity(6);
        if i > 0 {
            neighbours.push(idx(ti, face, j, i - 1));
        }
        if i + 1 < m {
            neighbours.push(idx(ti, face, j, i + 1));
        }
        if j > 0 {
            neighbours.push(idx(ti, face, j - 1, i));
        }
        if j + 1 < m {
            neighbours.push(idx(ti, face, j + 1, i));
        }
        if ti > 0 {
            neighbours.push(idx(ti - 1, face, j, i));
        }
        if ti + 1 < k {
            neighbours.push(idx(ti + 1, face, j, i));
        }
        if neighbours
            .iter()
            .filter(|&&o| o < level0.len())
            .any(|&o| disagree(&s.sample, &level0[o].sample, tolerance))
        {
            to_split.push(n);
        }
    }
    let mut all: Vec<Sampled> = level0;
    let mut parents: Vec<usize> = to_split;
    let per_split = if split_time { 8 } else { 4 };
    while !parents.is_empty() && all.len() + per_split <= budget {
        let room = (budget - all.len()) / per_split;
        parents.truncate(room);
        let children: Vec<Cell> = parents
            .iter()
            .flat_map(|&p| all[p].cell.children(split_time))
            .collect();
        let done = evaluate(r, bv, &numbered(children));
        let first = all.len();
        let mut next = Vec::new();
        for (g, &p) in parents.iter().enumerate() {
            let group = &done[g * per_split..(g + 1) * per_split];
            for (c, s) in group.iter().enumerate() {
                let split = group
                    .iter()
                    .any(|o| disagree(&s.sample, &o.sample, tolerance))
                    || disagree(&s.sample, &all[p].sample, tolerance);
                if split {
                    next.push(first + g * per_split + c);
                }
            }
        }
        all.extend(done);
        parents = next;
    }
    let groups = all
        .first()
        .map(|first| {
            (0..first.groups.len())
                .map(|i| {
                    (
                        first.groups[i].0,
                        all.iter().map(|s| s.groups[i].1).collect(),
                    )
                })
                .collect()
        })
        .unwrap_or_default();
    let samples = all
        .iter()
        .map(|s| {
            let (lighting, non_diffuse) = crate::denoise::split_sample(&s.sample);
            VolumeSample {
                direction: s.dir,
                t: s.t,
                radiance: s.sample.radiance.max(Vec3::ZERO),
                lighting,
                non_diffuse,
                distance: s.sample.distance,
                normal: s.sample.normal,
                object_id: pack_object_id(s.sample.object),
                radius: s.cell.radius(),
            }
        })
        .collect();
    LayeredVolume { samples, groups }
}
