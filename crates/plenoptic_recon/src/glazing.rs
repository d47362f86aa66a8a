//! See-through surfaces in geometry-assisted mode (docs/architecture.md, "Daylight"): glass
//! exported as glTF `alphaMode: BLEND` is traced as *coverage*, a ray stopping at it with
//! probability c (the pack's [`plenoptic_pack::ObjectEntry::coverage`]). Drawn as an opaque
//! proxy, a window would show its cube texels: the pane where the bake's rays stopped at it,
//! and elsewhere the sky behind, clamped and at cube resolution.
//!
//! Here the frame is reconstructed in two layers instead, as a rasterizer draws transparent
//! surfaces after opaque ones:
//! 1. *behind*: every proxy except the glazing, with the environment evaluated per pixel where
//!    nothing is (the sky through the window at full resolution);
//! 2. *glazing*: the glazing proxies alone. Their lookups accept only the texels whose rays
//!    stopped at the pane, so they give the pane's own radiance (its reflection and tint).
//!
//! Where a glazing surface is nearer than what lies behind it, the pixel's ray crosses k
//! glazing surfaces before it (counted by a ray cast through the glazing proxies' BVH: a
//! pane modelled as a thin box is two surfaces, and the path tracer's ray meets each with
//! probability c), and the pixel is `(1 − (1 − c)^k) · L_glazing + (1 − c)^k · L_behind`,
//! with the glazing's depth and object id: the mean over the coverage the path tracer
//! samples, with every crossed surface taken to shine as the nearest does (counting one
//! crossing, c · L_glazing + (1 − c) · L_behind, would show a pane modelled as a thin box
//! brighter than the path tracer does). The GPU draws both faces in the transparent pass, which
//! blends the same way.
//!
//! Transmissive glass (glTF `KHR_materials_transmission`, shown with materials and marched
//! reflections) is see-through the same way, as a thin wall: its layer shows only the
//! surface's reflection for the camera (marched, [`crate::specular`]), and the pixel is
//! `L_reflection ⊙ (1 + T + … + T^(k−1)) + T^k ⊙ L_behind` (every surface crossed taken to
//! reflect as the nearest does) with the per-surface transmittance
//! `T = (1 − F₀) · transmission · base colour` (F₀ from the IOR, at normal incidence;
//! [`crate::specular::see_through_transmittance`]). Glass that is also `BLEND` glazing is
//! composited as glazing. Rays go straight through, as glTF's default *thin-walled*
//! transmission has it (and the tracer, `plenoptic_trace::material`): exact for every surface
//! without `KHR_materials_volume`. A solid of glass (the pack's material thickness above 0)
//! would bend what is seen through it; it is shown as thin walls, its refraction left out.
//! The baked radiance would show the base view's view through the glass, displaced and at
//! cube resolution (the tour's glass balustrade a dark smear over the brick wall behind it).
//! The GPU draws such glass in Bevy's transparent pass with premultiplied alpha, both faces,
//! its reflection over what lies behind with the mean of T (`bevy_plenoptic::reconstruct`).
//!
//! Image and volume modes warp the range images whole and keep showing the baked texels
//! (the thesis's baselines).

use glam::Vec3;

use crate::background::{self, Coverage};
use crate::frame::{Frame, Report};
use crate::geometry::{Layer, Shot};
use crate::shading;
use crate::shadow::ShadowScene;
use crate::{Camera, Reconstructor, Result};
use rayon::prelude::*;

/// How much of what lies behind a see-through object shows through one of its surfaces.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum SeeThrough {
    /// Coverage c (`alphaMode: BLEND`): the surface shines with c, lets 1 − c through.
    Coverage(f32),
    /// Transmittance per surface (transmissive glass): the surface shows its reflection and
    /// lets this through.
    Transmission(Vec3),
}

/// The pack ids of the pack's see-through objects and how they let light through:
/// glazing (a coverage), and with materials shown and reflections marched, transmissive
/// materials.
pub(crate) fn glazing_objects(rec: &Reconstructor) -> Vec<(u32, SeeThrough)> {
    rec.pack()
        .manifest()
        .objects
        .iter()
        .filter_map(|o| {
            if let Some(c) = o.coverage {
                return Some((o.id, SeeThrough::Coverage(c.clamp(0.0, 1.0))));
            }
            let m = &rec.materials().object(o.id)?.material;
            crate::specular::see_through_transmittance(&rec.settings, m)
                .map(|t| (o.id, SeeThrough::Transmission(t)))
        })
        .collect()
}

/// Renders a geometry-assisted frame of a pack with `glazing` (see the module doc); the
/// environment is already shown where nothing is.
pub(crate) fn render(
    rec: &Reconstructor,
    camera: &Camera,
    t: f32,
    glazing: &[(u32, SeeThrough)],
    report: &mut Report,
) -> Result<Frame> {
    let ids: Vec<u32> = glazing.iter().map(|g| g.0).collect();
    let shot = Shot::new(rec, camera, t, None);
    let mut behind = shading::render(shot, Layer::Without(&ids), report)?;
    background::apply(
        &rec.environment_at(t),
        camera,
        Coverage::FrameObjects,
        &mut behind,
    );
    let start = std::time::Instant::now();
    let mut front_report = Report::default();
    let front = shading::render(shot, Layer::Only(&ids), &mut front_report)?;
    let crossings = rec.proxy().map(|proxy| {
        let scene = ShadowScene::of_objects(proxy, |id| ids.contains(&id));
        let placed = scene.at(proxy, t);
        let basis = camera.basis();
        let w = camera.width as usize;
        (0..front.object.len())
            .into_par_iter()
            .map(|j| {
                if front.object[j] == 0 || front.depth[j] >= behind.depth[j] {
                    return 0;
                }
                let dir = basis.direction((j % w) as f32 + 0.5, (j / w) as f32 + 0.5);
                let tmax = behind.depth[j].min(FAR);
                placed.crossings(basis.position, dir, tmax) as u8
            })
            .collect::<Vec<u8>>()
    });
    let covered = composite(&mut behind, &front, glazing, crossings.as_deref());
    report
        .stage_ms
        .push(("glazing".into(), start.elapsed().as_secs_f64() * 1e3));
    for m in front_report.missing {
        if !report.missing.contains(&m) {
            report.missing.push(m);
        }
    }
    report.glazing_pixels = covered;
    Ok(behind)
}

