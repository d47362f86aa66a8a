//! Mirror and glossy reflections for the actual camera (docs/architecture.md, "Pack v2": "the
//! view-dependent part for the actual camera — reflected rays marched through the base views'
//! distance cubes, glossy lobes sampled by roughness").
//!
//! The pack's non-diffuse cube holds a surface's specular radiance as its *base view* saw
//! it: a mirror shows, from anywhere, what it reflected towards the base view. For surfaces
//! that need it ([`Specular::Marched`]: no transmission, roughness at most the setting's) the
//! geometry-assisted mode replaces it with
//!
//! `emission(uv) + W(n·ω_o) · L_in(reflect(−ω_o, n))` (ideal mirrors; glossy lobes below)
//!
//! - `L_in` is found by marching the reflected ray through the distance cubes of the frame's
//!   base views at the bracketing time keys, the way screen-space reflections march a depth
//!   buffer (thesis ch. 6: a base view's range image holds the radiance field around it).
//!   Along the ray `x(s) = p + s·r` the point is projected into the view's cube; the ray has
//!   hit where `|x(s) − c|` first passes the cube's distance `D(x(s) − c)`. The crossing is
//!   refined by bisection and accepted only when the ray meets the stored surface there (the
//!   distance step is within the tolerance); a crossing at a silhouette means the ray went
//!   behind what the view saw, and that view cannot answer. The radiance is the view's
//!   radiance cube around the hit direction. Each bracketing key is marched in its own
//!   cubes and weighted by its time weight, as the GPU's per-(view, key) lookups are.
//! - Steps follow the cube's texels: each advances the projected point by about
//!   [`STEP_TEXELS`] texels.
//! - A ray that meets no proxy triangle sees the environment (a ray cast through the proxies'
//!   BVHs, [`crate::shadow`], before any march). The march alone cannot tell: a ray leaving
//!   through a window is, from every base view but one on its line, first behind the wall
//!   beside the window (a silhouette), so no view would answer and the pixel would keep the
//!   baked reflection of another place (on the tour, room A's mirror would show its windows
//!   dim and in the wrong place).
//! - A ray that meets a proxy triangle is answered at that point, without a march:
//!   - an ideal mirror's ray (with [`crate::ReconSettings::shaded_reflections`]) shows the
//!     point shaded as a pixel is, albedo at its UV × the baked lighting + the runtime sun
//!     (`reflected.rs`): the reflected scene at screen resolution, as the camera's own
//!     pixels show it;
//!   - otherwise (glossy rays, each averaged over its cone, and mirrors with the setting off)
//!     every view whose distance cube holds the point (within the depth tolerance and a texel)
//!     gives its radiance there.
//!
//!   Only where no view holds the point is the ray marched, as without proxies.
//! - A ray marched to the scene's far distance without meeting a stored surface sees the
//!   environment too (packs without proxies).
//! - Roughness: a glossy surface marches [`GLOSSY_RAYS`] rays reflected about half-vectors
//!   drawn from the GGX distribution (α = roughness², a Hammersley set turned per pixel),
//!   and each hit's radiance is averaged over a cone of half-angle 0.7α as it appears from
//!   the base view at the hit's distance (a 5 × 5 Gaussian-weighted set of directions):
//!   prefiltering done on the unfiltered cube. A single cone as wide as the lobe would miss
//!   its long tails and darken the glossy steel of `plenoptic_bake`'s `specular` test.
//! - `W` is, for ideal mirrors, the tracer's own Fresnel (the exact dielectric one,
//!   Schlick's for metals). A glossy lobe instead weights each ray by `f·cos θ_i / pdf =
//!   F·G·(ω_o·h) / ((n·ω_o)(n·h))` ([`crate::brdf::Bsdf::glossy_weight`]), the importance-
//!   sampled estimate of the lobe's integral, which has no bias (the mean of the rays times
//!   Karis's split-sum fit of the directional albedo, B. Karis, "Physically Based Shading on
//!   Mobile", 2014, leaves the `specular` test's steel darker than the path tracer's). Glossy
//!   surfaces also add the placed lamps' highlights, which
//!   the march cannot see ([`crate::lamps`]).
//! - Views are weighted by their view-space weight and by how close their direction to the
//!   hit is to the ray's (the hit surface may be glossy too). A pixel no view answers keeps
//!   the baked non-diffuse radiance.
//!
//! Transmission keeps the baked radiance: the cube stores the glass's first surface, so a
//! ray refracted into it is behind the stored distance at once.

