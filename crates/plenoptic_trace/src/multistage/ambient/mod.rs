//! The ambient field: indirect irradiance at sparse points of a simplified scene, stored per
//! object in object space (thesis §5.3: simplification by a quality parameter; §5.3.4:
//! ambient field reconstruction by barycentric interpolation).
//!
//! - [`FieldLayout`] (`layout.rs`): where the points are — tessellation, pruning and merging
//!   by the quality, grids sized by area and by edge length.
//! - `gather.rs`: the gather rays, traced once per point through delta bounces, and the
//!   bounces of indirect light iterated over those stored rays until they converge.
//! - `visibility.rs`: interpolation that does not leak through walls thinner than a cell.
//!
//! Why it is built this way (`docs/bake-accuracy.md` has the measurements): a
//! field gathered in two passes and extrapolated by one global ratio reached 0.73–0.79 of
//! the path tracer's mean luminance on the tour. The bounce ratio of a sunlit interior keeps
//! rising from pass to pass, so the extrapolation undershoots; gather rays stopped at glass
//! and mirrors; and about 30 % of the points lay inside solids while thin faces got points
//! metres apart. Each is fixed here: the iteration converges over the same rays, gather rays
//! follow delta bounces, points inside solids are filled from their neighbours, and grids
//! follow edge length as well as area.

mod gather;
mod layout;
mod visibility;

use glam::{Vec2, Vec3};
use plenoptic_scene::ObjectId;
use std::sync::Arc;

pub use layout::FieldLayout;

use crate::accel::PlacedScene;
use crate::{Result, TraceError};

/// Settings of the ambient field.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AmbientSettings {
    /// Quality q ∈ (0, 1]: finer tessellation and less pruning as it grows; the number of
    /// points (and the gathering time) grows about as q².
    pub quality: f32,
    /// Gather rays per point, traced once; noise of the field falls as 1/√rays.
    pub rays_per_point: u32,
    /// Most bounces of indirect light carried (1 = light that bounced once). The iteration
    /// over the stored rays costs a sparse product per bounce, far less than the tracing.
    pub max_bounces: u32,
    /// The iteration stops when the rest of the bounce series, estimated from the last two
    /// increments, is below this fraction of the field's summed luminance (0 = run all
    /// `max_bounces`).
    pub tolerance: f32,
    /// Delta bounces (mirrors, clear glass) a gather ray follows before it gives up.
    pub max_delta_depth: u32,
    /// Passes of edge-aware averaging over grid neighbours after convergence: each pass
    /// lowers the point-to-point noise (by about half the variance for six neighbours) and
    /// blurs indirect light over about one more cell; costs nothing next to the gathering.
    pub smoothing: u32,
    /// Seed of the random streams.
    pub seed: u64,
}

impl AmbientSettings {
    /// Coarse and quick: for previews and tests.
    pub const fn low() -> Self {
        Self {
            quality: 0.2,
            rays_per_point: 64,
            max_bounces: 64,
            tolerance: 0.005,
            max_delta_depth: 8,
            smoothing: 2,
            seed: 0,
        }
    }

    /// The default trade-off.
    pub const fn medium() -> Self {
        Self {
            quality: 0.5,
            rays_per_point: 128,
            ..Self::low()
        }
    }

    /// Fine and slow.
    pub const fn high() -> Self {
        Self {
            quality: 1.0,
            rays_per_point: 256,
            max_bounces: 128,
            tolerance: 0.002,
            ..Self::low()
        }
    }
}

impl Default for AmbientSettings {
    fn default() -> Self {
        Self::medium()
    }
}

/// Indirect irradiance (W/m², linear RGB) at the points of a [`FieldLayout`], for the scene at
/// one time.
#[derive(Debug, Clone, PartialEq)]
pub struct AmbientField {
    layout: Arc<FieldLayout>,
    time: f32,
    /// Per point, in the layout's flat order (object by object).
    irradiance: Vec<Vec3>,
    bounces: u32,
    invalid_points: usize,
    /// Per point: a grid edge of it is blocked, so lookups near it test visibility.
    guarded: Vec<bool>,
    /// Delta bounces a gather ray follows (`AmbientSettings::max_delta_depth`), for final
    /// gathers.
    max_delta_depth: u32,
}

