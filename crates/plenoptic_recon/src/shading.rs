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
//! radiance together (the same lookups, weights and fallbacks for both channels; two passes
//! before, one per channel), each skipping the objects the other shades. A separate raster pass gives each pixel its triangle, from
//! which the UV is interpolated (barycentric coordinates of the pixel's point on the placed
//! triangle) and the footprint computed (the square root of the surface area the pixel
//! covers, `distance · pixel angle · cos^1.5 α / √|cos θ|` for a pixel whose ray is at α
//! to the axis and meets the surface at θ, times the triangle's UV-per-metre scale: the
//! `√|det ∂uv/∂(x, y)|` a GPU's derivatives give).
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

use glam::{Vec2, Vec3};
use plenoptic_pack::{ChunkKind, VolumeSample};
use rayon::prelude::*;

use crate::brdf::{Bsdf, DELTA_ROUGHNESS, SurfaceMaterial};
use crate::camera::Camera;
use crate::frame::{Frame, Report};
use crate::geometry::{self, Layer, Pass};
use crate::material::Materials;
use crate::proxy::GeometryMask;
use crate::settings::{CubeFilter, Shading};
use crate::specular::{self, Reflections};
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
        ..pass(Channel::Lighting, &unlit)
    };
    let both = geometry::render_pair(rec, camera, t, mask, fused, &mut side);
    stages.push((
        "lighting_pass".to_string(),
        start.elapsed().as_secs_f64() * 1e3,
    ));
    let (lighting, non_diffuse, environment) = match both {
        Ok(pair) => (pair.frame, pair.second, pair.environment),
        Err(e) => {
            report.missing.push(format!("materials not applied: {e}"));
            return radiance_only(report);
        }
    };
    let start = std::time::Instant::now();
    let mut frame = if all_lit && environment {
        // What the radiance pass gives when it skips every object: the environment where
        // nothing is, black elsewhere (the compose below shades the objects).
        report.base_views = side.base_views.clone();
        Frame {
            width: lighting.width,
            height: lighting.height,
            radiance: (lighting.radiance.par_iter().zip(&lighting.object))
                .map(|(&c, &o)| if o == 0 { c } else { Vec3::ZERO })
                .collect(),
            depth: lighting.depth.clone(),
            object: lighting.object.clone(),
        }
    } else {
        geometry::render(rec, camera, t, mask, pass(Channel::Radiance, &lit), report)?
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
    let (surface, raster_ms) =
        surface_image(rec, materials, camera, t, layer, sun.is_some(), glossy);
    timed("albedo", start);
    let start = std::time::Instant::now();
    let reflections = if surface.iter().flatten().any(|px| px.marched) {
        Some(Reflections::new(
            rec,
            camera.position,
            t,
            &mut report.missing,
        ))
    } else {
        None
    };
    let (marched_pixels, unanswered) = (AtomicUsize::new(0), AtomicUsize::new(0));
    frame
        .radiance
        .par_iter_mut()
        .enumerate()
        .for_each(|(j, c)| {
            let Some(px) = &surface[j] else { return };
            if lighting.object[j] != px.object {
                return;
            }
            // The BSDF only where the sun or a reflection needs it.
            let front = px.view.dot(px.ng) < 0.0;
            let bsdf = (sun.is_some() || px.marched)
                .then(|| Bsdf::new(px.material, px.ng, px.ns, -px.view, front));
            let specular = reflections
                .as_ref()
                .zip(bsdf.as_ref())
                .filter(|_| px.marched)
                .and_then(|(r, bsdf)| {
                    let n = bsdf.normal();
                    let cos_o = -px.view.dot(n);
                    let dir = (px.view + n * (2.0 * cos_o)).normalize_or(n);
                    let eta = if front {
                        px.material.ior
                    } else {
                        1.0 / px.material.ior
                    };
                    let alpha = px.material.roughness * px.material.roughness;
                    let incoming = if px.material.roughness < DELTA_ROUGHNESS {
                        r.incoming(px.position, dir, 0.0)
                    } else {
                        // A per-pixel turn of the lobe's directions (golden-ratio sequence).
                        let turn = (j as f32 * 0.618_034).fract();
                        r.lobe(px.position, n, -px.view, alpha, turn)
                    };
                    marched_pixels.fetch_add(1, Ordering::Relaxed);
                    if incoming.is_none() {
                        unanswered.fetch_add(1, Ordering::Relaxed);
                    }
                    Some(px.emission + specular::reflectance(&px.material, cos_o, eta) * incoming?)
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
            *c = px.material.albedo() * lighting.radiance[j] + specular.unwrap_or(baked);
            if let (Some(sun), Some(bsdf)) = (&sun, &bsdf) {
                *c += sun.radiance(px.position, px.ng, px.footprint, bsdf, j as u32);
            }
        });
    report.reflections = (marched_pixels.into_inner(), unanswered.into_inner());
    timed(
        if sun.is_some() {
            "compose_sun"
        } else {
            "compose"
        },
        start,
    );
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

/// What the compose stage needs of the surface seen through one pixel.
struct SurfacePixel {
    object: u32,
    material: SurfaceMaterial,
    /// The point on the proxy (world).
    position: Vec3,
    /// Geometric normal as the mesh winds it (world, unit).
    ng: Vec3,
    /// Shading normal on `ng`'s side: the proxy's vertex normals interpolated, else `ng`.
    ns: Vec3,
    /// Unit direction of the pixel's ray.
    view: Vec3,
    /// How far the point moves on the surface's plane for a step of one pixel in x and in y
    /// (the footprint the runtime sun's shadow rays spread over).
    footprint: (Vec3, Vec3),
    /// Whether its specular part is marched for the camera ([`specular::Specular::marches`]).
    marched: bool,
    /// Transmissive glass drawn in the see-through layer: only its reflection is shown.
    see_through: bool,
    /// Emitted radiance at the pixel's UV where the pack leaves the emission to the runtime
    /// (pack 4) or the specular part is marched (which replaces the baked non-diffuse
    /// radiance, holding the emission before pack 4); else zero.
    emission: Vec3,
}

/// Per pixel, the surface of an object with a material seen there (`None` where there is
/// none), its footprint only `with_footprint` (the runtime sun's shadow rays need it), its
/// emission where the pack leaves it to the runtime or its specular part is marched
/// (`glossy`: [`specular::glossy_allowed`]); and
/// the milliseconds its raster pass took.
fn surface_image(
    rec: &Reconstructor,
    materials: &Materials,
    camera: &Camera,
    t: f32,
    layer: Layer<'_>,
    with_footprint: bool,
    glossy: bool,
) -> (Vec<Option<SurfacePixel>>, f64) {
    let n = camera.pixel_count();
    let Some(proxy) = rec.proxy() else {
        return ((0..n).map(|_| None).collect(), 0.0);
    };
    let start = std::time::Instant::now();
    let runtime_emission = rec.pack().runtime_emission();
    // Glazing (coverage) is composited as such even where its material transmits
    // (crate::glazing); only other transmissive glass shows its reflection alone.
    let glazing: Vec<u32> = match layer {
        Layer::Only(_) => rec
            .pack()
            .manifest()
            .objects
            .iter()
            .filter(|o| o.coverage.is_some())
            .map(|o| o.id)
            .collect(),
        _ => Vec::new(),
    };
    let mut placed = proxy.placed_meshes(t);
    match layer {
        Layer::All => {}
        Layer::Without(ids) => placed.retain(|o| !ids.contains(&o.0)),
        Layer::Only(ids) => placed.retain(|o| ids.contains(&o.0)),
    }
    let projected = crate::raster::project(camera, &placed);
    let (object, prim, depth) = crate::raster::rasterize_sources(camera, &projected);
    let raster_ms = start.elapsed().as_secs_f64() * 1e3;
    // Per projected triangle, once: its placed corners, normals, UVs and UV-per-metre scale.
    let triangles: Vec<Option<SurfaceTriangle<'_>>> = projected
        .sources
        .par_iter()
        .map(|&(oi, ti)| {
            let (id, xf, mesh) = placed.get(oi as usize)?;
            let m = materials.object(*id)?;
            let tri = mesh.triangles.get(ti as usize)?;
            let v = tri.map(|i| xf.transform_point3(mesh.positions[i as usize]));
            let uv = match tri.map(|i| m.uvs.get(i as usize).copied()) {
                [Some(a), Some(b), Some(c)] => Some([a, b, c]),
                _ => None,
            };
            let normals = (mesh.normals.len() == mesh.positions.len()).then(|| {
                let to_world = xf.matrix3.inverse().transpose();
                tri.map(|i| to_world * mesh.normals[i as usize])
            });
            // Tangents only where a normal map needs them (placed as the tracer places them).
            let tangents = (m.material.normal_texture.is_some()
                && m.tangents.len() == mesh.positions.len())
            .then(|| {
                let t = tri.map(|i| m.tangents[i as usize]);
                // A mirroring placement flips the bitangent's handedness, as in the tracer.
                let sign = t[0].w * xf.matrix3.determinant().signum();
                (t.map(|t| xf.matrix3 * t.truncate()), sign)
            });
            let mut t = SurfaceTriangle::new(*id, m, v, uv)?;
            if xf.matrix3.determinant() < 0.0 {
                // The tracer's geometric normal is the object-space one carried by the normal
                // matrix, which a mirroring transform turns against the placed winding.
                t.normal = -t.normal;
            }
            t.normals = normals;
            t.tangents = tangents;
            Some(t)
        })
        .collect();
    let basis = camera.basis();
    let w = camera.width as usize;
    // The angle one pixel subtends at the image centre.
    let pixel_angle = 2.0 * basis.tan_y / basis.height;
    let surface = (0..n)
        .into_par_iter()
        .map(|j| {
            let t = triangles.get(prim[j] as usize)?.as_ref()?;
            if t.object != object[j] {
                return None;
            }
            let dir = basis.direction((j % w) as f32 + 0.5, (j / w) as f32 + 0.5);
            let view = dir.normalize_or(basis.forward);
            // The pixel's ray met on the triangle's plane: the raster's interpolated depth is
            // off by ~10⁻⁴ of the distance, enough to put the point under the surface for a
            // shadow ray.
            let den = dir.dot(t.normal);
            let along = if den.abs() > 1e-4 {
                (t.origin - basis.position).dot(t.normal) / den
            } else {
                depth[j]
            };
            let position = basis.position + dir * along;
            let b = t.barycentric(position);
            let (uv, uv_footprint) = match &t.uv {
                Some(uv) => {
                    let cos = t.normal.dot(dir).abs().max(0.05);
                    // A pixel off the axis subtends cos³α of the central pixel's solid angle.
                    let c = dir.dot(basis.forward).max(0.0);
                    let off_axis = c * c.sqrt();
                    (
                        uv[0] * b.x + uv[1] * b.y + uv[2] * b.z,
                        t.scale * along * pixel_angle * off_axis / cos.sqrt(),
                    )
                }
                None => (Vec2::ZERO, f32::INFINITY),
            };
            let ng = t.normal;
            let mut ns = t.normals.map_or(ng, |[a, c, d]| {
                (a * b.x + c * b.y + d * b.z).normalize_or(ng)
            });
            if let Some(([ta, tb, tc], sign)) = t.tangents
                && let Some(local) =
                    materials.normal(rec.pack(), &t.material.material, uv, uv_footprint)
            {
                let tangent = ta * b.x + tb * b.y + tc * b.z;
                ns = crate::material::bend_normal(ns, tangent, sign, local);
            }
            if ns.dot(ng) < 0.0 {
                ns = -ns;
            }
            // The neighbouring pixels' rays met on the triangle's plane; at most 4 pixels'
            // worth of depth away, so that a grazing plane does not smear the footprint.
            let (x, y) = ((j % w) as f32 + 0.5, (j / w) as f32 + 0.5);
            let limit = 4.0 * along * pixel_angle;
            let step = |d: Vec3| {
                let den = d.dot(ng);
                let s = if den.abs() > 1e-6 {
                    (position - basis.position).dot(ng) / den
                } else {
                    along
                };
                (basis.position + d * s - position).clamp_length_max(limit)
            };
            let footprint = if with_footprint {
                (
                    step(basis.direction(x + 1.0, y)),
                    step(basis.direction(x, y + 1.0)),
                )
            } else {
                (Vec3::ZERO, Vec3::ZERO)
            };
            let material = materials.surface(rec.pack(), &t.material.material, uv, uv_footprint);
            // In the see-through layer, transmissive glass shows its reflection alone: what
            // it lets through is composited from the layer behind (crate::glazing).
            let see_through = matches!(layer, Layer::Only(_))
                && material.transmission > 0.0
                && !glazing.contains(&t.object);
            let reflection_of = SurfaceMaterial {
                transmission: 0.0,
                ..material
            };
            let marched = rec.settings.specular.marches(
                if see_through {
                    &reflection_of
                } else {
                    &material
                },
                glossy || see_through,
            );
            // A single-sided emitter emits from its front only, as the tracer has it.
            let emits = t.material.material.double_sided || view.dot(ng) < 0.0;
            let emission = if emits && (marched || runtime_emission) {
                materials.emission(rec.pack(), &t.material.material, uv, uv_footprint)
            } else {
                Vec3::ZERO
            };
            Some(SurfacePixel {
                object: t.object,
                material,
                marched,
                see_through,
                emission,
                position,
                ng,
                ns,
                view,
                footprint,
            })
        })
        .collect();
    (surface, raster_ms)
}

/// A placed proxy triangle of an object with a material, ready for per-pixel UVs.
struct SurfaceTriangle<'m> {
    object: u32,
    material: &'m crate::material::ObjectMaterial,
    origin: Vec3,
    e0: Vec3,
    e1: Vec3,
    /// The inverse Gram matrix of (e0, e1): barycentrics from dot products.
    inv: [f32; 3],
    normal: Vec3,
    /// Vertex normals placed in the world, when the proxy has them.
    normals: Option<[Vec3; 3]>,
    /// Vertex tangents placed in the world and the bitangent's sign, when the material has a
    /// normal map and the proxy tangents.
    tangents: Option<([Vec3; 3], f32)>,
    uv: Option<[Vec2; 3]>,
    /// √(UV area / world area).
    scale: f32,
}

impl<'m> SurfaceTriangle<'m> {
    fn new(
        object: u32,
        material: &'m crate::material::ObjectMaterial,
        v: [Vec3; 3],
        uv: Option<[Vec2; 3]>,
    ) -> Option<Self> {
        let (e0, e1) = (v[1] - v[0], v[2] - v[0]);
        let (d00, d01, d11) = (e0.dot(e0), e0.dot(e1), e1.dot(e1));
        let den = d00 * d11 - d01 * d01;
        if den.is_nan() || den.abs() <= 1e-20 {
            return None;
        }
        let world = e0.cross(e1);
        let scale = uv.map_or(0.0, |[a, b, c]| {
            ((b - a).perp_dot(c - a).abs() / world.length().max(1e-12)).sqrt()
        });
        Some(SurfaceTriangle {
            object,
            material,
            origin: v[0],
            e0,
            e1,
            inv: [d11 / den, -d01 / den, d00 / den],
            normal: world.normalize_or_zero(),
            normals: None,
            tangents: None,
            uv,
            scale,
        })
    }

    /// Barycentric coordinates of `p` (on or near the triangle's plane).
    fn barycentric(&self, p: Vec3) -> Vec3 {
        let e2 = p - self.origin;
        let (d20, d21) = (e2.dot(self.e0), e2.dot(self.e1));
        let b1 = self.inv[0] * d20 + self.inv[1] * d21;
        let b2 = self.inv[1] * d20 + self.inv[2] * d21;
        Vec3::new(1.0 - b1 - b2, b1, b2)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn barycentric_coordinates_recover_the_point() {
        let m = crate::material::ObjectMaterial {
            material: Default::default(),
            uvs: Vec::new(),
            tangents: Vec::new(),
        };
        let v = [Vec3::ZERO, Vec3::X * 2.0, Vec3::new(0.0, 3.0, 1.0)];
        let t = SurfaceTriangle::new(1, &m, v, None).unwrap();
        let q = v[0] * 0.2 + v[1] * 0.5 + v[2] * 0.3;
        let b = t.barycentric(q);
        assert!((b - Vec3::new(0.2, 0.5, 0.3)).length() < 1e-5, "{b}");
        assert!(SurfaceTriangle::new(1, &m, [Vec3::ZERO; 3], None).is_none());
    }
}
