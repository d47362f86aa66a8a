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
//! Where the pack leaves its lamps to the runtime (pack 5.0), each pixel adds their direct
//! diffuse light with a shadow ray per lamp ([`crate::lamps::diffuse`]).
//!
//! Normal maps bend each pixel's shading normal ([`crate::material::bend_normal`]), which the
//! runtime sun, the lamps and the reflections use; the stored lighting stays at cube resolution (its
//! texels average the bent normals they cover).
//!
//! Emission is the material's at the pixel's UV (factor × emissive texture, mip by footprint)
//! where the pack leaves it to the runtime (pack 4.0); in older packs it is in the
//! non-diffuse cube, at cube resolution, except on marched surfaces.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use glam::Vec3;
use plenoptic_pack::{ChunkKind, VolumeSample};
use rayon::prelude::*;

use crate::Result;
use crate::brdf::{Bsdf, DELTA_ROUGHNESS};
use crate::frame::{Frame, Report};
use crate::geometry::{self, Layer, Pass, Shot};
use crate::lamps::{self, RuntimeLamp};
use crate::proxy::ProxyGeometry;
use crate::settings::{CubeFilter, Shading};
use crate::shadow::PlacedShadows;
use crate::specular::{self, Reflections};
use crate::sun::PlacedSun;
use crate::surface::{PixelGeometry, SharedRaster, SurfacePixel, Surfaces};

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
pub(crate) fn render(shot: Shot<'_>, layer: Layer<'_>, report: &mut Report) -> Result<Frame> {
    let rec = shot.rec;
    let shot = Layered { shot, layer };
    let materials = rec.materials();
    let proxy = match rec.proxy() {
        Some(p) if rec.settings.shading == Shading::Materials && !materials.is_empty() => p,
        _ => return shot.radiance_only(report),
    };
    let mut stages = Vec::new();
    let Some(passes) = shot.passes(proxy, report, &mut stages)? else {
        return shot.radiance_only(report);
    };
    let Passes {
        mut frame,
        lit,
        side,
    } = passes;
    let raster_ms = shot.shade(proxy, &mut frame, lit, report, &mut stages);
    report.fallback = side.fallback;
    for m in side.missing.into_iter().chain(materials.messages()) {
        if !report.missing.contains(&m) {
            report.missing.push(m);
        }
    }
    stages.push(("albedo_raster".to_string(), raster_ms));
    report.stage_ms = stages;
    Ok(frame)
}

/// A frame of the proxies of `layer`.
struct Layered<'a> {
    shot: Shot<'a>,
    layer: Layer<'a>,
}

/// The geometry passes' results that the materials shade.
struct Passes {
    /// The frame: the radiance pass's, or the lighting pass's where it is the frame.
    frame: Frame,
    lit: Lit,
    /// The lighting pass's report.
    side: Report,
}

/// The lighting pass's colours per pixel.
struct Lit {
    /// The lighting apart from the frame, or (`None`) in the frame itself.
    lighting: Option<Vec<Vec3>>,
    non_diffuse: Vec<Vec3>,
    /// The lighting pass's raster, where it made one with triangles and its frame is the
    /// frame.
    triangles: Option<(crate::raster::Projected, Vec<u32>)>,
}

/// Milliseconds since `start`.
fn ms(start: Instant) -> f64 {
    start.elapsed().as_secs_f64() * 1e3
}

