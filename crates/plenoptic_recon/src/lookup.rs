//! The per-pixel work of the geometry-assisted mode, a row of pixels at a time.
//!
//! The row is held as a structure of arrays ([`Scratch`]) and processed in passes: the hit
//! points of all pixels, then, key by key, the lookup directions and texels of all pixels
//! (branch-free arithmetic the compiler vectorises), then the tests and sums (gathers from the
//! cubes). Every value is computed with the same operations in the same order as a
//! pixel-at-a-time loop over glam's `Vec3` would (no fused multiply-adds, the same
//! association), so the frames are identical to such a loop's, bit for bit.

use glam::{Affine3A, BVec4A, Vec3, Vec4};
use plenoptic_pack::cube;

use std::sync::Arc;

use crate::camera::CameraBasis;
use crate::reconstructor::KeyCubes;
use crate::sample;

/// One texel of a key's cubes: what an accepted lookup reads, together (half a cache line).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Texel {
    /// Radiance and 1: weighted, it adds to the radiance sum and the weight sum at once.
    pub radiance: Vec4,
    pub id: u32,
    pub distance: f32,
}

/// The object-id, distance and radiance cubes of one (view, key) interleaved texel by texel
/// (a lookup touches one cache line instead of three); built once per decoded key and cached
/// by the [`crate::Reconstructor`].
pub(crate) struct PackedTexels {
    pub texels: Vec<Texel>,
    /// The cubes it was built from (to tell when the chunk cache has reloaded them).
    from: KeyCubes,
}

impl PackedTexels {
    pub fn new(cubes: &KeyCubes) -> Self {
        let texels = cubes
            .ids
            .texels
            .iter()
            .zip(&cubes.distance.texels)
            .zip(&cubes.radiance.texels)
            .map(|((&id, &distance), &radiance)| Texel {
                radiance: radiance.extend(1.0),
                id,
                distance,
            })
            .collect();
        PackedTexels {
            texels,
            from: cubes.clone(),
        }
    }

    /// Whether it was built from these very cubes.
    pub fn built_from(&self, cubes: &KeyCubes) -> bool {
        Arc::ptr_eq(&self.from.ids, &cubes.ids)
            && Arc::ptr_eq(&self.from.distance, &cubes.distance)
            && Arc::ptr_eq(&self.from.radiance, &cubes.radiance)
    }

    /// Bytes held, the cubes it keeps alive included.
    pub fn bytes(&self) -> usize {
        self.texels.len() * (std::mem::size_of::<Texel>() + 20)
    }
}

/// A key's data as flat slices for the pixel loop.
pub(crate) struct FastKey<'a> {
    pub base: Vec3,
    pub weight: f32,
    pub face: u32,
    /// Id, distance and radiance per texel.
    pub texels: &'a [Texel],
    /// A second colour per texel, blended with the same weights as the radiance (the
    /// non-diffuse radiance beside the lighting: one pass looks up both).
    pub second: Option<&'a [Vec3]>,
    pub normal: Option<&'a [Vec3]>,
    /// Per object slot: M(τ) M(t)⁻¹.
    pub motion: &'a [Affine3A],
    /// Per object slot: the previous key has the same base view, face size and transform, so
    /// its lookup direction and texel can be reused.
    pub reuse: Vec<bool>,
}

impl<'a> FastKey<'a> {
    /// The key at `base` with weight `weight`: its `cubes` (their ids, distances and
    /// normals), `packed` from them, the `second` colour's cube and the objects' `motion`.
    pub fn new(
        base: Vec3,
        weight: f32,
        cubes: &'a KeyCubes,
        packed: &'a PackedTexels,
        second: Option<&'a plenoptic_pack::CubeImage<Vec3>>,
        motion: &'a [Affine3A],
    ) -> Self {
        FastKey {
            base,
            weight,
            face: cubes.ids.face_size,
            texels: &packed.texels,
            second: second.map(|c| c.texels.as_slice()),
            normal: cubes.normal.as_deref().map(|c| c.texels.as_slice()),
            motion,
            reuse: Vec::new(),
        }
    }
}

/// No object slot: nothing to look up for this pixel.
pub(crate) const NO_SLOT: u32 = u32::MAX;
/// No texel.
const NO_TEXEL: u32 = u32::MAX;

