//! Geometry-assisted frames from pack v2 (docs/architecture.md, "Pack v2"; thesis ch. 8:
//! separating illumination quality from image quality): a pixel on an object with a material
//! is
//!
//! `albedo(uv) · lighting + non-diffuse`
//!
//! where the *lighting* and the *non-diffuse radiance* (emission plus the specular part as
//! the base views saw it) are looked up in the range images exactly as the radiance was
//! (motion-compensated, view- and time-blended, with the volume and hole-fill fallbacks of
//! [`crate::geometry`]), and the *albedo* comes from the object's material at the pixel's own
//! UV, with the texture's mip chosen by the pixel's footprint ([`crate::material`]). Texture
//! detail is therefore at screen resolution whatever the cube size; only the lighting is at
//! cube resolution.
//!
//! The lighting and non-diffuse lookups are always seam-aware bilinear
//! ([`CubeFilter::Bilinear`]): at cube resolution, nearest texels show as blocks.
//!
//! One geometry pass runs per channel: radiance for objects without a material (and for the
//! environment where nothing is), lighting and non-diffuse for the others, each skipping the
//! objects another pass shades. A separate raster pass gives each pixel its triangle, from
//! which the UV is interpolated (barycentric coordinates of the pixel's point on the placed
//! triangle) and the footprint computed (the square root of the surface area the pixel
//! covers, `distance · pixel angle · cos^1.5 α / √|cos θ|` for a pixel whose ray is at α
//! to the axis and meets the surface at θ, times the triangle's UV-per-metre scale: the
//! `√|det ∂uv/∂(x, y)|` a GPU's derivatives give).
//!
//! Not yet built: normal maps (the stored lighting is for the texel's normal only), runtime
//! specular for the actual camera (the non-diffuse part is the base views'), emissive
//! textures (emission is in the non-diffuse cube at cube resolution).

use glam::{Vec2, Vec3};
use plenoptic_pack::{ChunkKind, VolumeSample};
use rayon::prelude::*;

use crate::camera::Camera;
use crate::frame::{Frame, Report};
use crate::geometry::{self, Layer, Pass};
use crate::material::Materials;
use crate::proxy::GeometryMask;
use crate::settings::{CubeFilter, Shading};
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
        filter: if channel == Channel::Radiance {
            rec.settings.cube_filter
        } else {
            CubeFilter::Bilinear
        },
    };
    let mut stages = Vec::new();
    // One geometry pass, timed as stage `name`.
    let mut run = |name: &str, channel, skip, report: &mut Report| {
        let start = std::time::Instant::now();
        let frame = geometry::render(rec, camera, t, mask, pass(channel, skip), report);
        stages.push((name.to_string(), start.elapsed().as_secs_f64() * 1e3));
        frame
    };
    // The lighting first: a pack v2 always has it, and a damaged one is then shown from its
    // radiance in one pass instead of two.
    let mut side = Report::default();
    let lighting = run("lighting_pass", Channel::Lighting, &unlit, &mut side);
    let non_diffuse = run("non_diffuse_pass", Channel::NonDiffuse, &unlit, &mut side);
    let (lighting, non_diffuse) = match (lighting, non_diffuse) {
        (Ok(l), Ok(s)) => (l, s),
        (Err(e), _) | (_, Err(e)) => {
            report.missing.push(format!("materials not applied: {e}"));
            return radiance_only(report);
        }
    };
    let mut frame = run("radiance_pass", Channel::Radiance, &lit, report)?;
    let mut timed = |name: &str, start: std::time::Instant| {
        stages.push((name.to_string(), start.elapsed().as_secs_f64() * 1e3));
    };
    let start = std::time::Instant::now();
    let (albedo, raster_ms) = albedo_image(rec, materials, camera, t, layer);
    timed("albedo", start);
    let start = std::time::Instant::now();
    frame
        .radiance
        .par_iter_mut()
        .enumerate()
        .for_each(|(j, c)| {
            if let Some((o, a)) = albedo[j]
                && lighting.object[j] == o
            {
                *c = a * lighting.radiance[j] + non_diffuse.radiance[j];
            }
        });
    timed("compose", start);
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

/// Per pixel, the object seen there and the diffuse albedo of its material (`None` where no
/// object with a material is); and the milliseconds its raster pass took.
fn albedo_image(
    rec: &Reconstructor,
    materials: &Materials,
    camera: &Camera,
    t: f32,
    layer: Layer<'_>,
) -> (Vec<Option<(u32, Vec3)>>, f64) {
    let n = camera.pixel_count();
    let Some(proxy) = rec.proxy() else {
        return (vec![None; n], 0.0);
    };
    let start = std::time::Instant::now();
    let mut placed = proxy.placed_meshes(t);
    match layer {
        Layer::All => {}
        Layer::Without(ids) => placed.retain(|o| !ids.contains(&o.0)),
        Layer::Only(ids) => placed.retain(|o| ids.contains(&o.0)),
    }
    let projected = crate::raster::project(camera, &placed);
    let (object, prim, depth) = crate::raster::rasterize_sources(camera, &projected);
    let raster_ms = start.elapsed().as_secs_f64() * 1e3;
    // Per projected triangle, once: its placed corners, UVs and UV-per-metre scale.
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
            SurfaceTriangle::new(*id, m, v, uv)
        })
        .collect();
    let basis = camera.basis();
    let w = camera.width as usize;
    // The angle one pixel subtends at the image centre.
    let pixel_angle = 2.0 * basis.tan_y / basis.height;
    let albedo = (0..n)
        .into_par_iter()
        .map(|j| {
            let t = triangles.get(prim[j] as usize)?.as_ref()?;
            if t.object != object[j] {
                return None;
            }
            let dir = basis.direction((j % w) as f32 + 0.5, (j / w) as f32 + 0.5);
            let (uv, footprint) = match &t.uv {
                Some(uv) => {
                    let b = t.barycentric(basis.position + dir * depth[j]);
                    let cos = t.normal.dot(dir).abs().max(0.05);
                    // A pixel off the axis subtends cos³α of the central pixel's solid angle.
                    let c = dir.dot(basis.forward).max(0.0);
                    let off_axis = c * c.sqrt();
                    (
                        uv[0] * b.x + uv[1] * b.y + uv[2] * b.z,
                        t.scale * depth[j] * pixel_angle * off_axis / cos.sqrt(),
                    )
                }
                None => (Vec2::ZERO, f32::INFINITY),
            };
            Some((
                t.object,
                materials.albedo(rec.pack(), &t.material.material, uv, footprint),
            ))
        })
        .collect();
    (albedo, raster_ms)
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
        };
        let v = [Vec3::ZERO, Vec3::X * 2.0, Vec3::new(0.0, 3.0, 1.0)];
        let t = SurfaceTriangle::new(1, &m, v, None).unwrap();
        let q = v[0] * 0.2 + v[1] * 0.5 + v[2] * 0.3;
        let b = t.barycentric(q);
        assert!((b - Vec3::new(0.2, 0.5, 0.3)).length() < 1e-5, "{b}");
        assert!(SurfaceTriangle::new(1, &m, [Vec3::ZERO; 3], None).is_none());
    }
}
