//! A row of the geometry-assisted pixel loop ([`crate::geometry`]): its rays, hit points and
//! object slots, and the lookups of some or all of its pixels ([`crate::lookup`]).

use glam::{Vec3, Vec4};
use plenoptic_pack::CubeImage;

use super::{MaskSource, NONE, SlotMap};
use crate::camera::CameraBasis;
use crate::lookup::{NO_SLOT, Scratch, Shade};
use crate::sample;

/// Looks up the pixels `xs` of a row prepared in `s`: the whole row ([`Rows::prepare`]), or
/// (`packed`) the pixels side by side ([`Scratch::gather_rays`]), and hands each lookup to
/// `store` as (its keys' acceptance, pixel, radiance sum with the weight sum in `w`, second
/// colour's sum).
pub(super) fn lookup_some(
    shade: &Shade<'_>,
    s: &mut Scratch,
    packed: bool,
    xs: &[usize],
    obj: &[u32],
    mut store: impl FnMut(u32, usize, Vec4, Vec3),
) {
    if xs.is_empty() {
        return;
    }
    if !packed {
        shade.row(s, obj);
        for &x in xs {
            store(s.accepted[x], x, s.sum[x], s.sum2[x]);
        }
        return;
    }
    let objects: Vec<u32> = xs.iter().map(|&x| obj[x]).collect();
    shade.row(s, &objects);
    for (i, &x) in xs.iter().enumerate() {
        store(s.accepted[i], x, s.sum[i], s.sum2[i]);
    }
}

/// What preparing a row of the pixel loop needs.
pub(super) struct Rows<'a> {
    pub basis: &'a CameraBasis,
    pub source: &'a MaskSource<'a>,
    pub slot_of: &'a SlotMap,
    pub skipped: &'a [bool],
    pub env: Option<&'a CubeImage<Vec3>>,
    pub env_bilinear: bool,
    pub width: usize,
}

impl Rows<'_> {
    /// Row `y`'s directions, hit points and object slots into `s` ([`Rows::slots`]). `dep`
    /// holds camera-space depths, which become distances along the rays.
    pub fn prepare(
        &self,
        s: &mut Scratch,
        y: usize,
        dep: &mut [f32],
        obj: &mut [u32],
        out: Option<(&mut [Vec3], &mut [u8])>,
    ) {
        let w = self.width;
        s.resize(w);
        s.directions(self.basis, y, w);
        match self.source {
            MaskSource::Raster(_) => {
                for (z, &o) in dep.iter_mut().zip(obj.iter()) {
                    if o == 0 {
                        *z = f32::INFINITY;
                    }
                }
                s.points_from_depth(self.basis, dep);
            }
            MaskSource::Mask(m) => {
                for x in 0..w {
                    let o = m.object[y * w + x];
                    if o != 0 {
                        obj[x] = o;
                        dep[x] = m.depth[y * w + x];
                    }
                    s.set_p(x, m.position[y * w + x]);
                }
                s.eye_directions(self.basis.position, w);
            }
        }
        self.slots(&mut s.slot, y, obj, out);
    }

    /// The surface normals of row `y`'s pixels whose proxy triangles are `prims` (the whole
    /// row, or `xs` gathered), in the order `s`'s rays were set ([`Scratch::set_normals`]);
    /// from the mask's own normals where the mask was given.
    pub fn normals(&self, s: &mut Scratch, y: usize, xs: Option<&[usize]>, prims: &[u32]) {
        let normal = |x: usize| match self.source {
            MaskSource::Raster(tris) => tris.world_normal(self.basis, prims[x]),
            MaskSource::Mask(m) => m
                .normal
                .get(y * self.width + x)
                .copied()
                .unwrap_or_default(),
        };
        match xs {
            Some(xs) => s.set_normals(xs.iter().map(|&x| normal(x))),
            None => s.set_normals((0..self.width).map(normal)),
        }
    }

    /// Row `y`'s camera-space depths `dep` as distances along the rays (∞ where nothing is),
    /// as [`Rows::prepare`] leaves them.
    pub fn distances(&self, y: usize, dep: &mut [f32], obj: &[u32]) {
        let py = y as f32 + 0.5;
        for (x, (z, &o)) in dep.iter_mut().zip(obj).enumerate() {
            *z = if o == 0 {
                f32::INFINITY
            } else {
                *z * self.basis.ray(x as f32 + 0.5, py).length()
            };
        }
    }

    /// Row `y`'s object slots ([`NO_SLOT`]: nothing to look up). With `out`, the environment
    /// is written where nothing is, and those pixels and skipped objects' are classed as
    /// having no lookup.
    pub fn slots(
        &self,
        slot: &mut [u32],
        y: usize,
        obj: &[u32],
        mut out: Option<(&mut [Vec3], &mut [u8])>,
    ) {
        for x in 0..self.width {
            let o = obj[x];
            slot[x] = NO_SLOT;
            let found = self.slot_of.get(o).filter(|&s| !self.skipped[s]);
            if o != 0
                && let Some(found) = found
            {
                slot[x] = found as u32;
                continue;
            }
            let Some((rad, cls)) = out.as_mut() else {
                continue;
            };
            cls[x] = NONE;
            if o == 0
                && let Some(env) = self.env
            {
                let dir = self.basis.direction(x as f32 + 0.5, y as f32 + 0.5);
                rad[x] = if self.env_bilinear {
                    sample::bilinear(env, dir)
                } else {
                    env.texels[plenoptic_pack::cube::direction_to_texel(env.face_size, dir)]
                };
            }
        }
    }
}