/// Per-row arrays (one set per rayon job, reused from row to row).
#[derive(Default)]
pub(crate) struct Scratch {
    /// Object slot per pixel ([`NO_SLOT`]: nothing to look up).
    pub slot: Vec<u32>,
    /// Unit ray direction per pixel.
    pub dir: [Vec<f32>; 3],
    /// `right · sx` per column of the frame (empty until the first row).
    columns: [Vec<f32>; 3],
    /// Hit point.
    pub p: [Vec<f32>; 3],
    /// Unit direction from the hit point to the eye.
    e: [Vec<f32>; 3],
    /// The pixel's surface normal (its proxy triangle's, unit, facing the eye; zero where
    /// unknown, which turns the face test of [`same_face`] off).
    n: [Vec<f32>; 3],
    /// The current lookup: direction from the base view, its length, the texel ([`NO_TEXEL`]:
    /// none), the angular weight.
    d: [Vec<f32>; 3],
    dist: Vec<f32>,
    ti: Vec<u32>,
    wa: Vec<f32>,
    /// With bilinear filtering: the first texel of the lookup's footprint ([`NO_TEXEL`]:
    /// across a seam) and the fractions along u and v.
    tap: Vec<u32>,
    fx: Vec<f32>,
    fy: Vec<f32>,
    /// Weighted radiance sum and, in `w`, the weight sum.
    pub sum: Vec<Vec4>,
    /// Weighted sum of the keys' second colours (same weights as `sum`).
    pub sum2: Vec<Vec3>,
    /// Which keys' lookups were accepted: bit 2k for key k, bit 2k + 1 where all four of its
    /// bilinear taps were (keys from the 16th on share the last two bits).
    pub accepted: Vec<u32>,
}

impl Scratch {
    /// Sizes every array for rows of `n` pixels.
    pub fn resize(&mut self, n: usize) {
        // Whole groups of four lanes; the padding is never fresh.
        let n = n.next_multiple_of(4);
        self.slot.resize(n, NO_SLOT);
        for a in [
            &mut self.dir,
            &mut self.p,
            &mut self.e,
            &mut self.d,
            &mut self.n,
        ] {
            for c in a {
                c.resize(n, 0.0);
            }
        }
        self.dist.resize(n, 0.0);
        self.ti.resize(n, NO_TEXEL);
        self.wa.resize(n, 0.0);
        self.tap.resize(n, NO_TEXEL);
        self.fx.resize(n, 0.0);
        self.fy.resize(n, 0.0);
        self.sum.resize(n, Vec4::ZERO);
        self.sum2.resize(n, Vec3::ZERO);
        self.accepted.resize(n, 0);
    }

    /// Makes this scratch hold the pixels `xs` of row `y` side by side (lane `i` is pixel
    /// `xs[i]`): their unit ray directions, hit points at distances `dist` along the rays,
    /// eye directions, and slots from `slots`.
    pub fn gather_rays(
        &mut self,
        b: &CameraBasis,
        y: usize,
        xs: &[usize],
        dist: &[f32],
        slots: &[u32],
    ) {
        let n = xs.len();
        self.resize(n);
        let o = b.position;
        for (i, &x) in xs.iter().enumerate() {
            let d = b.direction(x as f32 + 0.5, y as f32 + 0.5);
            let p = o + d * dist[x];
            let e = (o - p).normalize_or_zero();
            for (c, (dc, pc, ec)) in [(d.x, p.x, e.x), (d.y, p.y, e.y), (d.z, p.z, e.z)]
                .into_iter()
                .enumerate()
            {
                self.dir[c][i] = dc;
                self.p[c][i] = pc;
                self.e[c][i] = ec;
            }
            self.slot[i] = slots[x];
        }
        for c in &mut self.n {
            c[..n].fill(0.0);
        }
        // The padding of the last group of four looks nothing up.
        self.slot[n..].fill(NO_SLOT);
    }

