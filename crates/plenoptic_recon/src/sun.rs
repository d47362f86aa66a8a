//! The runtime sun (pack 3; docs/architecture.md, "The runtime sun"; thesis ch. 5, direct and
//! indirect light at different accuracies: the sun's direct light is left out of the stored
//! lighting and evaluated at runtime against the proxy geometry).
//!
//! A pack whose environment entry has `direct_sun` stores its lighting and non-diffuse
//! radiance without the sun's direct light at the surfaces the base views see. Here it is
//! added back per pixel, for the actual camera and time:
//!
//! `L_sun = 1/K Σ_k f(ω_k, ω_o) · E_sun · |n · ω_k| · V(x, ω_k)`
//!
//! with `f` the surface's full BSDF ([`crate::brdf`]: the Lambertian lobe, and the GGX
//! highlight the base views would have frozen in place), `E_sun` the track's illuminance at t
//! and `V` a shadow ray against the proxies ([`crate::shadow`]; glazing, the pack's objects
//! with a coverage c, lets 1 − c through at each surface, as the tracer's shadow rays pass
//! it). A sun with a disc (angular
//! radius > 0) is sampled with `K` = [`crate::ReconSettings::sun_shadow_rays`] directions
//! spread uniformly over the disc's cone, as the tracer draws them (stratified in cos θ and φ,
//! the strata turned per pixel). The rays also leave from `K` points spread over the pixel's
//! footprint on the surface (a rotated R₂ lattice), so that a shadow edge is antialiased as the
//! path tracer's jittered pixels show it; `K` applies to a delta sun too. Where the `K` rays
//! disagree (some blocked, some not), the pixel straddles an edge or lies in a penumbra, and
//! its estimate is made again with [`crate::ReconSettings::sun_edge_rays`] (32): adaptive
//! sampling, so that only edge pixels pay for a finely antialiased edge. The first rays then
//! spread over twice the pixel's footprint, so that an edge clipping only a corner of the pixel
//! still splits them (with 4 rays over the pixel itself, a near-horizontal edge would go
//! unrefined in most of the pixels it crosses). A sun without a disc (a glTF directional light) casts
//! hard shadows, and there the rays are placed instead of scattered: 5 rays, from the pixel's 4
//! corners and its centre, find the pixel an edge crosses, and the lit fraction of that pixel
//! is measured along the edge (`sun_edge.rs`: 16 to 30 more rays, exact to about 0.002
//! for a straight edge). Scattered rays leave an error of order 1/K in each edge pixel, which
//! the path tracer's reference shows as a crawl along the edge. The edge rays remain for the
//! pixels no single straight edge explains. Shadow edges are therefore at screen resolution,
//! and a highlight moves with the camera.
//!
//! Surfaces whose every lobe is ideal (a mirror, clear glass) take no light sample, as in the
//! tracer: they show the sun through their baked specular paths.

use glam::{Vec2, Vec3};
use plenoptic_pack::PackReader;
use plenoptic_pack::plenoptic_sky::SunTrack;

use crate::brdf::Bsdf;
use crate::proxy::ProxyGeometry;
use crate::shadow::{PlacedShadows, ShadowScene, shadow_lift};

/// Largest number of shadow rays per pixel a setting may ask for.
pub const MAX_SUN_RAYS: u32 = 64;

/// How much wider than the pixel the first rays spread when edges are refined: an edge that
/// only clips a corner of the pixel still splits them, and where they agree the sun's
/// visibility is the same all over the pixel, so their estimate stands.
const DETECT_SPREAD: f32 = 2.0;

/// The pack's runtime sun with the proxies its shadow rays test.
#[derive(Debug)]
pub struct RuntimeSun {
    track: SunTrack,
    angular_radius: f32,
}

/// A [`RuntimeSun`] at one time.
pub struct PlacedSun<'s> {
    towards: Vec3,
    illuminance: Vec3,
    /// Tangent and bitangent of the cone around `towards`.
    frame: (Vec3, Vec3),
    cos_max: f32,
    rays: u32,
    /// Rays for a pixel whose first `rays` disagree (no more than `rays`: no refinement).
    edge_rays: u32,
    shadows: PlacedShadows<'s>,
}