impl AmbientField {
    /// A field of zeros on `layout`.
    pub fn zero(layout: Arc<FieldLayout>, time: f32) -> Self {
        let irradiance = vec![Vec3::ZERO; layout.point_count()];
        let guarded = vec![false; irradiance.len()];
        Self {
            layout,
            time,
            irradiance,
            bounces: 0,
            invalid_points: 0,
            guarded,
            max_delta_depth: AmbientSettings::default().max_delta_depth,
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
        let g = gather::gather(placed, &layout, settings);
        Self {
            layout,
            time: placed.time(),
            irradiance: g.irradiance,
            bounces: g.bounces,
            invalid_points: g.invalid,
            guarded: g.guarded,
            max_delta_depth: settings.max_delta_depth,
        }
    }

    /// Bounces of indirect light the field carries (where the iteration stopped).
    pub fn bounces(&self) -> u32 {
        self.bounces
    }

    /// Points found inside solids and filled from their neighbours.
    pub fn invalid_points(&self) -> usize {
        self.invalid_points
    }

    /// Indirect irradiance at `hit`, seen from direction `from` (unit, pointing away from the
    /// surface), interpolated only from the field points the hit can see where a wall or an
    /// object stands within one grid cell (`visibility.rs`); zero where the field has no
    /// data. This is the lookup the renderer uses.
    pub fn irradiance_seen(&self, placed: &PlacedScene<'_>, hit: &crate::Hit, from: Vec3) -> Vec3 {
        let Some(w) = visibility::visible_weights(placed, &self.layout, &self.guarded, hit, from)
        else {
            return Vec3::ZERO;
        };
        w.iter().map(|&(i, wt)| self.irradiance[i] * wt).sum()
    }

    /// Indirect irradiance at `hit` by a final gather of `rays` cosine-distributed rays, each
    /// reading the field where it ends (interpolated as [`Self::irradiance_seen`] interpolates)
    /// and adding the light it meets on the way, as the field's own gather does (`gather.rs`):
    /// one bounce traced from the hit itself, the field supplying longer paths. The field's
    /// grid is coarser than the falloff of light into a corner or under an object, and its
    /// interpolation smooths that falloff away: on the tour, read directly it makes dim blocks
    /// at base views 5–30 % bright (docs/bake-accuracy.md, cause 6). `from` is the direction
    /// towards the viewer: the gather leaves the side of the surface it faces. Unbiased where
    /// the field is, and noisy: one ray per sample needs smoothing afterwards (the bake's
    /// `LightingCube::smooth_ambient`).
    pub fn irradiance_gathered(
        &self,
        placed: &PlacedScene<'_>,
        hit: &crate::Hit,
        from: Vec3,
        rays: u32,
        s: &mut crate::sampling::Sampler,
    ) -> Vec3 {
        let g = hit.geometric_normal;
        let o = gather::Origin {
            p: hit.position,
            n: if g.dot(from) >= 0.0 { g } else { -g },
            rays: rays.max(1),
            max_delta_depth: self.max_delta_depth,
            guarded: &self.guarded,
        };
        gather::final_gather(placed, &self.layout, &self.irradiance, &o, s)
    }

    /// Points with a blocked grid edge, whose lookups test visibility.
    pub fn guarded_points(&self) -> usize {
        self.guarded.iter().filter(|&&g| g).count()
    }

    /// Indirect irradiance at barycentrics (b1, b2) of `triangle` of `object`, plain
    /// barycentric interpolation without visibility (zero where the field has no data).
    pub fn irradiance_at(&self, object: ObjectId, triangle: u32, barycentrics: Vec2) -> Vec3 {
        let Some(w) = self.layout.weights(object, triangle, barycentrics) else {
            return Vec3::ZERO;
        };
        let base = self.layout.offsets[object as usize];
        w.iter()
            .map(|&(i, wt)| self.irradiance[base + i as usize] * wt)
            .sum()
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
            .map(|(p, q)| p.lerp(*q, s))
            .collect();
        Ok(Self {
            layout: a.layout.clone(),
            time: a.time + (b.time - a.time) * s,
            irradiance,
            bounces: a.bounces.min(b.bounces),
            invalid_points: a.invalid_points.max(b.invalid_points),
            guarded: a
                .guarded
                .iter()
                .zip(&b.guarded)
                .map(|(x, y)| *x || *y)
                .collect(),
            max_delta_depth: a.max_delta_depth.max(b.max_delta_depth),
        })
    }

    /// The sum of fields of one scene lit by different emitters (light groups: light
    /// transport is linear in the emitters), on the same layout. `None` for no fields.
    pub fn sum(fields: &[Self]) -> Option<Result<Self>> {
        let (first, rest) = fields.split_first()?;
        let mut out = first.clone();
        for f in rest {
            if !Arc::ptr_eq(&out.layout, &f.layout) && out.layout != f.layout {
                return Some(Err(TraceError::FieldMismatch(
                    "the fields were built on different layouts".into(),
                )));
            }
            for (p, q) in out.irradiance.iter_mut().zip(&f.irradiance) {
                *p += *q;
            }
            out.bounces = out.bounces.min(f.bounces);
            out.invalid_points = out.invalid_points.max(f.invalid_points);
            for (x, y) in out.guarded.iter_mut().zip(&f.guarded) {
                *x |= *y;
            }
        }
        Some(Ok(out))
    }

    /// Mean irradiance over all points (a cheap summary for tests and key-time selection).
    pub fn mean_irradiance(&self) -> Vec3 {
        let n = self.layout.point_count().max(1) as f32;
        self.irradiance.iter().copied().sum::<Vec3>() / n
    }

    /// Relative RMS difference of two fields on the same layout: RMS of the luminance
    /// difference over points divided by the mean luminance of `self` (the baker picks
    /// ambient key times with it).
    pub fn relative_rms(&self, other: &Self) -> f64 {
        let mut sq = 0.0f64;
        let mut sum = 0.0f64;
        let mut n = 0usize;
        for (x, y) in self.irradiance.iter().zip(&other.irradiance) {
            let (lx, ly) = (
                f64::from(crate::image::luminance(*x)),
                f64::from(crate::image::luminance(*y)),
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
