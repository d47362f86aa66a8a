//! The pack's materials at screen resolution (docs/architecture.md, "Pack v2":
//! "albedo(uv, mip chosen by screen-space footprint) × lighting"): per object its glTF
//! material and proxy UVs, and the diffuse albedo at any UV, sampled from the material's
//! mipmapped textures with trilinear filtering ([`crate::texels`]).
//!
//! The albedo is the one the bake divided the lighting by ([`plenoptic_pack::RangeImage`]):
//! `(1 − metallic)(1 − transmission) · base colour`, with the base-colour texture in sRGB
//! decoded to linear and metallic multiplied by the metallic-roughness texture's blue channel.
//! UVs pass through the binding's `KHR_texture_transform` and wrap modes first.
//!
//! Normal maps bend the shading normal as the path tracer bends it (tangent frame from the
//! proxy's interpolated tangent, Gram–Schmidt against the interpolated normal, the
//! bitangent's sign from the triangle's first vertex; `normal_scale` on x and y): the runtime
//! sun and reflections use the bent normal at screen resolution, while the stored lighting
//! holds its average over a cube texel (the bake's paths start on the bent normal).
//!
//! Textures are decoded from the pack on first use and kept, as linear 16-bit texels (their size is bounded by the
//! pack's `MAX_TEXTURE_SIDE`); one that cannot be read is reported once and treated as white.

use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

use crate::brdf::SurfaceMaterial;
use crate::texels::{LinearTexture, sample};
use glam::{Vec2, Vec3, Vec4};
use plenoptic_pack::{MaterialEntry, PackReader};

/// One object's material and the UVs and tangents of its proxy vertices (empty: none).
pub(crate) struct ObjectMaterial {
    pub material: MaterialEntry,
    pub uvs: Vec<Vec2>,
    /// Unit xyz, the bitangent's sign in w (glTF's TANGENT).
    pub tangents: Vec<Vec4>,
}

/// The materials of a pack's objects, with their textures decoded on first use.
pub(crate) struct Materials {
    objects: HashMap<u32, ObjectMaterial>,
    textures: Vec<OnceLock<Option<Arc<LinearTexture>>>>,
    /// Messages about textures or attributes that could not be read.
    pub missing: Mutex<Vec<String>>,
}

impl Materials {
    /// Reads the material table, each object's material and its proxy's UVs and tangents (whose vertex
    /// count the pack reader checked against the proxy mesh).
    pub fn load(pack: &PackReader) -> Self {
        let mut objects = HashMap::new();
        let mut missing = Vec::new();
        for o in &pack.manifest().objects {
            let Some(material) = pack.object_material(o.id) else {
                continue;
            };
            let (uvs, tangents) = match pack.proxy_attributes(o.id) {
                Ok(a) => a.map(|a| (a.uvs, a.tangents)).unwrap_or_default(),
                Err(e) => {
                    missing.push(format!("UVs of object {}: {e}", o.id));
                    Default::default()
                }
            };
            objects.insert(
                o.id,
                ObjectMaterial {
                    material: material.clone(),
                    uvs,
                    tangents,
                },
            );
        }
        Materials {
            objects,
            textures: (0..pack.textures().len())
                .map(|_| OnceLock::new())
                .collect(),
            missing: Mutex::new(missing),
        }
    }

    /// The material of pack object `id`, if it has one.
    pub fn object(&self, id: u32) -> Option<&ObjectMaterial> {
        self.objects.get(&id)
    }

    /// The messages about what could not be read so far.
    pub fn messages(&self) -> Vec<String> {
        self.missing.lock().map(|m| m.clone()).unwrap_or_default()
    }

    /// Whether no object has a material.
    pub fn is_empty(&self) -> bool {
        self.objects.is_empty()
    }

    fn texture(&self, pack: &PackReader, index: u32) -> Option<&LinearTexture> {
        let slot = self.textures.get(index as usize)?;
        slot.get_or_init(|| match pack.texture(index) {
            Ok(t) => Some(Arc::new(LinearTexture::decode(&t))),
            Err(e) => {
                if let Ok(mut m) = self.missing.lock() {
                    m.push(format!("material texture {index}: {e}"));
                }
                None
            }
        })
        .as_deref()
    }