impl PlacedSun<'_> {
    /// The sun with its illuminance multiplied by `weight` (its light group's).
    pub fn scaled(mut self, weight: Vec3) -> Self {
        self.illuminance *= weight;
        self
    }
}

impl RuntimeSun {
    /// The runtime sun of `pack`, when its lighting leaves the sun out.
    pub fn load(pack: &PackReader) -> Option<Self> {
        let (track, sun) = pack.direct_sun()?;
        Some(Self {
            track: track.clone(),
            angular_radius: sun.angular_radius,
        })
    }

    /// The sun at time `t`, its shadow rays against `shadows` (of `proxy`) placed then;
    /// `rays` shadow rays per pixel, and `edge_rays` where those disagree (both clamped to
    /// 1..=[`MAX_SUN_RAYS`]).
    pub fn at<'s>(
        &self,
        shadows: &'s ShadowScene,
        proxy: &ProxyGeometry,
        t: f32,
        (rays, edge_rays): (u32, u32),
    ) -> PlacedSun<'s> {
        let (towards, illuminance) = self.track.at(t);
        let towards = towards.normalize_or(Vec3::Y);
        PlacedSun {
            towards,
            illuminance,
            frame: towards.any_orthonormal_pair(),
            cos_max: self.angular_radius.min(0.5).cos(),
            rays: rays.clamp(1, MAX_SUN_RAYS),
            edge_rays: edge_rays.clamp(1, MAX_SUN_RAYS),
            shadows: shadows.at(proxy, t),
        }
    }
}

