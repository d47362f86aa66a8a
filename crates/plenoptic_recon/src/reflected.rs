//! The surface a mirror's reflected ray meets, shaded as a pixel of the camera's own frame
//! (docs/architecture.md, "Pack v2"; thesis ch. 8: illumination quality apart from image
//! quality, applied to what a mirror shows).
//!
//! A reflected ray cast against the proxies ([`crate::shadow::PlacedShadows::nearest`]) knows
//! the object and triangle it meets. That point is shaded as [`crate::shading`] shades a
//! pixel:
//!
//! `albedo(uv) · lighting + emission(uv) + non-diffuse + sun`
//!
//! - the *lighting* and the *non-diffuse radiance* are the base views' cubes at the point,
//!   looked up as a pixel's lookup is ([`crate::lookup::at_point`]: the nearest texel must
//!   show the point's surface, the bilinear taps that show it are blended), carried along the
//!   object's motion to each key's time, and weighted by the view's weight and by how close
//!   its direction to the point is to the ray's. Where none of the views blended for the
//!   camera shows the point, the other base views' keys at the frame's time are looked up
//!   the same way (a point far from the camera, seen in a mirror or through glass, is seen
//!   by a view near it: on the tour, glass reflecting the far side of the building); then
//!   the blended views' temporal-volume samples of its object near it;
//! - the *albedo* and the *emission* are the material's at the point's UV, the texture's mip
//!   chosen by the ray's footprint there (the pixel's cone, continued past the mirror);
//! - the runtime sun's direct light is evaluated at the point with its shadow rays
//!   ([`crate::sun`]), and so is the lamps' direct diffuse light where the pack leaves it to
//!   the runtime ([`crate::lamps::diffuse`]).
//!
//! Reading the base views' *radiance* at the hit instead (what the march does) shows the
//! reflected scene at cube resolution, its sun-shadow edges blurred, and takes the colour of
//! whatever a view's texel shows there: surfaces every view sees edge-on (the front of a box
//! level with the base views) come out as the colour of the box's top or of the floor behind
//! it, a pale ghost beside the box in the `specular` test's mirror.
//!
//! Where no view's cubes or samples show the point, its lighting is gathered: the mean
//! radiance arriving along [`GATHER_RAYS`] cosine-distributed rays, each cast against the
//! proxies and answered by the views that see where it lands (a final gather, as the bake's).
//! An irradiance probe at the base views (nine spherical-harmonic coefficients of each view's
//! radiance cube, evaluated on the point's normal) would light the gap behind the `specular`
//! test's box as the open room is lit; the gather sees the box.
//!
//! Glazing (a coverage, [`crate::glazing`]) is not shaded: its cube texels show what lies
//! behind it, blended as the tracer blends it, and the ray reads them there.

use std::collections::HashMap;
use std::sync::Arc;

use glam::{Affine3A, Vec3};

use crate::Reconstructor;
use crate::brdf::Bsdf;
use crate::lamps::RuntimeLamp;
use crate::lookup::{FastKey, PackedTexels, at_point};
use crate::material::Materials;
use crate::proxy::TriangleMesh;
use crate::reconstructor::KeyCubes;
use crate::shading::Channel;
use crate::shadow::PlacedShadows;
use crate::shadow::ProxyHit;
use crate::sun::PlacedSun;
use crate::volume::VolumeIndex;

/// One (view, key)'s lighting cubes, with the non-diffuse radiance beside them.
struct LitKey {
    base: Vec3,
    /// The view's weight × the key's time weight.
    weight: f32,
    /// The key's time.
    time: f32,
    cubes: KeyCubes,
    packed: Arc<PackedTexels>,
    non_diffuse: Option<Arc<plenoptic_pack::CubeImage<Vec3>>>,
}

/// An object placed at the frame's time, as a reflected ray's hit needs it.
struct PlacedObject<'r> {
    /// Object-to-world transform at the frame's time.
    xf: Affine3A,
    mesh: &'r TriangleMesh,
    /// Per key of [`ShadedHits::keys`]: M(τ) M(t)⁻¹, a point of the object at the frame's
    /// time carried to the key's time τ.
    to_key: Vec<Affine3A>,
}

/// What shading a reflected ray's hit needs at one camera position and time.
pub(crate) struct ShadedHits<'r> {
    rec: &'r Reconstructor,
    materials: &'r Materials,
    /// Pack id → the object placed, for the objects shaded: glazing (a coverage,
    /// `crate::glazing`) is left out, its cube texels showing what lies behind it as the
    /// tracer blends it.
    placed: HashMap<u32, PlacedObject<'r>>,
    /// The keys of the views blended for the camera, then those of every other view.
    keys: Vec<LitKey>,
    /// How many of `keys` are the blended views' (the others are read only where none of
    /// these shows a point).
    blended_keys: usize,
    /// Per base view: its position, weight and temporal-volume samples of the lighting.
    volumes: Vec<(Vec3, f32, VolumeIndex)>,
    sun: Option<&'r PlacedSun<'r>>,
    /// The lamps whose direct diffuse light the pack leaves to the runtime, and the proxies
    /// their shadow rays meet ([`crate::lamps::diffuse`]).
    lamps: Vec<RuntimeLamp>,
    lamp_shadows: Option<PlacedShadows<'r>>,
    depth_tolerance: f32,
    angular_power: f32,
}

