//! Geometry-assisted frames from pack v2 (docs/architecture.md, "Pack v2"; thesis ch. 8:
//! separating illumination quality from image quality): a pixel on an object with a material
//! is
//!
//! `albedo(uv) · lighting + emission(uv) + non-diffuse`
//!
//! where the *lighting* and the *non-diffuse radiance* (the specular part as the base views
//! saw it) are looked up in the range images exactly as the radiance was
//! (motion-compensated, view- and time-blended, with the volume and hole-fill fallbacks of
//! [`crate::geometry`]), and the *albedo* comes from the object's material at the pixel's own
//! UV, with the texture's mip chosen by the pixel's footprint ([`crate::material`]), as does
//! the *emission*. Texture detail is therefore at screen resolution whatever the cube size;
//! only the lighting is at cube resolution.
//!
//! The lighting and non-diffuse lookups are always seam-aware bilinear
//! ([`CubeFilter::Bilinear`]): at cube resolution, nearest texels show as blocks.
//!
//! Two geometry passes run: radiance for objects without a material (and for the environment
//! where nothing is), and one for the others that looks up the lighting and the non-diffuse
//! radiance together (the same lookups, weights and fallbacks for both channels), each
//! skipping the objects the other shades. Where every object has a material the second pass
//! also shows the environment (from the radiance cubes) and the first does not run. The
//! surface seen through each pixel ([`crate::surface`]) comes from a raster pass that gives
//! each pixel its triangle, from which the UV is interpolated (barycentric coordinates of the
//! pixel's point on the placed triangle) and the footprint computed (the square root of the
//! surface area the pixel covers, `distance · pixel angle · cos^1.5 α / √|cos θ|` for a pixel
//! whose ray is at α to the axis and meets the surface at θ, times the triangle's UV-per-metre
//! scale: the `√|det ∂uv/∂(x, y)|` a GPU's derivatives give). Each pixel is shaded as soon as
//! its surface is known; those whose reflection is marched wait for the reflections' set-up.
//!
//! Mirrors and glossy metals reflect for the actual camera ([`crate::specular`]): their
//! non-diffuse radiance is replaced by their emission at the pixel's UV plus the reflected
//! ray's radiance, marched through the base views' distance cubes.
//!
//! Normal maps bend each pixel's shading normal ([`crate::material::bend_normal`]), which the
//! runtime sun and the reflections use; the stored lighting stays at cube resolution (its
//! texels average the bent normals they cover).
//!
//! Emission is the material's at the pixel's UV (factor × emissive texture, mip by footprint)
//! where the pack leaves it to the runtime (pack 4.0); in older packs it is in the
//! non-diffuse cube, at cube resolution, except on marched surfaces.

use std::sync::atomic::{AtomicUsize, Ordering};

use glam::Vec3;
use plenoptic_pack::{ChunkKind, VolumeSample};
use rayon::prelude::*;

use crate::brdf::{Bsdf, DELTA_ROUGHNESS};
use crate::camera::Camera;
use crate::frame::{Frame, Report};
use crate::geometry::{self, Layer, Pass};
use crate::proxy::GeometryMask;
use crate::settings::{CubeFilter, Shading};
use crate::specular::{self, Reflections};
use crate::surface::{SharedRaster, SurfacePixel, Surfaces};
use crate::{Reconstructor, Result};

/// Which colour a geometry-assisted pass looks up.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) enum Channel {
    /// Outgoing radiance (version 1's only colour; image and volume modes).
    Radiance,
    /// Diffuse lighting: what the diffuse albedo multiplies.
    Lighting,
    /// Emission plus the specular part.
    NonDiffuse,
}

impl Channel {
    /// The cube chunk kind holding the channel.
    pub fn kind(self) -> ChunkKind {
        match self {
            Channel::Radiance => ChunkKind::RadianceCube,
            Channel::Lighting => ChunkKind::LightingCube,
            Channel::NonDiffuse => ChunkKind::NonDiffuseCube,
        }
    }

    /// The channel's name in messages.
    pub fn name(self) -> &'static str {
        match self {
            Channel::Radiance => "radiance",
            Channel::Lighting => "lighting",
            Channel::NonDiffuse => "non-diffuse",
        }
    }

    /// The channel's value in a temporal-volume sample.
    pub fn of_sample(self, s: &VolumeSample) -> Vec3 {
        match self {
            Channel::Radiance => s.radiance,
            Channel::Lighting => s.lighting,
            Channel::NonDiffuse => s.non_diffuse,
        }
    }
}