use std::sync::Arc;

use glam::Vec3;
use plenoptic_pack::cube::direction_to_texel;
use plenoptic_pack::{CubeImage, LightKind, Manifest, plenoptic_sky::PlacedEnvironment};

use crate::Reconstructor;
use crate::brdf::{DELTA_ROUGHNESS, SurfaceMaterial, fresnel_dielectric, fresnel_schlick};
use crate::reflected::ShadedHits;
use crate::shadow::{PlacedShadows, ProxyHit};
use crate::sun::PlacedSun;
use crate::temporal::key_weights;

/// How the geometry-assisted mode shows the specular part of surfaces with a material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Specular {
    /// The non-diffuse radiance the base views saw (highlights and reflections frozen at the
    /// base views' positions): one lookup pass, no march.
    Baked,
    /// Surfaces without transmission reflect for the actual camera, marched through the
    /// distance cubes ([`crate::specular`]): ideal mirrors always, glossy surfaces whose
    /// perceptual roughness is at most `max_roughness` when every punctual light's highlight
    /// is evaluated at runtime ([`glossy_allowed`]: the runtime sun's, placed lamps'); the
    /// others keep [`Specular::Baked`]. Costs a march per
    /// (view, key) and ray (up to [`MAX_STEPS`] cube lookups each; [`GLOSSY_RAYS`] rays on
    /// glossy surfaces).
    Marched {
        /// Roughest surface marched (rougher reflections are blurred enough that the base
        /// views' serve).
        max_roughness: f32,
    },
}

impl Default for Specular {
    fn default() -> Self {
        Specular::Marched {
            max_roughness: 0.45,
        }
    }
}

impl Specular {
    /// Whether a surface of material `m` is marched; `glossy`: whether glossy surfaces may
    /// be ([`glossy_allowed`]).
    pub fn marches(&self, m: &SurfaceMaterial, glossy: bool) -> bool {
        match *self {
            Specular::Baked => false,
            Specular::Marched { max_roughness } => {
                m.transmission <= 0.0
                    && (m.roughness < DELTA_ROUGHNESS || (glossy && m.roughness <= max_roughness))
            }
        }
    }
}

/// Whether glossy surfaces of `rec`'s pack may be marched: only when every light's direct
/// highlight is evaluated at runtime: the sun's ([`crate::sun`]) and every lamp's
/// ([`crate::lamps`], pack 4.1). A point or spot light has no geometry in the cubes, so
/// where the pack does not place it, a glossy surface's highlight of it exists only in the
/// baked non-diffuse radiance (an ideal mirror has none: the tracer's delta lobes take no
/// light samples).
pub fn glossy_allowed(rec: &Reconstructor) -> bool {
    glossy_allowed_in(rec.pack().manifest(), rec.runtime_sun().is_some())
}

/// [`glossy_allowed`] for a pack with `manifest`, which leaves its sun to the runtime when
/// `runtime_sun` (the GPU path decides with this).
pub fn glossy_allowed_in(manifest: &Manifest, runtime_sun: bool) -> bool {
    let directional = manifest
        .lights
        .iter()
        .filter(|l| matches!(l.kind, LightKind::Directional))
        .count();
    directional <= usize::from(runtime_sun) && crate::lamps::runtime_lamps(manifest).is_some()
}

/// How far a reflected ray is marched in a pack with `manifest` before it counts as leaving
/// the scene: 1.5 × the scene bounds' diagonal, or 100 m without bounds.
pub fn march_distance(manifest: &Manifest) -> f32 {
    let bounds = manifest.scene_bounds;
    let extent = (bounds.max - bounds.min).length();
    if extent.is_finite() && extent > 0.0 {
        extent * 1.5
    } else {
        100.0
    }
}