    /// The unit ray directions of row `y` (what [`CameraBasis::direction`] gives at the pixel
    /// centres).
    pub fn directions(&mut self, b: &CameraBasis, y: usize, n: usize) {
        let [cx, cy, cz] = &mut self.columns;
        if cx.len() != n {
            // right · sx per column, the same for every row (a frame's scratch is its own).
            cx.clear();
            cy.clear();
            cz.clear();
            for x in 0..n {
                let sx = (2.0 * (x as f32 + 0.5) / b.width - 1.0) * b.tan_x;
                cx.push(b.right.x * sx);
                cy.push(b.right.y * sx);
                cz.push(b.right.z * sx);
            }
        }
        let sy = (1.0 - 2.0 * (y as f32 + 0.5) / b.height) * b.tan_y;
        let (ux, uy, uz) = (b.up.x * sy, b.up.y * sy, b.up.z * sy);
        let (cx, cy, cz) = (&cx[..n], &cy[..n], &cz[..n]);
        let [dx, dy, dz] = &mut self.dir;
        let (dx, dy, dz) = (&mut dx[..n], &mut dy[..n], &mut dz[..n]);
        for x in 0..n {
            let rx = cx[x] + ux + b.forward.x;
            let ry = cy[x] + uy + b.forward.y;
            let rz = cz[x] + uz + b.forward.z;
            let r = 1.0 / (rx * rx + ry * ry + rz * rz).sqrt();
            dx[x] = rx * r;
            dy[x] = ry * r;
            dz[x] = rz * r;
        }
    }

    /// Hit points from camera-space depths `z` (∞: none): writes the distance along the ray
    /// back into `z` (∞ stays ∞) and the points and eye directions into the scratch.
    #[inline(never)]
    pub fn points_from_depth(&mut self, b: &CameraBasis, z: &mut [f32]) {
        let n = z.len();
        let [dx, dy, dz] = &self.dir;
        let (dx, dy, dz) = (&dx[..n], &dy[..n], &dz[..n]);
        let [px, py, pz] = &mut self.p;
        let (px, py, pz) = (&mut px[..n], &mut py[..n], &mut pz[..n]);
        let (f, o) = (b.forward, b.position);
        for x in 0..n {
            let dist = z[x] / (dx[x] * f.x + dy[x] * f.y + dz[x] * f.z);
            z[x] = if z[x] == f32::INFINITY {
                f32::INFINITY
            } else {
                dist
            };
            px[x] = o.x + dx[x] * dist;
            py[x] = o.y + dy[x] * dist;
            pz[x] = o.z + dz[x] * dist;
        }
        self.eye_directions(o, n);
    }

    /// Unit directions from the hit points to the eye (`normalize_or_zero`).
    pub fn eye_directions(&mut self, o: Vec3, n: usize) {
        let [px, py, pz] = &self.p;
        let (px, py, pz) = (&px[..n], &py[..n], &pz[..n]);
        let [ex, ey, ez] = &mut self.e;
        let (ex, ey, ez) = (&mut ex[..n], &mut ey[..n], &mut ez[..n]);
        for x in 0..n {
            let (vx, vy, vz) = (o.x - px[x], o.y - py[x], o.z - pz[x]);
            let r = 1.0 / (vx * vx + vy * vy + vz * vz).sqrt();
            let ok = r.is_finite() && r > 0.0;
            ex[x] = if ok { vx * r } else { 0.0 };
            ey[x] = if ok { vy * r } else { 0.0 };
            ez[x] = if ok { vz * r } else { 0.0 };
        }
    }

    /// The surface normals of the first pixels from world normals either side (zero:
    /// unknown, no face test), turned to face the eye against the pixels' ray directions
    /// (which must be set).
    pub fn set_normals(&mut self, normals: impl Iterator<Item = Vec3>) {
        for (i, n) in normals.enumerate() {
            let d = Vec3::new(self.dir[0][i], self.dir[1][i], self.dir[2][i]);
            let n = if n.dot(d) > 0.0 { -n } else { n };
            (self.n[0][i], self.n[1][i], self.n[2][i]) = (n.x, n.y, n.z);
        }
    }

    /// Sets the hit point of pixel `x` (the eye directions must be recomputed after).
    #[inline]
    pub fn set_p(&mut self, x: usize, p: Vec3) {
        self.p[0][x] = p.x;
        self.p[1][x] = p.y;
        self.p[2][x] = p.z;
    }
}

/// What the per-pixel lookups need.
pub(crate) struct Shade<'a> {
    pub fast: &'a [FastKey<'a>],
    /// Relative distance tolerance.
    pub tol: f32,
    /// Angular power, and the same as an integer when it is one (else 0).
    pub power: f32,
    pub power_int: u32,
    /// Seamless bilinear filtering of the radiance of accepted lookups.
    pub bilinear: bool,
}