/// How far (m) a pixel's ray is cast for glazing crossings when nothing lies behind.
const FAR: f32 = 1e4;

/// Composites the see-through layer `front` over `behind` in place where a see-through
/// object is nearer, with k the pixel's `crossings` (at least 1; 1 without them): glazing
/// as `(1 − (1 − c)^k) · front + (1 − c)^k · behind`, transmissive glass as
/// `front ⊙ (1 + T + … + T^(k−1)) + T^k ⊙ behind`; with the object's depth and id. Returns
/// how many pixels were covered.
fn composite(
    behind: &mut Frame,
    front: &Frame,
    glazing: &[(u32, SeeThrough)],
    crossings: Option<&[u8]>,
) -> usize {
    let kind = |o: u32| glazing.iter().find(|g| g.0 == o).map(|g| g.1);
    let mut covered = 0;
    for j in 0..behind.radiance.len() {
        let o = front.object[j];
        let Some(kind) = (o != 0).then(|| kind(o)).flatten() else {
            continue;
        };
        if front.depth[j] >= behind.depth[j] {
            continue;
        }
        let k = i32::from(crossings.map_or(1, |k| k[j].max(1)));
        let back: Vec3 = behind.radiance[j];
        behind.radiance[j] = match kind {
            SeeThrough::Coverage(c) => {
                let through = (1.0 - c).powi(k);
                front.radiance[j] * (1.0 - through) + back * through
            }
            SeeThrough::Transmission(t) => {
                // Each surface crossed reflects as the nearest does, seen through those
                // before it: front · (1 + T + … + T^(k−1)) + T^k · behind.
                let (mut sum, mut through) = (Vec3::ZERO, Vec3::ONE);
                for _ in 0..k {
                    sum += through;
                    through *= t;
                }
                front.radiance[j] * sum + through * back
            }
        };
        behind.depth[j] = front.depth[j];
        behind.object[j] = o;
        covered += 1;
    }
    covered
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(radiance: Vec<Vec3>, depth: Vec<f32>, object: Vec<u32>) -> Frame {
        Frame {
            width: radiance.len() as u32,
            height: 1,
            radiance,
            depth,
            object,
        }
    }

    #[test]
    fn nearer_glazing_is_blended_by_its_coverage_and_farther_glazing_is_hidden() {
        let mut behind = frame(
            vec![Vec3::splat(4.0), Vec3::splat(4.0), Vec3::splat(4.0)],
            vec![f32::INFINITY, 1.0, 5.0],
            vec![0, 1, 1],
        );
        let front = frame(
            vec![Vec3::splat(0.8), Vec3::splat(0.8), Vec3::ZERO],
            vec![3.0, 3.0, f32::INFINITY],
            vec![7, 7, 0],
        );
        let n = composite(
            &mut behind,
            &front,
            &[(7, SeeThrough::Coverage(0.25))],
            None,
        );
        assert_eq!(n, 1);
        // Sky behind the pane: 0.25 · 0.8 + 0.75 · 4.
        assert!((behind.radiance[0].x - 3.2).abs() < 1e-6);
        assert_eq!((behind.depth[0], behind.object[0]), (3.0, 7));
        // The wall in front of the pane hides it.
        assert_eq!(behind.radiance[1], Vec3::splat(4.0));
        assert_eq!(behind.object[1], 1);
        // No pane there.
        assert_eq!(behind.radiance[2], Vec3::splat(4.0));
    }

    #[test]
    fn a_ray_through_both_faces_of_a_pane_is_blended_twice() {
        let mut behind = frame(vec![Vec3::splat(4.0)], vec![f32::INFINITY], vec![0]);
        let front = frame(vec![Vec3::splat(0.8)], vec![3.0], vec![7]);
        composite(
            &mut behind,
            &front,
            &[(7, SeeThrough::Coverage(0.25))],
            Some(&[2]),
        );
        // (1 − 0.75²) · 0.8 + 0.75² · 4.
        assert!((behind.radiance[0].x - (0.4375 * 0.8 + 0.5625 * 4.0)).abs() < 1e-5);
    }

    #[test]
    fn glass_shows_its_reflection_per_surface_and_lets_the_rest_through() {
        let mut behind = frame(vec![Vec3::splat(4.0)], vec![f32::INFINITY], vec![0]);
        let front = frame(vec![Vec3::splat(0.1)], vec![3.0], vec![7]);
        let t = Vec3::splat(0.9);
        composite(
            &mut behind,
            &front,
            &[(7, SeeThrough::Transmission(t))],
            Some(&[2]),
        );
        // 0.1 · (1 + 0.9) + 0.81 · 4.
        assert!((behind.radiance[0].x - (0.19 + 3.24)).abs() < 1e-5);
        assert_eq!(behind.object[0], 7);
    }
}