/// What a surface of transmissive glass with material `m` lets through per surface crossed,
/// when `settings` show it see-through (reflections marched, materials shown, transmission
/// above zero; `crate::glazing`): `(1 − F₀) · transmission · base colour`, F₀ from the IOR at
/// normal incidence. `None` where the glass shows its baked radiance instead. Both backends
/// call this.
pub fn see_through_transmittance(
    settings: &crate::ReconSettings,
    m: &plenoptic_pack::MaterialEntry,
) -> Option<Vec3> {
    let shown = matches!(settings.specular, Specular::Marched { .. })
        && settings.shading == crate::Shading::Materials
        && m.transmission > 0.0;
    shown.then(|| {
        let ior = if m.ior > 0.0 { m.ior } else { 1.5 };
        let f0 = ((ior - 1.0) / (ior + 1.0)).powi(2);
        let tint = m.base_colour.truncate().clamp(Vec3::ZERO, Vec3::ONE);
        tint * ((1.0 - f0) * m.transmission.min(1.0))
    })
}

/// How far (m) a reflected ray starts off its surface when it is cast against the proxies.
pub const RAY_OFFSET: f32 = 1e-3;

/// The cone (half-angle, radians) over which a gathering ray of [`crate::reflected`] averages
/// the views' radiance.
const GATHER_CONE: f32 = 0.1;

/// Rays per pixel on a glossy surface (`Reflections::lobe`).
pub const GLOSSY_RAYS: usize = 8;
/// Most march steps per view.
pub const MAX_STEPS: usize = 160;
/// Cube texels the projected point moves per march step: the bisection finds the crossing
/// within a step, and surfaces thinner than a step may be skipped. 2 halves the cost of 1;
/// it left the `specular` test's figures unchanged and moved the tour's mean from 0.583 to
/// 0.586 (its mirror frames 1.90 → 1.92 and 1.67 → 1.71).
pub const STEP_TEXELS: f32 = 2.0;
/// Bisection steps refining a crossing.
pub const REFINE_STEPS: usize = 6;

/// One base view's cubes at one time key for the reflection march.
struct MarchView {
    centre: Vec3,
    /// The view-space weight × the key's time weight.
    weight: f32,
    distance: Arc<CubeImage<f32>>,
    radiance: Arc<CubeImage<Vec3>>,
    /// The angle a texel subtends at the face centre.
    texel_angle: f32,
}

/// The base views' cubes at one time, ready to answer reflected rays.
pub(crate) struct Reflections<'r> {
    views: Vec<MarchView>,
    /// The proxies placed at the frame's time: a ray that meets none leaves the scene.
    rays: Option<PlacedShadows<'r>>,
    environment: PlacedEnvironment,
    /// The lamps whose highlights glossy surfaces add ([`crate::lamps`]).
    lamps: Vec<crate::lamps::RuntimeLamp>,
    /// How far a ray is marched before it counts as leaving the scene.
    far: f32,
    depth_tolerance: f32,
    angular_power: f32,
    /// Whether a ray that meets a proxy is answered at that point
    /// ([`crate::ReconSettings::shaded_reflections`]).
    at_hits: bool,
    /// Mirror rays' hits shaded as pixels are ([`crate::reflected`]), where the pack has
    /// proxies and materials and `at_hits`.
    shaded: Option<ShadedHits<'r>>,
    /// The camera's position and the angle one pixel subtends: a ray's footprint.
    eye: Vec3,
    pixel_angle: f32,
}

impl<'r> Reflections<'r> {
    /// The cubes of the views blended for `camera` at time `t`, the runtime `sun` shining on
    /// the surfaces mirrors show (unreadable keys are listed in `missing` and left out).
    pub fn new(
        rec: &'r Reconstructor,
        camera: &crate::Camera,
        t: f32,
        sun: Option<&'r PlacedSun<'r>>,
        missing: &mut Vec<String>,
    ) -> Self {
        let position = camera.position;
        let manifest = rec.pack().manifest();
        let mut views = Vec::new();
        for (v, w) in rec.view_weights(position) {
            let bv = &manifest.base_views[v];
            // Each key is marched in its own cubes (the GPU's lookups are per view and key).
            for (k, wk) in key_weights(&bv.time_keys, t) {
                let Some(cubes) = rec.key_cubes(v, k, missing) else {
                    continue;
                };
                views.push(MarchView {
                    centre: bv.position,
                    weight: w * wk,
                    texel_angle: 2.0 / cubes.distance.face_size.max(1) as f32,
                    distance: cubes.distance,
                    radiance: cubes.radiance,
                });
            }
        }
        let rays = rec
            .proxy_rays()
            .zip(rec.proxy())
            .map(|(r, proxy)| r.at(proxy, t));
        Reflections {
            views,
            rays,
            environment: rec.environment_at(t),
            lamps: rec.runtime_lamps().unwrap_or_default(),
            far: march_distance(manifest),
            depth_tolerance: rec.settings.depth_tolerance,
            angular_power: rec.settings.angular_power,
            at_hits: rec.settings.shaded_reflections,
            shaded: if rec.settings.shaded_reflections {
                ShadedHits::new(rec, position, t, sun, missing)
            } else {
                None
            },
            eye: position,
            pixel_angle: {
                let b = camera.basis();
                2.0 * b.tan_y / b.height
            },
        }
    }