impl Shade<'_> {
    /// The blends of the accepted lookups of a row of pixels (`s.slot`, `s.p` and the eye
    /// directions filled; `obj`: their objects) into `s.sum` and `s.ws`.
    ///
    /// Key by key: the lookups of the whole row, then their tests and sums. A key that has the
    /// same base view, face size and motion as the previous one for a pixel's object keeps the
    /// previous lookup. The sums are in key order, as one pixel at a time would make them.
    pub fn row(&self, s: &mut Scratch, obj: &[u32]) {
        let n = obj.len();
        s.sum[..n].fill(Vec4::ZERO);
        s.sum2[..n].fill(Vec3::ZERO);
        s.accepted[..n].fill(0);
        for (ki, k) in self.fast.iter().enumerate() {
            self.lookups(s, k, ki == 0, n);
            self.accumulate(s, k, obj, 2 * ki.min(15) as u32);
        }
    }

    /// The lookups of key `k` for the pixels that do not reuse the previous key's, four
    /// pixels at a time.
    #[inline(never)]
    fn lookups(&self, s: &mut Scratch, k: &FastKey<'_>, first: bool, n: usize) {
        let n4 = n.next_multiple_of(4);
        let slots = &s.slot[..n4];
        let [px, py, pz] = &s.p;
        let (px, py, pz) = (&px[..n4], &py[..n4], &pz[..n4]);
        let [ex, ey, ez] = &s.e;
        let (ex, ey, ez) = (&ex[..n4], &ey[..n4], &ez[..n4]);
        let [dx, dy, dz] = &mut s.d;
        let (dx, dy, dz) = (&mut dx[..n4], &mut dy[..n4], &mut dz[..n4]);
        let (dist, ti, wa) = (&mut s.dist[..n4], &mut s.ti[..n4], &mut s.wa[..n4]);
        let (tap, fxs, fys) = (&mut s.tap[..n4], &mut s.fx[..n4], &mut s.fy[..n4]);
        let geometry = CubeLanes::new(k.face);
        let b = k.base;
        let (bx, by, bz) = (Vec4::splat(b.x), Vec4::splat(b.y), Vec4::splat(b.z));
        let load = |a: &[f32], x: usize| Vec4::from_slice(&a[x..x + 4]);
        for x in (0..n4).step_by(4) {
            let sl = [slots[x], slots[x + 1], slots[x + 2], slots[x + 3]];
            let is_fresh = |s: u32| s != NO_SLOT && (first || !k.reuse[s as usize]);
            let fresh = [
                is_fresh(sl[0]),
                is_fresh(sl[1]),
                is_fresh(sl[2]),
                is_fresh(sl[3]),
            ];
            if fresh == [false; 4] {
                if first {
                    ti[x..x + 4].fill(NO_TEXEL);
                }
                continue;
            }
            let (p0, p1, p2) = (load(px, x), load(py, x), load(pz, x));
            // The points at the key's time: M(τ) M(t)⁻¹ p, as `Affine3A::transform_point3`
            // computes it, lane by lane.
            let (qx, qy, qz) = if sl[1..].iter().all(|&s| s == sl[0]) {
                let m = &k.motion[sl[0] as usize];
                let (a, bb, c, t) = (
                    m.matrix3.x_axis,
                    m.matrix3.y_axis,
                    m.matrix3.z_axis,
                    m.translation,
                );
                let row = |a: f32, bb: f32, c: f32, t: f32| {
                    Vec4::splat(a) * p0
                        + Vec4::splat(bb) * p1
                        + Vec4::splat(c) * p2
                        + Vec4::splat(t)
                };
                (
                    row(a.x, bb.x, c.x, t.x),
                    row(a.y, bb.y, c.y, t.y),
                    row(a.z, bb.z, c.z, t.z),
                )
            } else {
                let (mut qx, mut qy, mut qz) = ([0.0f32; 4], [0.0f32; 4], [0.0f32; 4]);
                for i in 0..4 {
                    if fresh[i] {
                        let q = k.motion[sl[i] as usize].transform_point3(Vec3::new(
                            px[x + i],
                            py[x + i],
                            pz[x + i],
                        ));
                        (qx[i], qy[i], qz[i]) = (q.x, q.y, q.z);
                    }
                }
                (Vec4::from(qx), Vec4::from(qy), Vec4::from(qz))
            };
            let (vx, vy, vz) = (qx - bx, qy - by, qz - bz);
            let dist2 = vx * vx + vy * vy + vz * vz;
            let invalid = dist2.is_nan_mask() | dist2.cmple(Vec4::splat(1e-12));
            let l = dist2.sqrt();
            let (t, taps, fx, fy) = geometry.texels(vx, vy, vz, self.bilinear);
            let invalid = invalid.bitmask();
            for i in 0..4 {
                if fresh[i] && invalid & (1 << i) == 0 {
                    ti[x + i] = t[i];
                } else if fresh[i] || first {
                    ti[x + i] = NO_TEXEL;
                }
            }
            if self.bilinear {
                for i in 0..4 {
                    if fresh[i] {
                        tap[x + i] = taps[i];
                    }
                }
                let f = BVec4A::new(fresh[0], fresh[1], fresh[2], fresh[3]);
                let put = |a: &mut [f32], v: Vec4| {
                    Vec4::select(f, v, load(a, x)).write_to_slice(&mut a[x..x + 4]);
                };
                put(fxs, fx);
                put(fys, fy);
            }
            let e = load(ex, x) * vx + load(ey, x) * vy + load(ez, x) * vz;
            let cos = -e / l;
            let c = ((Vec4::ONE + cos) * 0.5).max(Vec4::splat(1e-3));
            let w = if self.power <= 0.0 {
                Vec4::ONE
            } else if self.power_int > 0 {
                powi4(c, self.power_int)
            } else {
                Vec4::from(c.to_array().map(|c| c.powf(self.power)))
            };
            let f = BVec4A::new(fresh[0], fresh[1], fresh[2], fresh[3]);
            let put = |a: &mut [f32], v: Vec4| {
                Vec4::select(f, v, load(a, x)).write_to_slice(&mut a[x..x + 4]);
            };
            put(dx, vx);
            put(dy, vy);
            put(dz, vz);
            put(dist, l);
            put(wa, w);
        }
    }

    /// Tests the current lookups of key `k` and adds the accepted ones to the sums.
    #[inline(never)]
    fn accumulate(&self, s: &mut Scratch, k: &FastKey<'_>, obj: &[u32], bit: u32) {
        let n = obj.len();
        let tol = self.tol;
        let (ti, dist, wa) = (&s.ti[..n], &s.dist[..n], &s.wa[..n]);
        let (tap, fxs, fys) = (&s.tap[..n], &s.fx[..n], &s.fy[..n]);
        let sum = &mut s.sum[..n];
        for x in 0..n {
            let t = ti[x] as usize;
            let Some(tx) = k.texels.get(t) else { continue };
            if tx.id != obj[x] {
                continue;
            }
            // The pixel's normal in the key's frame (an object's motion turns it).
            let np = Vec3::new(s.n[0][x], s.n[1][x], s.n[2][x]);
            let np = match k.motion.get(s.slot[x] as usize) {
                Some(m) if np != Vec3::ZERO => m.transform_vector3(np),
                _ => np,
            };
            if !same_face(k, t, np) {
                continue;
            }
            let (dc, l) = (tx.distance, dist[x]);
            // Fast path: the texel's centre distance agrees. Otherwise compare with the
            // distance to the texel's surface plane along the lookup direction (grazing
            // surfaces change depth quickly across a texel).
            if (dc - l).abs() > tol * l {
                let Some(nc) = k.normal else { continue };
                let nrm = nc[t];
                let d = Vec3::new(s.d[0][x], s.d[1][x], s.d[2][x]);
                let denom = d.dot(nrm) / l;
                if denom.abs() <= 0.05 {
                    continue;
                }
                let expected = (cube::texel_direction(k.face, t) * dc).dot(nrm) / denom;
                if (expected - l).abs() > tol * l {
                    continue;
                }
            }
            // The colour and, with a second colour, that one with the same weights.
            let mut whole = !self.bilinear;
            let (radiance, second) = if !self.bilinear {
                (tx.radiance, k.second.and_then(|c| c.get(t).copied()))
            } else if tap[x] != NO_TEXEL {
                // The footprint inside one face: its texels of the same object at the same
                // distance, and the nearest texel.
                let (i, fx, fy) = (tap[x] as usize, fxs[x], fys[x]);
                let n = k.face as usize;
                let (Some(a), Some(b)) = (k.texels.get(i..i + 2), k.texels.get(i + n..i + n + 2))
                else {
                    continue;
                };
                let o = obj[x];
                let d = Vec3::new(s.d[0][x], s.d[1][x], s.d[2][x]);
                let keep =
                    |tj: &Texel, j: usize| j == t || same_surface(k, tj, j, (o, np), d, l, tol);
                // Each tap tested once (the plane test is not free).
                let kept = [
                    keep(&a[0], i),
                    keep(&a[1], i + 1),
                    keep(&b[0], i + n),
                    keep(&b[1], i + n + 1),
                ];
                whole = kept == [true; 4];
                let w = |k: usize, w: f32| if kept[k] { w } else { 0.0 };
                let taps = [
                    (i, w(0, (1.0 - fx) * (1.0 - fy))),
                    (i + 1, w(1, fx * (1.0 - fy))),
                    (i + n, w(2, (1.0 - fx) * fy)),
                    (i + n + 1, w(3, fx * fy)),
                ];
                let acc = a[0].radiance * taps[0].1
                    + a[1].radiance * taps[1].1
                    + b[0].radiance * taps[2].1
                    + b[1].radiance * taps[3].1;
                if acc.w > 0.0 {
                    let second = k.second.map(|c| {
                        taps.iter().fold(Vec3::ZERO, |s, &(j, w)| {
                            s + c.get(j).copied().unwrap_or_default() * w
                        }) * (1.0 / acc.w)
                    });
                    (acc * (1.0 / acc.w), second)
                } else {
                    (tx.radiance, k.second.and_then(|c| c.get(t).copied()))
                }
            } else {
                let d = Vec3::new(s.d[0][x], s.d[1][x], s.d[2][x]);
                filtered(k, d, t, (obj[x], np), l, tol)
            };
            s.accepted[x] |= (1 | (whole as u32) << 1) << bit;
            let weight = k.weight * wa[x];
            sum[x] += radiance * weight;
            if let Some(c) = second {
                s.sum2[x] += c * weight;
            }
        }
    }
}