impl Layered<'_> {
    /// The frame from the radiance alone.
    fn radiance_only(&self, report: &mut Report) -> Result<Frame> {
        let pass = Pass::radiance(self.layer, self.shot.rec.settings.cube_filter);
        geometry::render(self.shot, pass, report)
    }

    /// A pass of `channel` skipping `skip`. The lighting is smooth and at cube resolution:
    /// always filtered (seam-aware bilinear, restricted to texels of the same object and
    /// distance), whatever the radiance uses.
    fn pass<'b>(&'b self, channel: Channel, skip: &'b [u32]) -> Pass<'b> {
        Pass {
            layer: self.layer,
            channel,
            skip,
            second: None,
            environment: None,
            sparse: false,
            filter: if channel == Channel::Radiance {
                self.shot.rec.settings.cube_filter
            } else {
                CubeFilter::Bilinear
            },
        }
    }

    /// The lighting and the non-diffuse radiance in one pass (the same lookups, weights and
    /// fallbacks for both), and the radiance pass for the objects without a material unless
    /// the lighting pass's frame serves. A pack v2 always has them; a damaged one is shown
    /// from its radiance instead (`None`).
    fn passes(
        &self,
        proxy: &ProxyGeometry,
        report: &mut Report,
        stages: &mut Vec<(String, f64)>,
    ) -> Result<Option<Passes>> {
        let rec = self.shot.rec;
        let materials = rec.materials();
        let (lit, unlit): (Vec<u32>, Vec<u32>) = proxy
            .object_ids()
            .iter()
            .partition(|&&o| materials.object(o).is_some());
        let mut side = Report::default();
        let start = Instant::now();
        // Where every object has a material, the radiance pass would only show the
        // environment: this pass looks it up instead, in the radiance cube as that pass would.
        let all_lit = unlit.is_empty();
        let fused = Pass {
            second: Some(Channel::NonDiffuse),
            environment: all_lit.then_some((Channel::Radiance, rec.settings.cube_filter)),
            sparse: rec.settings.sparse_lighting,
            ..self.pass(Channel::Lighting, &unlit)
        };
        let both = geometry::render_pair(self.shot, fused, &mut side);
        stages.push(("lighting_pass".to_string(), ms(start)));
        let pair = match both {
            Ok(pair) => pair,
            Err(e) => {
                report.missing.push(format!("materials not applied: {e}"));
                return Ok(None);
            }
        };
        report.interpolated_pixels += pair.interpolated;
        let start = Instant::now();
        // Where every object has a material the lighting pass's frame becomes the frame, its
        // pixels shaded in place (each read before it is written), the environment where
        // nothing is and black on objects left unshaded, as the radiance pass would leave
        // them.
        let (frame, lighting, triangles) = if all_lit && pair.environment {
            report.base_views = side.base_views.clone();
            (pair.frame, None, pair.triangles)
        } else {
            let radiance = self.pass(Channel::Radiance, &lit);
            let frame = geometry::render(self.shot, radiance, report)?;
            // The same proxies rasterized the same way: the same objects per pixel.
            debug_assert_eq!(frame.object, pair.frame.object);
            (frame, Some(pair.frame.radiance), None)
        };
        stages.push(("radiance_pass".to_string(), ms(start)));
        let lit = Lit {
            lighting,
            non_diffuse: pair.second,
            triangles,
        };
        Ok(Some(Passes { frame, lit, side }))
    }

    /// Shades `frame` with the materials: each pixel as soon as its surface is known, those
    /// whose reflection is marched after the reflections' set-up, which only a frame that has
    /// them pays for. Returns the surfaces' raster time, ms.
    fn shade(
        &self,
        proxy: &ProxyGeometry,
        frame: &mut Frame,
        lit: Lit,
        report: &mut Report,
        stages: &mut Vec<(String, f64)>,
    ) -> f64 {
        let Shot { rec, camera, t, .. } = self.shot;
        let start = Instant::now();
        let sun = rec.runtime_sun().zip(rec.proxy_rays()).map(|(s, shadows)| {
            let rays = (rec.settings.sun_shadow_rays, rec.settings.sun_edge_rays);
            s.at(shadows, proxy, t, rays).scaled(rec.relight.sun)
        });
        let lamps = rec.lamps_lit_at_runtime();
        let lamp_shadows = rec
            .proxy_rays()
            .filter(|_| !lamps.is_empty())
            .map(|shadows| shadows.at(proxy, t));
        let glossy = specular::glossy_allowed(rec);
        let with_footprint = sun.is_some();
        let surfaces = Surfaces::new(
            rec,
            proxy,
            rec.materials(),
            camera,
            t,
            self.layer,
            with_footprint,
            glossy,
            // The lighting pass's raster where it made one with triangles and its frame is
            // this one: the same proxies and pixels.
            lit.triangles.map(|(projected, prim)| SharedRaster {
                projected,
                prim,
                object: &frame.object,
                depth: &frame.depth,
            }),
        );
        let shader = Shader {
            sun: sun.as_ref(),
            lamps: &lamps,
            lamp_shadows: lamp_shadows.as_ref(),
            runtime_emission: rec.pack().runtime_emission(),
            non_diffuse: &lit.non_diffuse,
            marched_pixels: AtomicUsize::new(0),
            unanswered: AtomicUsize::new(0),
        };
        let lighting = lit.lighting.as_deref();
        let object = &frame.object;
        let marched: Vec<(usize, SurfacePixel)> = frame
            .radiance
            .par_iter_mut()
            .enumerate()
            .filter_map(|(j, c)| {
                let light = lighting.map_or(*c, |l| l[j]);
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
                *c = shader.pixel(j, &px, light, None);
                None
            })
            .collect();
        stages.push(("albedo".to_string(), ms(start)));
        let start = Instant::now();
        let reflections = (!marched.is_empty())
            .then(|| Reflections::new(rec, camera, t, sun.as_ref(), &mut report.missing));
        let reflected: Vec<(usize, Vec3)> = marched
            .par_iter()
            .map(|(j, px)| {
                let light = lighting.map_or(frame.radiance[*j], |l| l[*j]);
                (*j, shader.pixel(*j, px, light, reflections.as_ref()))
            })
            .collect();
        for (j, c) in reflected {
            frame.radiance[j] = c;
        }
        report.reflections = (
            shader.marched_pixels.into_inner(),
            shader.unanswered.into_inner(),
        );
        stages.push(("reflections".to_string(), ms(start)));
        surfaces.raster_ms
    }
}