    /// Radiance arriving at `origin` along unit direction `dir`, averaged over a cone of
    /// half-angle `cone` (radians): `None` where no base view can tell.
    pub fn incoming(&self, origin: Vec3, dir: Vec3, cone: f32) -> Option<Vec3> {
        // Off the surface the ray starts on before it is cast: the nearest hit where it is
        // answered there, else only whether anything is met.
        let start = origin + dir * RAY_OFFSET;
        let hit = match &self.rays {
            None => None,
            Some(rays) if !self.at_hits => {
                if !rays.occluded(start, dir, self.far) {
                    return Some(self.environment.radiance(dir));
                }
                None
            }
            Some(rays) => match rays.nearest(start, dir, self.far) {
                None => return Some(self.environment.radiance(dir)),
                Some(h) => Some(ProxyHit {
                    t: h.t + RAY_OFFSET,
                    ..h
                }),
            },
        };
        // Where the proxies tell where the ray meets a surface, the views that see that
        // point answer; the march is for packs without proxies, and for points no view sees
        // (and for every ray, as on the GPU, with `shaded_reflections` off).
        if let Some(hit) = hit {
            // A mirror's ray: the surface it meets shaded as a pixel is.
            if cone == 0.0
                && let Some(shaded) = &self.shaded
            {
                let width = ((origin - self.eye).length() + hit.t) * self.pixel_angle;
                // A point no view shows gathers its lighting from the rays it sends out,
                // answered as a glossy surface's are (the views' radiance where they meet).
                let gather = |o: Vec3, wi: Vec3| self.incoming(o, wi, GATHER_CONE);
                if let Some(c) = shaded.radiance(origin, dir, hit, width, &gather) {
                    return Some(c);
                }
            }
            let s = hit.t;
            let point = origin + dir * s;
            let (mut sum, mut total) = (Vec3::ZERO, 0.0f32);
            for v in self.views.iter().filter(|v| self.sees(v, point)) {
                let (l, w) = self.answer(v, dir, s, point, cone);
                sum += l * w;
                total += w;
            }
            if total > 0.0 {
                return Some(sum / total);
            }
        }
        let (mut sum, mut total) = (Vec3::ZERO, 0.0f32);
        let mut escaped = false;
        for v in &self.views {
            match self.march(v, origin, dir) {
                March::Hit { s, point } => {
                    let (l, w) = self.answer(v, dir, s, point, cone);
                    sum += l * w;
                    total += w;
                }
                March::Escaped => escaped = true,
                March::Hidden => {}
            }
        }
        if total > 0.0 {
            Some(sum / total)
        } else if escaped {
            Some(self.environment.radiance(dir))
        } else {
            None
        }
    }

    /// Whether `v`'s distance cube holds `point`: the distance stored towards it is the
    /// point's within the depth tolerance and a texel's size there (the march's test of a
    /// crossing).
    fn sees(&self, v: &MarchView, point: Vec3) -> bool {
        let to = point - v.centre;
        let d = to.length();
        let cube = &v.distance;
        let stored = cube.texels[direction_to_texel(cube.face_size, to)];
        (d - stored).abs() <= (self.depth_tolerance + v.texel_angle) * d
    }

    /// `v`'s radiance at `point`, met at `s` along the ray `dir`, over the lobe's cone
    /// `cone` as wide as it is there, and `v`'s weight for it: its view-space weight times
    /// how close its direction to the point is to the ray's.
    fn answer(&self, v: &MarchView, dir: Vec3, s: f32, point: Vec3, cone: f32) -> (Vec3, f32) {
        let to = point - v.centre;
        let d = to.length();
        let w = v.weight * angular_weight(to, dir, self.angular_power);
        // The lobe's cone, as wide as it is at the hit, seen from the view.
        let angle = (cone * s / d.max(1e-3)).min(0.5);
        (self.fetch(v, to, angle), w)
    }