/// The cosine below which a texel's normal and the pixel's surface normal are two faces: the
/// texel is not the pixel's surface however near it lies ([`same_face`]). 60°: well beyond a
/// smooth normal's turn across a proxy triangle or a normal map's bumps, well short of a
/// crease (a wall and the reveal of its window, 90°) or the far side of a thin surface (180°).
pub const SAME_FACE_COS: f32 = 0.5;

/// Whether texel `j` of key `k` faces as the pixel's surface does: its stored normal (which
/// faces the base view) within [`SAME_FACE_COS`] of the pixel's normal `np` (facing the
/// camera, in the key's frame). Without either normal (a key without normals, a pixel without
/// a proxy triangle: `np` zero) every texel passes. A window's reveal is the wall's object at
/// the wall's distance; without this test the wall beside the window takes the reveal's
/// sky-lit texels and shows a bright halo, and the side of room B's lamp (a closed cylinder)
/// takes the texels of its lamp-lit top where the two meet.
#[inline]
fn same_face(k: &FastKey<'_>, j: usize, np: Vec3) -> bool {
    match k.normal.and_then(|c| c.get(j)) {
        Some(n) if np != Vec3::ZERO => n.dot(np) >= SAME_FACE_COS,
        _ => true,
    }
}

/// Whether texel `j` of key `k` (its texel `tj`) shows the surface of the lookup `d` (from
/// the base view, length `l`) of object `o` whose surface normal is `np`: the same object,
/// facing alike ([`same_face`]), and its distance agrees within
/// the relative tolerance `tol`, or (where the key has normals) the texel's centre point lies
/// on the plane through the lookup's point with the texel's normal, within `tol · l`. A
/// surface seen at a grazing angle changes distance by more than the tolerance from one
/// texel to the next; without the plane the bilinear footprint would lose those taps, and the
/// lighting would show the cube's texels as blocks (docs/architecture.md, "Reconstruction").
#[inline]
fn same_surface(
    k: &FastKey<'_>,
    tj: &Texel,
    j: usize,
    (o, np): (u32, Vec3),
    d: Vec3,
    l: f32,
    tol: f32,
) -> bool {
    if tj.id != o || !same_face(k, j, np) {
        return false;
    }
    if (tj.distance - l).abs() <= tol * l {
        return true;
    }
    let Some(n) = k.normal.and_then(|c| c.get(j)) else {
        return false;
    };
    let centre = cube::texel_direction(k.face, j) * tj.distance;
    (centre - d).dot(*n).abs() <= tol * l
}

