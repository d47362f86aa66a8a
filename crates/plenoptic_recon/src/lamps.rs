//! Lamps' direct light at runtime (packs 4.1 and 5.0; docs/architecture.md, "The runtime
//! lamps"; thesis ch. 5, direct and indirect light at different accuracies: the direct light
//! of punctual lights evaluated at runtime against the proxy geometry).
//!
//! A glossy surface's baked non-diffuse radiance holds the highlights of the scene's point
//! and spot lights as the base views saw them: frozen in the wrong place for any other
//! camera. Marching the reflection for the camera ([`crate::specular`]) cannot bring them
//! back, because a punctual light has no geometry in the cubes, so until pack 4.1 a pack
//! with a lamp kept its glossy surfaces baked. A 4.1 pack says where each lamp that never
//! moves is ([`plenoptic_pack::LightPlacement`]), and the glossy surfaces whose reflections
//! are marched add each lamp's highlight per pixel, as the tracer's next-event estimate
//! does:
//!
//! `L = Σ_lamps f_glossy(ω_l, ω_o) · I · colour / r² · a_spot · |n · ω_l| · V`
//!
//! with `f_glossy` the GGX lobe of the surface's BSDF ([`crate::brdf::Bsdf::eval_glossy`]),
//! `a_spot` glTF's smooth cone falloff, nothing beyond the light's range, and `V` a shadow
//! ray against the proxies.
//!
//! A 5.0 pack may also leave the lamps' direct *diffuse* light out of its lighting
//! ([`plenoptic_pack::PackReader::lamps_at_runtime`]): at 64-pixel faces a texel mixes the
//! brightly lit top of a table lamp with its dim side, and its shadow edges blur. Every
//! pixel with a material then adds
//!
//! `L = Σ_lamps f_diffuse(ω_l, ω_o) · I · colour / r² · a_spot · |n · ω_l| · V`
//!
//! with `f_diffuse` the Lambertian lobe of the tracer's BSDF ([`Bsdf::eval_diffuse`]): what
//! the bake took out (`RadianceSample::lamp_diffuse`). The sun is left to [`crate::sun`].

use glam::Vec3;
use plenoptic_pack::{LightKind, Manifest};

use crate::brdf::Bsdf;
use crate::shadow::{PlacedShadows, shadow_lift};

/// Most lamps whose light is evaluated per pixel (the GPU's view buffer holds this many). A
/// pack with more keeps its glossy surfaces baked.
pub use plenoptic_pack::MAX_RUNTIME_LAMPS;

/// A point or spot light, placed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RuntimeLamp {
    /// Position, metres.
    pub position: Vec3,
    /// Unit direction a spot light shines along.
    pub direction: Vec3,
    /// Colour × intensity (candela).
    pub radiant: Vec3,
    /// Its index in the manifest's lights.
    pub light: usize,
    /// Range, metres (infinite: none).
    pub range: f32,
    /// A spot light's cosines of its outer cone angle and `1 / (cos inner − cos outer)`;
    /// `None` for a point light.
    pub cone: Option<(f32, f32)>,
}

/// The lamps of a pack with `manifest` whose highlights the runtime evaluates: every point
/// and spot light, when all of them are placed and there are at most
/// [`MAX_RUNTIME_LAMPS`] ([`plenoptic_pack::lamps_placed`]); `None` when any highlight must
/// stay baked (a lamp that moves, an area light, a pack before 4.1, too many lamps).
/// Directional lights are not lamps.
pub fn runtime_lamps(manifest: &Manifest) -> Option<Vec<RuntimeLamp>> {
    if !plenoptic_pack::lamps_placed(&manifest.lights) {
        return None;
    }
    let mut lamps = Vec::new();
    for (i, l) in manifest.lights.iter().enumerate() {
        let cone = match l.kind {
            LightKind::Directional | LightKind::Area { .. } => continue,
            LightKind::Point => None,
            LightKind::Spot {
                inner_cone,
                outer_cone,
            } => {
                let (ci, co) = (inner_cone.cos(), outer_cone.cos());
                Some((co, 1.0 / (ci - co).max(1e-3)))
            }
        };
        let placed = l.placed.as_ref()?;
        lamps.push(RuntimeLamp {
            position: placed.position,
            direction: placed.direction,
            radiant: l.colour * l.intensity,
            light: i,
            range: placed.range.unwrap_or(f32::INFINITY),
            cone,
        });
    }
    Some(lamps)
}