    /// Radiance arriving at `origin` over a GGX lobe of roughness `alpha` (α = perceptual²)
    /// around normal `n`, seen from `wo`: the mean of [`Reflections::incoming`] over
    /// [`GLOSSY_RAYS`] directions reflected about half-vectors drawn from the lobe's
    /// distribution `D(h)(n·h)` (a Hammersley set turned by `turn` ∈ [0, 1), per pixel), each
    /// averaged over a cone a third of the lobe's width. `None` where no direction is
    /// answered.
    pub fn lobe(
        &self,
        origin: Vec3,
        bsdf: &crate::brdf::Bsdf,
        alpha: f32,
        turn: f32,
    ) -> Option<Vec3> {
        let n = bsdf.normal();
        let wo = bsdf.outgoing();
        let (a, b) = n.any_orthonormal_pair();
        let (mut sum, mut count) = (Vec3::ZERO, 0u32);
        for k in 0..GLOSSY_RAYS {
            let (u1, u2) = hammersley(k, GLOSSY_RAYS, turn);
            let tan2 = alpha * alpha * u1 / (1.0 - u1);
            let cos_h = 1.0 / (1.0 + tan2).sqrt();
            let sin_h = (1.0 - cos_h * cos_h).max(0.0).sqrt();
            let phi = std::f32::consts::TAU * u2;
            let h = n * cos_h + (a * phi.cos() + b * phi.sin()) * sin_h;
            let wi = h * (2.0 * wo.dot(h)) - wo;
            let w = bsdf.glossy_weight(h, wi);
            if w == Vec3::ZERO {
                // Below the surface: no light, but the lobe's share all the same.
                count += 1;
                continue;
            }
            if let Some(l) = self.incoming(origin, wi, 0.7 * alpha) {
                sum += l * w;
                count += 1;
            }
        }
        (count > 0).then(|| sum / count as f32)
    }

    /// The lamps' highlights at `p` (geometric normal `ng`) through `bsdf`, shadowed by the
    /// proxies ([`crate::lamps::highlights`]).
    pub fn highlights(&self, p: Vec3, ng: Vec3, bsdf: &crate::brdf::Bsdf) -> Vec3 {
        crate::lamps::highlights(&self.lamps, p, ng, bsdf, self.rays.as_ref())
    }

    /// Marches the ray through `v`'s distance cube.
    fn march(&self, v: &MarchView, origin: Vec3, dir: Vec3) -> March {
        let cube = &v.distance;
        // Signed gap between the point's distance from the view and the cube's there
        // (negative: in front of what the view saw).
        let gap = |s: f32| -> (f32, f32) {
            let q = origin + dir * s - v.centre;
            let d = q.length();
            let stored = cube.texels[direction_to_texel(cube.face_size, q)];
            (d - stored, d)
        };
        let start = gap(0.0).1;
        // Leave the surface the ray starts on: its own texels may be a texel's depth off.
        let mut s = (start * v.texel_angle).max(0.01);
        let mut prev_s = 0.0;
        for _ in 0..MAX_STEPS {
            if s > self.far {
                return March::Escaped;
            }
            let (g, d) = gap(s);
            if g > 0.0 {
                // Crossed between prev_s and s: refine.
                let (mut lo, mut hi) = (prev_s, s);
                let mut g_hi = g;
                for _ in 0..REFINE_STEPS {
                    let mid = 0.5 * (lo + hi);
                    let (gm, _) = gap(mid);
                    if gm > 0.0 {
                        hi = mid;
                        g_hi = gm;
                    } else {
                        lo = mid;
                    }
                }
                let point = origin + dir * hi;
                let d_hit = (point - v.centre).length();
                // A surface (not a silhouette the ray went behind): the step in distance is
                // within the tolerance, or the last step's size along the view's ray.
                let step = (hi - lo) + d_hit * v.texel_angle;
                if g_hi <= self.depth_tolerance * d_hit + step {
                    return March::Hit { s: hi, point };
                }
                return March::Hidden;
            }
            prev_s = s;
            // About STEP_TEXELS texels of the view's cube per step: the point moves across the
            // view's rays at sin θ of its speed along the ray.
            let q = (origin + dir * s - v.centre) / d.max(1e-6);
            let sin = q.cross(dir).length().max(0.15);
            s += (STEP_TEXELS * d * v.texel_angle / sin).clamp(0.005, 1.0);
        }
        March::Hidden
    }