/// The radiance of key `k` in direction `d` (length `l`) filtered over the bilinear taps that
/// show the lookup's surface of object `o` ([`same_surface`]) or are the nearest texel `t`,
/// as radiance and 1; and its second colour filtered alike.
fn filtered(
    k: &FastKey<'_>,
    d: Vec3,
    t: usize,
    (o, np): (u32, Vec3),
    l: f32,
    tol: f32,
) -> (Vec4, Option<Vec3>) {
    let (mut acc, mut acc2) = (Vec4::ZERO, Vec3::ZERO);
    for (i, w) in sample::bilinear_taps(k.face, d) {
        let Some(tx) = k.texels.get(i) else { continue };
        if w > 0.0 && (i == t || same_surface(k, tx, i, (o, np), d, l, tol)) {
            acc += tx.radiance * w;
            if let Some(c) = k.second.and_then(|c| c.get(i)) {
                acc2 += *c * w;
            }
        }
    }
    if acc.w > 0.0 {
        (
            (acc.truncate() / acc.w).extend(1.0),
            k.second.map(|_| acc2 / acc.w),
        )
    } else {
        (
            k.texels[t].radiance,
            k.second.and_then(|c| c.get(t).copied()),
        )
    }
}

/// Key `k`'s colour at point `p` of object `o` (placed at the key's time; `None` where the
/// key's nearest texel towards it shows another surface, [`same_surface`]), filtered as a
/// pixel's lookup is, with its second colour: a single lookup outside the pixel loop (the
/// surface a reflected ray meets, [`crate::specular`]).
pub(crate) fn at_point(k: &FastKey<'_>, p: Vec3, o: u32, tol: f32) -> Option<(Vec3, Option<Vec3>)> {
    let d = p - k.base;
    let l = d.length();
    if l.is_nan() || l <= 1e-6 {
        return None;
    }
    let t = cube::direction_to_texel(k.face, d);
    let tx = k.texels.get(t)?;
    if !same_surface(k, tx, t, (o, Vec3::ZERO), d, l, tol) {
        return None;
    }
    let (c, second) = filtered(k, d, t, (o, Vec3::ZERO), l, tol);
    Some((c.truncate(), second))
}