    /// The material `m` at `uv` (base colour, metalness and roughness textured), with the
    /// textures' mip chosen from `footprint`: the pixel's size in UV units (before the
    /// binding's transform). Its [`SurfaceMaterial::albedo`] is the diffuse albedo.
    pub fn surface(
        &self,
        pack: &PackReader,
        m: &MaterialEntry,
        uv: Vec2,
        footprint: f32,
    ) -> SurfaceMaterial {
        let mut base = m.base_colour.truncate();
        if let Some(b) = m.base_colour_texture
            && let Some(t) = self.texture(pack, b.texture)
        {
            base *= sample(t, b, uv, footprint).truncate();
        }
        let (mut metallic, mut roughness) = (m.metallic, m.roughness);
        if let Some(b) = m.metallic_roughness_texture
            && let Some(t) = self.texture(pack, b.texture)
        {
            let mr = sample(t, b, uv, footprint);
            metallic *= mr.z;
            roughness *= mr.y;
        }
        SurfaceMaterial {
            base,
            metallic: metallic.clamp(0.0, 1.0),
            roughness: roughness.clamp(0.0, 1.0),
            transmission: m.transmission.clamp(0.0, 1.0),
            ior: if m.ior > 0.0 { m.ior } else { 1.5 },
            thin_walled: m.thickness <= 0.0,
        }
    }

    /// The emitted radiance of material `m` at `uv`: the emissive factor × its sRGB texture,
    /// with the mip chosen from `footprint` as in [`Materials::surface`].
    pub fn emission(&self, pack: &PackReader, m: &MaterialEntry, uv: Vec2, footprint: f32) -> Vec3 {
        let mut e = m.emissive;
        if e != Vec3::ZERO
            && let Some(b) = m.emissive_texture
            && let Some(t) = self.texture(pack, b.texture)
        {
            e *= sample(t, b, uv, footprint).truncate();
        }
        e
    }

    /// The tangent-space normal of material `m`'s normal map at `uv` (x and y scaled by its
    /// `normal_scale`, not normalised), with the mip chosen from `footprint` as in
    /// [`Materials::surface`]; `None` when it has no normal map or it cannot be read.
    pub fn normal(
        &self,
        pack: &PackReader,
        m: &MaterialEntry,
        uv: Vec2,
        footprint: f32,
    ) -> Option<Vec3> {
        let b = m.normal_texture?;
        let t = self.texture(pack, b.texture)?;
        let c = sample(t, b, uv, footprint).truncate() * 2.0 - Vec3::ONE;
        Some(Vec3::new(c.x * m.normal_scale, c.y * m.normal_scale, c.z))
    }
}

/// Shading normal `ns` bent by tangent-space normal `local` in the frame of `tangent` (world,
/// not necessarily unit or orthogonal to `ns`) with bitangent sign `sign`, as the path tracer
/// bends it; `ns` itself where the frame degenerates.
pub(crate) fn bend_normal(ns: Vec3, tangent: Vec3, sign: f32, local: Vec3) -> Vec3 {
    let t = (tangent - ns * ns.dot(tangent)).normalize_or_zero();
    if t == Vec3::ZERO {
        return ns;
    }
    let b = ns.cross(t) * if sign < 0.0 { -1.0 } else { 1.0 };
    (t * local.x + b * local.y + ns * local.z).normalize_or(ns)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_maps_bend_along_the_tangent_frame() {
        let up = Vec3::Y;
        // The flat normal map's (0.5, 0.5, 1) leaves the normal alone.
        assert!((bend_normal(up, Vec3::X, 1.0, Vec3::Z) - up).length() < 1e-6);
        // Tilted towards +tangent; a tangent not orthogonal to the normal is made so.
        let tilted = Vec3::new(0.6, 0.0, 0.8);
        let n = bend_normal(up, Vec3::new(2.0, 0.5, 0.0), 1.0, tilted);
        assert!((n - Vec3::new(0.6, 0.8, 0.0)).length() < 1e-5, "{n}");
        // The bitangent is n × t, flipped by a negative sign.
        let along_b = Vec3::new(0.0, 0.6, 0.8);
        assert!(
            (bend_normal(up, Vec3::X, 1.0, along_b) - Vec3::new(0.0, 0.8, -0.6)).length() < 1e-5
        );
        assert!(
            (bend_normal(up, Vec3::X, -1.0, along_b) - Vec3::new(0.0, 0.8, 0.6)).length() < 1e-5
        );
        // A tangent along the normal has no frame.
        assert_eq!(bend_normal(up, Vec3::Y, 1.0, tilted), up);
    }
}