    /// `v`'s radiance around direction `to`, over a cone of half-angle `angle`.
    fn fetch(&self, v: &MarchView, to: Vec3, angle: f32) -> Vec3 {
        let c = &v.radiance;
        let at = |dir: Vec3| -> Vec3 { c.texels[direction_to_texel(c.face_size, dir)] };
        let axis = to.normalize_or(Vec3::Z);
        if angle < 0.5 * v.texel_angle {
            return at(axis);
        }
        let (a, b) = axis.any_orthonormal_pair();
        let (mut sum, mut total) = (Vec3::ZERO, 0.0);
        for i in -2i32..=2 {
            for j in -2i32..=2 {
                let w = (-0.5 * (i * i + j * j) as f32).exp();
                let off = (a * i as f32 + b * j as f32) * (0.5 * angle);
                sum += at(axis + off) * w;
                total += w;
            }
        }
        sum / total
    }
}

/// How much a view whose direction to the point a ray meets is `to` counts for the ray along
/// unit `dir`: `((1 + cos) / 2)^power` of the angle between them (the view sees the point as
/// the ray does when they agree; the hit surface may be glossy).
pub(crate) fn angular_weight(to: Vec3, dir: Vec3, power: f32) -> f32 {
    let cos = to.dot(dir) / to.length().max(1e-6);
    ((1.0 + cos) * 0.5).max(1e-3).powf(power)
}

/// Point `k` of a Hammersley set of `n` in the unit square, its second coordinate turned by
/// `turn` ∈ [0, 1) (a per-pixel or per-point rotation, so that neighbours' sets differ): the
/// directions of a glossy lobe's rays and of a gather's.
pub(crate) fn hammersley(k: usize, n: usize, turn: f32) -> (f32, f32) {
    let u1 = (k as f32 + 0.5) / n as f32;
    let u2 = ((k as u32).reverse_bits() as f32 / 4_294_967_296.0 + turn).fract();
    (u1, u2)
}

/// How a march ended.
enum March {
    /// The ray met a surface the view saw, at `s` along it.
    Hit { s: f32, point: Vec3 },
    /// It went behind what the view saw: the view cannot tell what it meets.
    Hidden,
    /// It left the scene.
    Escaped,
}

/// An ideal mirror's reflectance at a surface of material `m` seen at `cos_o = n·ω_o`,
/// entering a medium of relative IOR `eta` (1/IOR on a back face): the tracer's own Fresnel
/// (the exact dielectric one, Schlick's for metals), what the radiance along the reflected
/// ray is multiplied by. Glossy lobes weight each of their rays instead
/// ([`crate::brdf::Bsdf::glossy_weight`]).
pub(crate) fn reflectance(m: &SurfaceMaterial, cos_o: f32, eta: f32) -> Vec3 {
    let cos_o = cos_o.clamp(1e-4, 1.0);
    let metal = m.metallic;
    Vec3::splat((1.0 - metal) * fresnel_dielectric(cos_o, eta))
        + fresnel_schlick(m.base, cos_o) * metal
}

#[cfg(test)]
mod tests {
    use super::*;

    fn metal(base: Vec3, roughness: f32) -> SurfaceMaterial {
        SurfaceMaterial {
            base,
            metallic: 1.0,
            roughness,
            transmission: 0.0,
            ior: 1.5,
            thin_walled: true,
        }
    }

    #[test]
    fn a_mirror_reflects_its_base_colour_head_on_and_everything_at_grazing() {
        let m = metal(Vec3::splat(0.9), 0.0);
        let head_on = reflectance(&m, 1.0, 1.5);
        assert!(
            (head_on - Vec3::splat(0.9)).abs().max_element() < 1e-4,
            "{head_on}"
        );
        let grazing = reflectance(&m, 0.01, 1.5);
        assert!(grazing.min_element() > 0.94, "{grazing}");
        // Glass head on: 4 %.
        let glass = SurfaceMaterial { metallic: 0.0, ..m };
        assert!((reflectance(&glass, 1.0, 1.5).x - 0.04).abs() < 1e-3);
    }