impl PlacedSun<'_> {
    /// Unit direction towards the sun's centre.
    pub fn towards(&self) -> Vec3 {
        self.towards
    }

    /// Radiance towards the viewer of the sun's direct light at `p` (geometric normal `ng`,
    /// either side) through `bsdf`; the pixel's footprint on the surface spans `footprint`
    /// (the displacements of a step of one pixel in x and in y) and `pixel` turns the strata.
    /// Where the first rays disagree, the estimate is made again with the edge rays.
    pub fn radiance(
        &self,
        p: Vec3,
        ng: Vec3,
        footprint: (Vec3, Vec3),
        bsdf: &Bsdf,
        pixel: u32,
    ) -> Vec3 {
        if self.illuminance == Vec3::ZERO || !bsdf.takes_light_samples() {
            return Vec3::ZERO;
        }
        let ray = |count, spread| Rays {
            p,
            ng,
            footprint: (footprint.0 * spread, footprint.1 * spread),
            count,
            turn: hash01(pixel),
            shift: hash01(pixel ^ 0x5bd1_e995),
        };
        let refine = self.edge_rays > self.rays;
        let sampled = |count| self.estimate(&ray(count, 1.0), bsdf).sum / count as f32;
        let sum = if refine && self.cos_max >= 1.0 {
            self.hard_edge(p, ng, footprint, bsdf)
                .unwrap_or_else(|| sampled(self.edge_rays))
        } else if refine {
            let first = self.estimate(&ray(self.rays, DETECT_SPREAD), bsdf);
            if first.open > 0 && first.blocked > 0 {
                sampled(self.edge_rays)
            } else {
                first.sum / self.rays as f32
            }
        } else {
            sampled(self.rays)
        };
        sum * self.illuminance
    }

    /// A sun without a disc, whose shadows are hard: the BSDF-weighted cosine times the lit
    /// fraction of the pixel. Rays from the 4 corners of the pixel's footprint find whether
    /// an edge crosses the pixel (any straight edge through it separates them), and one from
    /// its centre a shadow thinner than the pixel that passes between them; where they
    /// disagree, the fraction is measured along the edge ([`crate::sun_edge`]). `None` where
    /// no single straight edge explains the pixel.
    fn hard_edge(&self, p: Vec3, ng: Vec3, footprint: (Vec3, Vec3), bsdf: &Bsdf) -> Option<Vec3> {
        let wi = self.towards;
        let f = bsdf.eval(wi);
        if f == Vec3::ZERO {
            return Some(Vec3::ZERO);
        }
        let lift = shadow_lift(p, ng, wi);
        let pass = |uv: Vec2| {
            let q = p + footprint.0 * uv.x + footprint.1 * uv.y;
            self.shadows.transmittance(q + lift, wi, 1e9)
        };
        let probes = [
            (0.0, 0.0),
            (-0.5, -0.5),
            (0.5, -0.5),
            (0.5, 0.5),
            (-0.5, 0.5),
        ]
        .map(|(u, v)| pass(Vec2::new(u, v)));
        // The edge is where opaque proxies block; glazing the open rays cross dims them all
        // alike (its own border lies on its frame).
        let open = probes.map(|t| t > 0.0);
        let through = probes.iter().copied().fold(0.0, f32::max);
        let lit = if open.iter().all(|&c| c == open[0]) {
            f32::from(u8::from(open[0]))
        } else {
            crate::sun_edge::straight_edge_coverage(|uv| pass(uv) > 0.0)?
        };
        Some(f * wi.dot(bsdf.normal()).abs() * lit * through)
    }

    /// The sum over `rays` of the BSDF-weighted cosines of the unblocked ones, with how many
    /// rays were blocked and how many open.
    fn estimate(&self, rays: &Rays, bsdf: &Bsdf) -> Estimate {
        let n = bsdf.normal();
        let Rays {
            p,
            ng,
            footprint,
            count,
            turn,
            shift,
        } = *rays;
        let mut out = Estimate {
            sum: Vec3::ZERO,
            blocked: 0,
            open: 0,
        };
        for k in 0..count {
            let wi = self.direction(k, count, turn);
            let f = bsdf.eval(wi);
            if f == Vec3::ZERO {
                continue;
            }
            // Point k of the R₂ sequence in the pixel, turned per pixel; one ray: the centre.
            let q = if count == 1 {
                p
            } else {
                let u = (turn + k as f32 * 0.754_877_7).fract() - 0.5;
                let v = (shift + k as f32 * 0.569_840_3).fract() - 0.5;
                p + footprint.0 * u + footprint.1 * v
            };
            let pass = self
                .shadows
                .transmittance(q + shadow_lift(p, ng, wi), wi, 1e9);
            if pass == 0.0 {
                out.blocked += 1;
                continue;
            }
            out.open += 1;
            out.sum += f * wi.dot(n).abs() * pass;
        }
        out
    }

    /// Shadow-ray direction `k` of `rays`: uniform over the disc's cone, stratum `k` in
    /// cos θ, a golden-angle step in φ, all turned by `turn`.
    fn direction(&self, k: u32, rays: u32, turn: f32) -> Vec3 {
        if self.cos_max >= 1.0 {
            return self.towards;
        }
        let u = (k as f32 + 0.5) / rays as f32;
        let cos_t = 1.0 - u * (1.0 - self.cos_max);
        let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
        let phi = std::f32::consts::TAU * (turn + k as f32 * 0.618_034).fract();
        let (t, b) = self.frame;
        (t * (sin_t * phi.cos()) + b * (sin_t * phi.sin()) + self.towards * cos_t).normalize()
    }
}

/// The shadow rays of one estimate: from the pixel's point `p` (geometric normal `ng`) over
/// its `footprint`, `count` of them, their sequences turned by `turn` and `shift`.
#[derive(Clone, Copy)]
struct Rays {
    p: Vec3,
    ng: Vec3,
    footprint: (Vec3, Vec3),
    count: u32,
    turn: f32,
    shift: f32,
}

/// What [`PlacedSun::estimate`] found.
struct Estimate {
    sum: Vec3,
    blocked: u32,
    open: u32,
}

/// A number in [0, 1) from `x` (a 32-bit integer hash).
fn hash01(x: u32) -> f32 {
    let mut h = x.wrapping_mul(0x9E37_79B9) ^ 0x85EB_CA6B;
    h ^= h >> 16;
    h = h.wrapping_mul(0x7FEB_352D);
    h ^= h >> 15;
    (h >> 8) as f32 / (1u32 << 24) as f32
}