impl RuntimeLamp {
    /// Direction towards the lamp from `p`, its distance, and the irradiance it gives normal
    /// to that direction (`None` beyond the range or outside the cone), as the tracer's
    /// `punctual_at` computes them.
    pub fn towards(&self, p: Vec3) -> Option<(Vec3, f32, Vec3)> {
        let d = self.position - p;
        let dist2 = d.length_squared();
        let dist = dist2.sqrt();
        if dist <= 0.0 || dist > self.range {
            return None;
        }
        let wi = d / dist;
        let mut value = self.radiant / dist2;
        if let Some((cos_outer, scale)) = self.cone {
            let att = ((self.direction.dot(-wi) - cos_outer) * scale).clamp(0.0, 1.0);
            value *= att * att;
        }
        (value != Vec3::ZERO).then_some((wi, dist, value))
    }
}

/// The lamps' highlights towards the viewer at `p` (geometric normal `ng`, either side)
/// through `bsdf`, each shadowed by a ray against `shadows` (all lit without proxies; glazing
/// lets 1 − c through at each surface, [`PlacedShadows::transmittance`]).
pub fn highlights(
    lamps: &[RuntimeLamp],
    p: Vec3,
    ng: Vec3,
    bsdf: &Bsdf,
    shadows: Option<&PlacedShadows>,
) -> Vec3 {
    direct(lamps, p, ng, bsdf, shadows, |wi| bsdf.eval_glossy(wi))
}

/// The lamps' direct diffuse light towards the viewer at `p` through `bsdf`'s Lambertian lobe,
/// shadowed as [`highlights`] are: what a 5.0 pack with runtime lamps leaves out of its
/// lighting.
pub fn diffuse(
    lamps: &[RuntimeLamp],
    p: Vec3,
    ng: Vec3,
    bsdf: &Bsdf,
    shadows: Option<&PlacedShadows>,
) -> Vec3 {
    direct(lamps, p, ng, bsdf, shadows, |wi| bsdf.eval_diffuse(wi))
}