/// Renders a geometry-assisted frame of the proxies of `layer`: with materials as the module
/// doc says when the settings ask for it and the pack has materials, else from the radiance.
pub(crate) fn render(
    rec: &Reconstructor,
    camera: &Camera,
    t: f32,
    mask: Option<&GeometryMask>,
    layer: Layer<'_>,
    report: &mut Report,
) -> Result<Frame> {
    let materials = rec.materials();
    let radiance_only = |report: &mut Report| {
        let pass = Pass::radiance(layer, rec.settings.cube_filter);
        geometry::render(rec, camera, t, mask, pass, report)
    };
    let proxy = match rec.proxy() {
        Some(p) if rec.settings.shading == Shading::Materials && !materials.is_empty() => p,
        _ => return radiance_only(report),
    };
    let ids = proxy.object_ids();
    let (lit, unlit): (Vec<u32>, Vec<u32>) =
        ids.iter().partition(|&&o| materials.object(o).is_some());
    // The lighting is smooth and at cube resolution: always filtered (seam-aware bilinear,
    // restricted to texels of the same object and distance), whatever the radiance uses.
    let pass = |channel, skip| Pass {
        layer,
        channel,
        skip,
        second: None,
        environment: None,
        sparse: false,
        filter: if channel == Channel::Radiance {
            rec.settings.cube_filter
        } else {
            CubeFilter::Bilinear
        },
    };
    // The lighting and the non-diffuse radiance in one pass (the same lookups, weights and
    // fallbacks for both). A pack v2 always has them; a damaged one is shown from its
    // radiance instead.
    let mut stages = Vec::new();
    let mut side = Report::default();
    let start = std::time::Instant::now();
    // Where every object has a material, the radiance pass would only show the environment:
    // this pass looks it up instead, in the radiance cube as that pass would.
    let all_lit = unlit.is_empty();
    let fused = Pass {
        second: Some(Channel::NonDiffuse),
        environment: all_lit.then_some((Channel::Radiance, rec.settings.cube_filter)),
        sparse: rec.settings.sparse_lighting,
        ..pass(Channel::Lighting, &unlit)
    };
    let both = geometry::render_pair(rec, camera, t, mask, fused, &mut side);
    stages.push((
        "lighting_pass".to_string(),
        start.elapsed().as_secs_f64() * 1e3,
    ));
    let (lighting, non_diffuse, environment, triangles) = match both {
        Ok(pair) => {
            report.interpolated_pixels += pair.interpolated;
            (pair.frame, pair.second, pair.environment, pair.triangles)
        }
        Err(e) => {
            report.missing.push(format!("materials not applied: {e}"));
            return radiance_only(report);
        }
    };
    let start = std::time::Instant::now();
    // The lighting per pixel apart from the frame, or (`None`) in the frame itself: where
    // every object has a material the lighting pass's frame becomes the frame, its pixels
    // shaded in place (each read before it is written), the environment where nothing is and
    // black on objects left unshaded, as the radiance pass would leave them.
    let (mut frame, lighting, triangles) = if all_lit && environment {
        report.base_views = side.base_views.clone();
        (lighting, None, triangles)
    } else {
        let frame = geometry::render(rec, camera, t, mask, pass(Channel::Radiance, &lit), report)?;
        // The same proxies rasterized the same way: the same objects per pixel.
        debug_assert_eq!(frame.object, lighting.object);
        (frame, Some(lighting.radiance), None)
    };
    stages.push((
        "radiance_pass".to_string(),
        start.elapsed().as_secs_f64() * 1e3,
    ));
    let mut timed = |name: &str, start: std::time::Instant| {
        stages.push((name.to_string(), start.elapsed().as_secs_f64() * 1e3));
    };
    let start = std::time::Instant::now();
    let sun = rec.runtime_sun().zip(rec.proxy_rays()).map(|(s, shadows)| {
        let rays = (rec.settings.sun_shadow_rays, rec.settings.sun_edge_rays);
        s.at(shadows, proxy, t, rays)
    });
    let glossy = specular::glossy_allowed(rec);
    let runtime_emission = rec.pack().runtime_emission();
    let with_footprint = sun.is_some();
    let surfaces = Surfaces::new(
        rec,
        proxy,
        materials,
        camera,
        t,
        layer,
        with_footprint,
        glossy,
        // The lighting pass's raster where it made one with triangles and its frame is this
        // one: the same proxies and pixels.
        triangles.map(|(projected, prim)| SharedRaster {
            projected,
            prim,
            object: &frame.object,
            depth: &frame.depth,
        }),
    );
    let (marched_pixels, unanswered) = (AtomicUsize::new(0), AtomicUsize::new(0));
    // Pixel `j` of surface `px` under `light`; its reflection marched through `reflections`
    // where it is marched.
    let shade = |j: usize, px: &SurfacePixel, light: Vec3, reflections: Option<&Reflections>| {
        // The BSDF only where the sun or a reflection needs it (there the pixel has its
        // geometry).
        let bsdf = px.geometry.as_ref().map(|g| {
            let front = g.view.dot(g.ng) < 0.0;
            (g, Bsdf::new(px.material, g.ng, g.ns, -g.view, front), front)
        });
        let marching = reflections.filter(|_| px.marched).zip(bsdf.as_ref());
        let specular = marching.and_then(|(r, (g, bsdf, front))| {
            let n = bsdf.normal();
            let cos_o = -g.view.dot(n);
            let dir = (g.view + n * (2.0 * cos_o)).normalize_or(n);
            let alpha = px.material.roughness * px.material.roughness;
            let eta = if *front {
                px.material.ior
            } else {
                1.0 / px.material.ior
            };
            let delta = px.material.roughness < DELTA_ROUGHNESS;
            let incoming = if delta {
                r.incoming(g.position, dir, 0.0)
                    .map(|l| specular::reflectance(&px.material, cos_o, eta) * l)
            } else {
                // A per-pixel turn of the lobe's directions (golden-ratio sequence).
                let turn = (j as f32 * 0.618_034).fract();
                r.lobe(g.position, bsdf, alpha, turn)
            };
            marched_pixels.fetch_add(1, Ordering::Relaxed);
            if incoming.is_none() {
                unanswered.fetch_add(1, Ordering::Relaxed);
            }
            // A glossy surface's lamps' highlights, which the march cannot see.
            let highlights = if delta {
                Vec3::ZERO
            } else {
                r.highlights(g.position, g.ng, bsdf)
            };
            Some(px.emission + incoming? + highlights)
        });
        // Glass in the see-through layer that no view answers shows no reflection (its
        // baked radiance holds what it lets through, which is composited apart).
        let baked = if px.see_through {
            Vec3::ZERO
        } else if runtime_emission {
            // Pack 4: the emission at the pixel's UV, the specular part from the cubes.
            non_diffuse[j] + px.emission
        } else {
            non_diffuse[j]
        };
        let mut c = px.material.albedo() * light + specular.unwrap_or(baked);
        if let (Some(sun), Some((g, bsdf, _))) = (&sun, &bsdf) {
            c += sun.radiance(g.position, g.ng, g.footprint, bsdf, j as u32);
        }
        c
    };
    // Each pixel shaded as soon as its surface is known; those whose reflection is marched
    // wait for the reflections' set-up, which only a frame that has them pays for.
    let object = &frame.object;
    let marched: Vec<(usize, SurfacePixel)> = frame
        .radiance
        .par_iter_mut()
        .enumerate()
        .filter_map(|(j, c)| {
            let light = lighting.as_ref().map_or(*c, |l| l[j]);
            let px = surfaces.pixel(j).filter(|px| px.object == object[j]);
            let Some(px) = px else {
                if lighting.is_none() && object[j] != 0 {
                    *c = Vec3::ZERO;
                }
                return None;
            };
            if px.marched {
                return Some((j, px));
            }
            *c = shade(j, &px, light, None);
            None
        })
        .collect();
    timed("albedo", start);
    let start = std::time::Instant::now();
    let reflections = (!marched.is_empty())
        .then(|| Reflections::new(rec, camera, t, sun.as_ref(), &mut report.missing));
    let reflected: Vec<(usize, Vec3)> = marched
        .par_iter()
        .map(|(j, px)| {
            let light = lighting.as_ref().map_or(frame.radiance[*j], |l| l[*j]);
            (*j, shade(*j, px, light, reflections.as_ref()))
        })
        .collect();
    for (j, c) in reflected {
        frame.radiance[j] = c;
    }
    report.reflections = (marched_pixels.into_inner(), unanswered.into_inner());
    timed("reflections", start);
    report.fallback = side.fallback;
    for m in side.missing.into_iter().chain(materials.messages()) {
        if !report.missing.contains(&m) {
            report.missing.push(m);
        }
    }
    stages.push(("albedo_raster".to_string(), surfaces.raster_ms));
    report.stage_ms = stages;
    Ok(frame)
}