/// 2²³ as f32.
const TWO_23: f32 = (1u32 << 23) as f32;

/// `c^k` for `k ≥ 1` by repeated squaring, lane by lane as `f32::powi` multiplies.
#[inline(always)]
fn powi4(mut c: Vec4, mut k: u32) -> Vec4 {
    let mut r = Vec4::ONE;
    loop {
        if k & 1 == 1 {
            r *= c;
        }
        k >>= 1;
        if k == 0 {
            return r;
        }
        c *= c;
    }
}

/// Cube texel addressing four directions at a time: [`cube::direction_to_texel`] with
/// selects instead of branches, and the index computed in f32 (exact for cubes of fewer than
/// 2²³ texels, face size ≤ 1182; larger cubes take [`cube::direction_to_texel`] lane by lane).
struct CubeLanes {
    face_size: u32,
    n: Vec4,
    n_minus_1: Vec4,
    face_texels: Vec4,
    exact: bool,
}

impl CubeLanes {
    fn new(face_size: u32) -> Self {
        let n = face_size.max(1) as f32;
        CubeLanes {
            face_size,
            n: Vec4::splat(n),
            n_minus_1: Vec4::splat(n - 1.0),
            face_texels: Vec4::splat(n * n),
            exact: 6 * (face_size.max(1) as u64).pow(2) < 1 << 23,
        }
    }