/// What shading a pixel needs beside its surface and its lighting.
struct Shader<'a> {
    sun: Option<&'a PlacedSun<'a>>,
    /// The lamps whose direct diffuse light is added per pixel, and the proxies their shadow
    /// rays meet ([`crate::lamps::diffuse`]).
    lamps: &'a [RuntimeLamp],
    lamp_shadows: Option<&'a PlacedShadows<'a>>,
    /// Whether the pack leaves the emission to the runtime (pack 4).
    runtime_emission: bool,
    non_diffuse: &'a [Vec3],
    /// Pixels whose reflection was marched, and those of them no view answered.
    marched_pixels: AtomicUsize,
    unanswered: AtomicUsize,
}

impl Shader<'_> {
    /// Pixel `j` of surface `px` under `light`; its reflection marched through `reflections`
    /// where it is marched.
    #[inline]
    fn pixel(
        &self,
        j: usize,
        px: &SurfacePixel,
        light: Vec3,
        reflections: Option<&Reflections>,
    ) -> Vec3 {
        // The BSDF only where the sun or a reflection needs it (there the pixel has its
        // geometry).
        let bsdf = px.geometry.as_ref().map(|g| {
            let front = g.view.dot(g.ng) < 0.0;
            (g, Bsdf::new(px.material, g.ng, g.ns, -g.view, front), front)
        });
        let marching = reflections.filter(|_| px.marched).zip(bsdf.as_ref());
        let specular =
            marching.and_then(|(r, (g, bsdf, front))| self.reflected(j, px, r, g, bsdf, *front));
        // Glass in the see-through layer that no view answers shows no reflection (its
        // baked radiance holds what it lets through, which is composited apart).
        let baked = if px.see_through {
            Vec3::ZERO
        } else if self.runtime_emission {
            // Pack 4: the emission at the pixel's UV, the specular part from the cubes.
            self.non_diffuse[j] + px.emission
        } else {
            self.non_diffuse[j]
        };
        let mut c = px.material.albedo() * light + specular.unwrap_or(baked);
        if let Some((g, bsdf, _)) = &bsdf {
            if let Some(sun) = self.sun {
                c += sun.radiance(g.position, g.ng, g.footprint, bsdf, j as u32);
            }
            c += lamps::diffuse(self.lamps, g.position, g.ng, bsdf, self.lamp_shadows);
        }
        c
    }

    /// The non-diffuse radiance of marched pixel `j`: its emission, the reflected ray's
    /// radiance marched through `r` (`None` where no view answers), and a glossy surface's
    /// lamps' highlights, which the march cannot see.
    #[inline]
    fn reflected(
        &self,
        j: usize,
        px: &SurfacePixel,
        r: &Reflections,
        g: &PixelGeometry,
        bsdf: &Bsdf,
        front: bool,
    ) -> Option<Vec3> {
        let n = bsdf.normal();
        let cos_o = -g.view.dot(n);
        let dir = (g.view + n * (2.0 * cos_o)).normalize_or(n);
        let alpha = px.material.roughness * px.material.roughness;
        let eta = if front {
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
        self.marched_pixels.fetch_add(1, Ordering::Relaxed);
        if incoming.is_none() {
            self.unanswered.fetch_add(1, Ordering::Relaxed);
        }
        let highlights = if delta {
            Vec3::ZERO
        } else {
            r.highlights(g.position, g.ng, bsdf)
        };
        Some(px.emission + incoming? + highlights)
    }
}