impl<'r> ShadedHits<'r> {
    /// The lighting of the views blended for a camera at `position` at time `t`; `None`
    /// without proxies, materials or lighting cubes (unreadable keys are listed in `missing`
    /// and left out).
    pub fn new(
        rec: &'r Reconstructor,
        position: Vec3,
        t: f32,
        sun: Option<&'r PlacedSun<'r>>,
        missing: &mut Vec<String>,
    ) -> Option<Self> {
        let proxy = rec.proxy()?;
        let materials = rec.materials();
        if materials.is_empty() {
            return None;
        }
        let manifest = rec.pack().manifest();
        let mut keys = Vec::new();
        let mut volumes = Vec::new();
        let blended = rec.view_weights(position);
        for &(v, w) in &blended {
            keys.extend(lit_keys(rec, v, w, t, missing));
            if let Some(index) = VolumeIndex::build(rec, v, t, Channel::Lighting, missing) {
                volumes.push((manifest.base_views[v].position, w, index));
            }
        }
        let blended_keys = keys.len();
        // Then every other view, each weighted 1: a point the blended views cannot see (far
        // from the camera, seen in a mirror or through glass) is often seen by one of these.
        for v in 0..manifest.base_views.len() {
            if !blended.iter().any(|&(b, _)| b == v) {
                keys.extend(lit_keys(rec, v, 1.0, t, missing));
            }
        }
        if keys.is_empty() {
            // No lighting to look up (a pack without it, or unreadable keys): the radiance at
            // the hit serves, rather than a gather at every hit.
            return None;
        }
        let glazing: Vec<u32> = manifest
            .objects
            .iter()
            .filter(|o| o.coverage.is_some())
            .map(|o| o.id)
            .collect();
        let placed = proxy
            .placed_meshes(t)
            .into_iter()
            .filter(|(id, _, _)| !glazing.contains(id))
            .map(|(id, xf, mesh)| {
                let now_inverse = xf.inverse();
                let to_key = keys
                    .iter()
                    .map(|k| proxy.transform(id, k.time) * now_inverse)
                    .collect();
                (id, PlacedObject { xf, mesh, to_key })
            })
            .collect();
        let lamps = rec.lamps_lit_at_runtime();
        let lamp_shadows = rec
            .proxy_rays()
            .filter(|_| !lamps.is_empty())
            .map(|shadows| shadows.at(proxy, t));
        Some(ShadedHits {
            rec,
            materials,
            placed,
            keys,
            blended_keys,
            volumes,
            sun,
            lamps,
            lamp_shadows,
            depth_tolerance: rec.settings.depth_tolerance,
            angular_power: rec.settings.angular_power,
        })
    }

    /// The radiance leaving `hit`, met by the ray from `origin` along unit `dir`, towards
    /// `origin`; the ray's footprint is `width` metres across there. `None` where the object
    /// has no material or is glazing.
    pub fn radiance(
        &self,
        origin: Vec3,
        dir: Vec3,
        hit: ProxyHit,
        width: f32,
        gather: &dyn Fn(Vec3, Vec3) -> Option<Vec3>,
    ) -> Option<Vec3> {
        let object = self.placed.get(&hit.object)?;
        let p = origin + dir * hit.t;
        let surface = crate::surface::surface_at(
            self.rec,
            self.materials,
            hit.object,
            object.mesh,
            object.xf,
            hit.triangle,
            p,
            dir,
            width,
        )?;
        // The side of the surface the ray meets.
        let n = if surface.ns.dot(dir) > 0.0 {
            -surface.ns
        } else {
            surface.ns
        };
        let (lighting, non_diffuse) = match self.lighting(p, dir, hit.object, &object.to_key) {
            Some(l) => l,
            None => (self.gathered(p, n, surface.ng, gather)?, Vec3::ZERO),
        };
        let mut c = surface.material.albedo() * lighting + non_diffuse + surface.emission;
        if self.sun.is_some() || !self.lamps.is_empty() {
            let front = dir.dot(surface.ng) < 0.0;
            let bsdf = Bsdf::new(surface.material, surface.ng, surface.ns, -dir, front);
            if let Some(sun) = self.sun {
                c += sun.radiance(p, surface.ng, (Vec3::ZERO, Vec3::ZERO), &bsdf, 0);
            }
            let shadows = self.lamp_shadows.as_ref();
            c += crate::lamps::diffuse(&self.lamps, p, surface.ng, &bsdf, shadows);
        }
        Some(c)
    }