    /// The texel indices of directions (x, y, z) and, with `bilinear`, their bilinear
    /// footprints where they lie inside one face: the index of the first texel (the others are
    /// +1, +n, +n+1; [`NO_TEXEL`] where the footprint crosses a seam) and the fractions along
    /// u and v.
    #[inline(always)]
    fn texels(
        &self,
        x: Vec4,
        y: Vec4,
        z: Vec4,
        bilinear: bool,
    ) -> ([u32; 4], [u32; 4], Vec4, Vec4) {
        let none = ([NO_TEXEL; 4], Vec4::ZERO, Vec4::ZERO);
        if !self.exact {
            let (x, y, z) = (x.to_array(), y.to_array(), z.to_array());
            let t = std::array::from_fn(|i| {
                cube::direction_to_texel(self.face_size, Vec3::new(x[i], y[i], z[i])) as u32
            });
            return (t, none.0, none.1, none.2);
        }
        let (face, u, v) = self.face_uv(x, y, z);
        let zero = Vec4::ZERO;
        let (un, vn) = (u * self.n, v * self.n);
        // `(u n) as usize` then `min(n − 1)`; NaN → 0 (maxps returns its second operand).
        let i = un.trunc().max(zero).min(self.n_minus_1);
        let j = vn.trunc().max(zero).min(self.n_minus_1);
        let base = face * self.face_texels;
        let t = to_indices(base + j * self.n + i);
        if !bilinear {
            return (t, none.0, none.1, none.2);
        }
        // The footprint's first texel: floor(u n − ½) is i or i − 1.
        let half = Vec4::splat(0.5);
        let (s, r) = (un - half, vn - half);
        let i0 = Vec4::select(s.cmpge(i), i, i - Vec4::ONE);
        let j0 = Vec4::select(r.cmpge(j), j, j - Vec4::ONE);
        let last = self.n_minus_1 - Vec4::ONE;
        let inside = i0.cmpge(zero) & i0.cmple(last) & j0.cmpge(zero) & j0.cmple(last);
        let mut first = to_indices(Vec4::select(inside, base + j0 * self.n + i0, zero));
        let inside = inside.bitmask();
        for (k, f) in first.iter_mut().enumerate() {
            if inside & (1 << k) == 0 {
                *f = NO_TEXEL;
            }
        }
        (t, first, s - i0, r - j0)
    }

    /// `(face, u, v)` of directions (x, y, z), as [`cube::direction_to_face_uv`] computes them.
    #[inline(always)]
    fn face_uv(&self, x: Vec4, y: Vec4, z: Vec4) -> (Vec4, Vec4, Vec4) {
        let sel = Vec4::select;
        let zero = Vec4::ZERO;
        let (ax, ay, az) = (x.abs(), y.abs(), z.abs());
        let xm = ax.cmpge(ay) & ax.cmpge(az);
        let ym = !xm & ay.cmpge(az);
        let (px, py, pz) = (x.cmpge(zero), y.cmpge(zero), z.cmpge(zero));
        let face = sel(
            xm,
            sel(px, zero, Vec4::splat(1.0)),
            sel(
                ym,
                sel(py, Vec4::splat(2.0), Vec4::splat(3.0)),
                sel(pz, Vec4::splat(4.0), Vec4::splat(5.0)),
            ),
        );
        let sc = sel(xm, sel(px, -z, z), sel(ym | pz, x, -x));
        let tc = sel(ym, sel(py, z, -z), -y);
        let ma = sel(xm, ax, sel(ym, ay, az));
        let ok = ma.cmpgt(zero) & ma.is_finite_mask();
        let half = Vec4::splat(0.5);
        let u = sel(ok, half * (sc / ma + Vec4::ONE), half);
        let v = sel(ok, half * (tc / ma + Vec4::ONE), half);
        (sel(ok, face, zero), u, v)
    }
}

/// Non-negative integral f32 values below 2²³ as u32: the low 23 bits of `value + 2²³`.
#[inline(always)]
fn to_indices(v: Vec4) -> [u32; 4] {
    let t = (v + Vec4::splat(TWO_23)).to_array();
    let m = (1 << 23) - 1;
    [
        t[0].to_bits() & m,
        t[1].to_bits() & m,
        t[2].to_bits() & m,
        t[3].to_bits() & m,
    ]
}

#[cfg(test)]
#[path = "lookup_tests.rs"]
mod tests;