/// `Σ_lamps f(ω_l) · E_l · |n · ω_l| · V_l` at `p`: each lamp's irradiance through the lobe
/// `f`, shadowed by a ray against `shadows`.
fn direct(
    lamps: &[RuntimeLamp],
    p: Vec3,
    ng: Vec3,
    bsdf: &Bsdf,
    shadows: Option<&PlacedShadows>,
    f: impl Fn(Vec3) -> Vec3,
) -> Vec3 {
    let n = bsdf.normal();
    let mut sum = Vec3::ZERO;
    for lamp in lamps {
        let Some((wi, dist, irradiance)) = lamp.towards(p) else {
            continue;
        };
        let f = f(wi);
        if f == Vec3::ZERO {
            continue;
        }
        let lift = shadow_lift(p, ng, wi);
        let pass = shadows.map_or(1.0, |s| {
            s.transmittance(p + lift, wi, dist - 2.0 * lift.length())
        });
        if pass == 0.0 {
            continue;
        }
        sum += f * irradiance * wi.dot(n).abs() * pass;
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::brdf::SurfaceMaterial;
    use plenoptic_pack::{Light, LightPlacement};

    fn light(kind: LightKind, placed: Option<LightPlacement>) -> Light {
        Light {
            kind,
            colour: Vec3::ONE,
            intensity: 10.0,
            follows_object: None,
            node_path: None,
            placed,
        }
    }

    fn at(position: Vec3) -> Option<LightPlacement> {
        Some(LightPlacement {
            position,
            direction: Vec3::NEG_Y,
            range: None,
        })
    }

    #[test]
    fn only_packs_whose_every_lamp_is_placed_have_runtime_lamps() {
        let mut m = Manifest::new(plenoptic_pack::TimeRange::default(), 1.0);
        m.lights = vec![light(LightKind::Directional, None)];
        assert_eq!(runtime_lamps(&m).map(|l| l.len()), Some(0));
        m.lights.push(light(LightKind::Point, at(Vec3::Y)));
        assert_eq!(runtime_lamps(&m).map(|l| l.len()), Some(1));
        // A lamp that moves (or a pack before 4.1) keeps every highlight baked.
        m.lights.push(light(LightKind::Point, None));
        assert_eq!(runtime_lamps(&m), None);
        m.lights.pop();
        m.lights.push(light(
            LightKind::Area {
                width: 1.0,
                height: 1.0,
            },
            at(Vec3::Y),
        ));
        assert_eq!(runtime_lamps(&m), None);
        m.lights.pop();
        for _ in 0..MAX_RUNTIME_LAMPS {
            m.lights.push(light(LightKind::Point, at(Vec3::X)));
        }
        assert_eq!(runtime_lamps(&m), None);
    }

    #[test]
    fn a_highlight_peaks_in_the_mirror_direction_and_falls_with_distance_and_cone() {
        let steel = SurfaceMaterial {
            base: Vec3::splat(0.8),
            metallic: 1.0,
            roughness: 0.3,
            transmission: 0.0,
            ior: 1.5,
            thin_walled: false,
        };
        // A floor seen from (−1, 1, 0): the mirror direction points at (1, 1, 0).
        let wo = Vec3::new(-1.0, 1.0, 0.0).normalize();
        let bsdf = Bsdf::new(steel, Vec3::Y, Vec3::Y, wo, true);
        let lamp = |position: Vec3, cone| RuntimeLamp {
            position,
            direction: -position.normalize(),
            radiant: Vec3::splat(10.0),
            light: 0,
            range: 5.0,
            cone,
        };
        let h = |l: RuntimeLamp| highlights(&[l], Vec3::ZERO, Vec3::Y, &bsdf, None).x;
        let mirror = h(lamp(Vec3::new(1.0, 1.0, 0.0), None));
        let aside = h(lamp(Vec3::new(-0.2, 1.0, 1.0), None));
        assert!(mirror > 10.0 * aside && aside >= 0.0, "{mirror} {aside}");
        // Twice as far: a quarter of the irradiance, the same lobe.
        let far = h(lamp(Vec3::new(2.0, 2.0, 0.0), None));
        assert!(
            (far - 0.25 * mirror).abs() < 1e-4 * mirror,
            "{far} {mirror}"
        );
        // Beyond the range, or a spot aimed elsewhere: nothing.
        assert_eq!(h(lamp(Vec3::new(4.0, 4.0, 0.0), None)), 0.0);
        let mut away = lamp(Vec3::new(1.0, 1.0, 0.0), Some((0.9, 10.0)));
        away.direction = Vec3::Y;
        assert_eq!(h(away), 0.0);
        // Below the surface: nothing.
        assert_eq!(h(lamp(Vec3::new(1.0, -1.0, 0.0), None)), 0.0);
    }

    #[test]
    fn a_lamps_diffuse_light_and_highlight_make_up_its_whole_reflection() {
        // Plastic: a Lambertian lobe under a glossy coat. Lit from above and aside, seen
        // from elsewhere: the two lobes sum to the BSDF's whole reflection.
        let plastic = SurfaceMaterial {
            base: Vec3::new(0.7, 0.5, 0.3),
            metallic: 0.0,
            roughness: 0.4,
            transmission: 0.0,
            ior: 1.5,
            thin_walled: false,
        };
        let wo = Vec3::new(-1.0, 0.8, 0.3).normalize();
        let bsdf = Bsdf::new(plastic, Vec3::Y, Vec3::Y, wo, true);
        let lamp = RuntimeLamp {
            position: Vec3::new(0.6, 1.5, -0.4),
            direction: Vec3::NEG_Y,
            radiant: Vec3::splat(8.0),
            light: 0,
            range: f32::INFINITY,
            cone: None,
        };
        let p = Vec3::new(0.1, 0.0, 0.2);
        let d = diffuse(&[lamp], p, Vec3::Y, &bsdf, None);
        let h = highlights(&[lamp], p, Vec3::Y, &bsdf, None);
        let (wi, _, e) = lamp.towards(p).unwrap();
        let whole = bsdf.eval(wi) * e * wi.dot(Vec3::Y);
        assert!(d.x > 0.0 && h.x > 0.0, "{d} {h}");
        assert!(
            (d + h - whole).abs().max_element() < 1e-5 * whole.max_element(),
            "{d} + {h} against {whole}"
        );
        // The Lambertian lobe is the albedo's share of what the Fresnel lets in: at most the
        // albedo over π per unit irradiance.
        let per_irradiance = d / (e * wi.dot(Vec3::Y));
        assert!(
            per_irradiance
                .cmple(plastic.albedo() / std::f32::consts::PI)
                .all()
        );
        assert!(per_irradiance.x > 0.8 * plastic.albedo().x / std::f32::consts::PI);
    }
}