    /// The lighting and non-diffuse radiance at point `p` of `object`, met along `dir`: the
    /// blended views' keys whose cubes show it (the point carried to each key's time by
    /// `to_key`), else the other views' keys that show it, else the blended views' volume
    /// samples near it; `None` where none does.
    fn lighting(
        &self,
        p: Vec3,
        dir: Vec3,
        object: u32,
        to_key: &[Affine3A],
    ) -> Option<(Vec3, Vec3)> {
        let tol = self.depth_tolerance;
        let angular =
            |base: Vec3| crate::specular::angular_weight(p - base, dir, self.angular_power);
        let (mut sum, mut sum2, mut total) = (Vec3::ZERO, Vec3::ZERO, 0.0f32);
        for (i, (k, motion)) in self.keys.iter().zip(to_key).enumerate() {
            if i == self.blended_keys && total > 0.0 {
                break;
            }
            let second = k.non_diffuse.as_deref();
            let fast = FastKey::new(k.base, k.weight, &k.cubes, &k.packed, second, &[]);
            let at_key = motion.transform_point3(p);
            if let Some((l, second)) = at_point(&fast, at_key, object, tol) {
                let w = k.weight * angular(k.base);
                sum += l * w;
                sum2 += second.unwrap_or(Vec3::ZERO) * w;
                total += w;
            }
        }
        if total <= 0.0 {
            for (base, w, index) in &self.volumes {
                if let Some((l, second, wv)) = index.lookup_pair(
                    p - *base,
                    object,
                    tol,
                    Some(Channel::NonDiffuse),
                    Vec3::ZERO,
                ) {
                    let w = w * angular(*base) * wv;
                    sum += l * w;
                    sum2 += second * w;
                    total += w;
                }
            }
        }
        (total > 0.0).then(|| (sum / total, sum2 / total))
    }

    /// The diffuse lighting at `p` (normal `n` on the side it is seen from, geometric normal
    /// `ng`) gathered over [`GATHER_RAYS`] cosine-distributed directions: the mean of the
    /// radiance `gather` finds arriving along them (rays it cannot answer left out), which is
    /// `E/π` for cosine-weighted directions. `None` where no ray is answered.
    fn gathered(
        &self,
        p: Vec3,
        n: Vec3,
        ng: Vec3,
        gather: &dyn Fn(Vec3, Vec3) -> Option<Vec3>,
    ) -> Option<Vec3> {
        let (a, b) = n.any_orthonormal_pair();
        // A turn of the set per point (its coordinates hashed), so that neighbouring rays'
        // sets differ.
        let turn = {
            let h = (p * 1e4).as_ivec3();
            let k = (h.x as u32).wrapping_mul(0x9E37_79B1)
                ^ (h.y as u32).wrapping_mul(0x85EB_CA77)
                ^ (h.z as u32).wrapping_mul(0xC2B2_AE3D);
            (k >> 8) as f32 / (1u32 << 24) as f32
        };
        let (mut sum, mut count) = (Vec3::ZERO, 0u32);
        for k in 0..GATHER_RAYS {
            let (u1, u2) = crate::specular::hammersley(k, GATHER_RAYS, turn);
            let r = u1.sqrt();
            let phi = std::f32::consts::TAU * u2;
            let wi =
                (a * (r * phi.cos()) + b * (r * phi.sin()) + n * (1.0 - u1).sqrt()).normalize_or(n);
            let origin = p + crate::shadow::shadow_lift(p, ng, wi);
            if let Some(l) = gather(origin, wi) {
                sum += l;
                count += 1;
            }
        }
        (count > 0).then(|| sum / count as f32)
    }
}

/// The lighting cubes of base view `v` (weighted `w`) at the keys that bracket time `t`,
/// each weighted `w` × its time weight; unreadable keys are listed in `missing` and left out.
fn lit_keys(
    rec: &Reconstructor,
    v: usize,
    w: f32,
    t: f32,
    missing: &mut Vec<String>,
) -> Vec<LitKey> {
    let bv = &rec.pack().manifest().base_views[v];
    let mut keys = Vec::new();
    for (k, wk) in crate::temporal::key_weights(&bv.time_keys, t) {
        let Some(cubes) = rec.key_cubes_in(v, k, Channel::Lighting, missing) else {
            continue;
        };
        let non_diffuse = rec
            .key_cubes_in(v, k, Channel::NonDiffuse, missing)
            .map(|c| c.radiance)
            .filter(|c| c.face_size == cubes.distance.face_size);
        keys.push(LitKey {
            base: bv.position,
            weight: w * wk,
            time: bv.time_keys[k],
            packed: rec.packed_texels(v, k, Channel::Lighting, &cubes),
            cubes,
            non_diffuse,
        });
    }
    keys
}

/// Rays gathering the lighting of a point no view shows ([`ShadedHits::radiance`]).
pub const GATHER_RAYS: usize = 8;