    #[test]
    fn only_opaque_smooth_surfaces_are_marched() {
        let s = Specular::default();
        assert!(s.marches(&metal(Vec3::ONE, 0.0), false));
        assert!(s.marches(&metal(Vec3::ONE, 0.4), true));
        assert!(!s.marches(&metal(Vec3::ONE, 0.4), false));
        assert!(!s.marches(&metal(Vec3::ONE, 0.5), true));
        let glass = SurfaceMaterial {
            transmission: 1.0,
            ..metal(Vec3::ONE, 0.0)
        };
        assert!(!s.marches(&glass, true));
        assert!(!Specular::Baked.marches(&metal(Vec3::ONE, 0.0), true));
    }

    /// One view at the origin with these cubes, under a uniform environment.
    fn one_view(
        distance: CubeImage<f32>,
        radiance: CubeImage<Vec3>,
        sky: Vec3,
    ) -> Reflections<'static> {
        Reflections {
            rays: None,
            views: vec![MarchView {
                centre: Vec3::ZERO,
                weight: 1.0,
                texel_angle: 2.0 / distance.face_size as f32,
                distance: Arc::new(distance),
                radiance: Arc::new(radiance),
            }],
            environment: PlacedEnvironment::Uniform(sky),
            lamps: Vec::new(),
            far: 20.0,
            depth_tolerance: 0.03,
            angular_power: 8.0,
            at_hits: false,
            shaded: None,
            eye: Vec3::ZERO,
            pixel_angle: 1e-3,
        }
    }

    /// A view at the origin inside a box room of half-size 2 whose walls have distinct
    /// radiance; a ray from a point on the floor towards +x must find the +x wall.
    #[test]
    fn a_march_finds_the_wall_the_ray_meets() {
        let n = 32;
        let room = |dir: Vec3| {
            let a = dir.abs();
            2.0 / a.max_element()
        };
        let colour = |dir: Vec3| {
            let (face, _, _) = plenoptic_pack::cube::direction_to_face_uv(dir);
            Vec3::splat(face as f32 + 1.0)
        };
        let r = one_view(
            CubeImage::from_fn(n, |_, d| room(d)),
            CubeImage::from_fn(n, |_, d| colour(d)),
            Vec3::splat(-1.0),
        );
        // From the floor (y = −2) up and towards +x: meets the +x wall (face 0) at y ≈ −1.
        let origin = Vec3::new(1.0, -2.0, 0.3);
        let dir = Vec3::new(1.0, 1.0, 0.0).normalize();
        let hit = r.incoming(origin, dir, 0.0).unwrap();
        assert_eq!(hit, Vec3::splat(1.0));
        // Straight up: the ceiling (face 2).
        assert_eq!(r.incoming(origin, Vec3::Y, 0.0).unwrap(), Vec3::splat(3.0));
        // A cone averages neighbouring texels: still the ceiling's colour in its middle.
        let blurred = r.incoming(Vec3::new(0.0, -2.0, 0.0), Vec3::Y, 0.2).unwrap();
        assert!((blurred - Vec3::splat(3.0)).length() < 1e-4, "{blurred}");
    }

    /// A pillar in front of the view hides part of the room: a ray passing behind it (as the
    /// view sees it) cannot be answered by that view; with no view left it is `None`, and a
    /// room with an opening lets the ray escape to the environment.
    #[test]
    fn rays_behind_an_occluder_are_hidden_and_openings_escape() {
        let n = 64;
        let pillar = |d: Vec3| d.z > 0.0 && (d.x / d.z).abs() < 0.1 && (d.y / d.z).abs() < 0.5;
        let distance = CubeImage::from_fn(n, |_, d| {
            if pillar(d) {
                0.5 / d.z
            } else if d.x > 0.9 * d.length() {
                f32::INFINITY // an opening towards +x
            } else {
                2.0 / d.abs().max_element()
            }
        });
        let r = one_view(distance, CubeImage::filled(n, Vec3::ONE), Vec3::splat(7.0));
        // From a point the view sees, along −x: it passes behind the pillar (as the view sees
        // it) before it could meet the −x wall.
        let behind = r.incoming(Vec3::new(0.3, 0.0, 0.6), Vec3::NEG_X, 0.0);
        assert_eq!(behind, None);
        // Out through the opening.
        let out = r.incoming(Vec3::new(0.5, 0.0, 0.0), Vec3::X, 0.0);
        assert_eq!(out, Some(Vec3::splat(7.0)));
    }
}
