//! The pack's materials (pack 1.2; docs/architecture.md, "Pack v2", **Materials**: "the glTF
//! material and its textures (mipmapped KTX2), per object"; `docs/pack-format.md`,
//! "Materials"): the manifest's `textures` and `materials` tables, each object's `material`
//! index into the latter, their consistency checks, and the reader's access to them.
//!
//! A material is glTF's metallic-roughness material with the extensions plenoptic imports
//! (emissive strength folded into `emissive`, transmission, IOR). Texture `i` of the
//! `textures` table is the [`crate::ChunkKind::MaterialTexture`] chunk with key `i`; a binding
//! keeps the glTF sampler's wrap modes and the reference's `KHR_texture_transform`.
//!
//! Packs before 1.2 have neither table: every object reads as having no material.

use glam::{Vec2, Vec3, Vec4};
use serde::{Deserialize, Serialize};

use crate::directory::{ChunkKind, NO_BASE_VIEW};
use crate::error::{PackError, Result};
use crate::manifest::Manifest;
use crate::texture::{ColourSpace, MAX_TEXTURE_SIDE, TextureImage, mip_count};

/// One entry of the manifest's `textures` table: what chunk (kind 10, key = index) holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct TextureEntry {
    /// Width of level 0, texels (1..=[`MAX_TEXTURE_SIDE`]).
    pub width: u32,
    /// Height of level 0, texels (1..=[`MAX_TEXTURE_SIDE`]).
    pub height: u32,
    /// Number of mip levels: the full chain, `⌊log₂ max(width, height)⌋ + 1`.
    pub levels: u32,
    /// sRGB (base colour, emissive) or linear (metallic-roughness, normal).
    pub colour_space: ColourSpace,
}

/// How texture coordinates outside [0, 1] wrap (glTF sampler `wrapS` / `wrapT`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum WrapMode {
    /// Tiles (glTF's default).
    #[default]
    Repeat,
    /// Clamps to the edge texels.
    ClampToEdge,
    /// Tiles, every other tile mirrored.
    MirroredRepeat,
}

/// `KHR_texture_transform`: `uv' = offset + R(rotation) · (scale ∘ uv)`, with
/// `R(r) = [[cos r, sin r], [−sin r, cos r]]` (rows), as the extension defines it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct UvTransform {
    /// Offset, in units of the texture's size.
    pub offset: Vec2,
    /// Rotation, radians.
    pub rotation: f32,
    /// Scale of the UV components.
    pub scale: Vec2,
}

/// A material's reference to a texture.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct TextureBinding {
    /// Index into the manifest's `textures` table (and key of the texture's chunk).
    pub texture: u32,
    /// Wrap mode along u.
    #[serde(default)]
    pub wrap_s: WrapMode,
    /// Wrap mode along v.
    #[serde(default)]
    pub wrap_t: WrapMode,
    /// The reference's `KHR_texture_transform`, applied to the proxy's TEXCOORD_0 before
    /// sampling; absent for none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub transform: Option<UvTransform>,
}

/// How a material's alpha (base colour alpha × texture alpha) is used (glTF `alphaMode`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(tag = "mode", rename_all = "snake_case")]
pub enum AlphaMode {
    /// Alpha is ignored.
    #[default]
    Opaque,
    /// The surface exists where alpha ≥ `cutoff`.
    Mask {
        /// glTF `alphaCutoff`.
        cutoff: f32,
    },
    /// Alpha is coverage.
    Blend,
}

/// A glTF metallic-roughness material as the pack stores it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MaterialEntry {
    /// Name from the file, or empty.
    #[serde(default)]
    pub name: String,
    /// Linear base colour factor; `w` is the alpha factor.
    pub base_colour: Vec4,
    /// Multiplies `base_colour` (sRGB texture).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub base_colour_texture: Option<TextureBinding>,
    /// Metallic factor in [0, 1].
    pub metallic: f32,
    /// Perceptual roughness factor in [0, 1].
    pub roughness: f32,
    /// Blue multiplies metallic, green roughness (linear texture).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub metallic_roughness_texture: Option<TextureBinding>,
    /// Tangent-space normal map (linear texture).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub normal_texture: Option<TextureBinding>,
    /// Normal map scale.
    pub normal_scale: f32,
    /// Linear emitted radiance factor: glTF's emissive factor × `KHR_materials_emissive_strength`
    /// (may exceed 1).
    pub emissive: Vec3,
    /// Multiplies `emissive` (sRGB texture).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub emissive_texture: Option<TextureBinding>,
    /// `KHR_materials_transmission` factor in [0, 1] (0 when absent).
    pub transmission: f32,
    /// `KHR_materials_ior` (1.5 when absent).
    pub ior: f32,
    /// `KHR_materials_volume` thickness factor (format 3.2; absent: 0): 0 makes a
    /// transmissive surface a thin wall that light crosses without bending, above 0 the mesh
    /// bounds a refracting solid.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub thickness: f32,
    /// Whether back faces are shaded as front faces.
    pub double_sided: bool,
    /// Opaque, mask (with its cutoff) or blend.
    pub alpha_mode: AlphaMode,
}

impl Default for MaterialEntry {
    /// glTF's default material.
    fn default() -> Self {
        MaterialEntry {
            name: String::new(),
            base_colour: Vec4::ONE,
            base_colour_texture: None,
            metallic: 1.0,
            roughness: 1.0,
            metallic_roughness_texture: None,
            normal_texture: None,
            normal_scale: 1.0,
            emissive: Vec3::ZERO,
            emissive_texture: None,
            transmission: 0.0,
            ior: 1.5,
            thickness: 0.0,
            double_sided: false,
            alpha_mode: AlphaMode::Opaque,
        }
    }
}

fn is_zero(x: &f32) -> bool {
    *x == 0.0
}

impl MaterialEntry {
    /// The material's texture bindings with the colour space each slot needs:
    /// (slot name, binding, colour space).
    pub fn bindings(&self) -> [(&'static str, Option<TextureBinding>, ColourSpace); 4] {
        [
            (
                "base colour texture",
                self.base_colour_texture,
                ColourSpace::Srgb,
            ),
            (
                "metallic-roughness texture",
                self.metallic_roughness_texture,
                ColourSpace::Linear,
            ),
            ("normal texture", self.normal_texture, ColourSpace::Linear),
            ("emissive texture", self.emissive_texture, ColourSpace::Srgb),
        ]
    }
}

/// Checks the material tables of `manifest`: texture sizes and chains, every factor finite,
/// every binding naming a texture of the table in the slot's colour space, every object's
/// material in the table, and (when `has_texture_chunk` is given) a chunk for every texture.
/// The message names the material, texture or object.
pub fn validate_materials(
    manifest: &Manifest,
    has_texture_chunk: Option<&dyn Fn(u32) -> bool>,
) -> std::result::Result<(), String> {
    for (i, t) in manifest.textures.iter().enumerate() {
        let sides = 1..=MAX_TEXTURE_SIDE;
        if !sides.contains(&t.width) || !sides.contains(&t.height) {
            return Err(format!(
                "texture {i} is {} × {}; sides must be in 1..={MAX_TEXTURE_SIDE}",
                t.width, t.height
            ));
        }
        if t.levels != mip_count(t.width, t.height) {
            return Err(format!(
                "texture {i} has {} levels; the full chain of {} × {} has {}",
                t.levels,
                t.width,
                t.height,
                mip_count(t.width, t.height)
            ));
        }
        if let Some(has) = has_texture_chunk
            && !has(i as u32)
        {
            return Err(format!("texture {i} has no MaterialTexture chunk"));
        }
    }
    for (i, m) in manifest.materials.iter().enumerate() {
        let scalars = [
            m.metallic,
            m.roughness,
            m.normal_scale,
            m.transmission,
            m.ior,
        ];
        let finite = m.base_colour.is_finite()
            && m.emissive.is_finite()
            && scalars.iter().all(|v| v.is_finite());
        let cutoff_ok = match m.alpha_mode {
            AlphaMode::Mask { cutoff } => cutoff.is_finite() && cutoff >= 0.0,
            _ => true,
        };
        if !finite || !cutoff_ok {
            return Err(format!(
                "material {i} '{}' has a non-finite factor or a bad alpha cutoff",
                m.name
            ));
        }
        for (slot, binding, space) in m.bindings() {
            let Some(b) = binding else { continue };
            let t = manifest.textures.get(b.texture as usize).ok_or_else(|| {
                format!(
                    "material {i} '{}': {slot} is texture {}, but the pack has {} textures",
                    m.name,
                    b.texture,
                    manifest.textures.len()
                )
            })?;
            if t.colour_space != space {
                return Err(format!(
                    "material {i} '{}': {slot} is texture {} in {:?}, the slot needs {space:?}",
                    m.name, b.texture, t.colour_space
                ));
            }
            if b.transform.is_some_and(|x| {
                !(x.offset.is_finite() && x.scale.is_finite() && x.rotation.is_finite())
            }) {
                return Err(format!(
                    "material {i} '{}': {slot} has a non-finite texture transform",
                    m.name
                ));
            }
        }
    }
    for o in &manifest.objects {
        if let Some(m) = o.material
            && m as usize >= manifest.materials.len()
        {
            return Err(format!(
                "object {} '{}' has material {m}, but the pack has {} materials",
                o.id,
                o.name,
                manifest.materials.len()
            ));
        }
    }
    Ok(())
}

impl crate::PackReader {
    /// The pack's materials (empty for packs before 1.2).
    pub fn materials(&self) -> &[MaterialEntry] {
        &self.manifest().materials
    }

    /// The pack's texture table (empty for packs before 1.2).
    pub fn textures(&self) -> &[TextureEntry] {
        &self.manifest().textures
    }

    /// The material of object `object_id`, or `None` ("no material": objects without one and
    /// every object of a pack before 1.2). The index was checked at open.
    pub fn object_material(&self, object_id: u32) -> Option<&MaterialEntry> {
        let object = self.manifest().objects.iter().find(|o| o.id == object_id)?;
        self.materials().get(object.material? as usize)
    }

    /// Texture `index` of the texture table with its decoded mip levels (level 0 first). The
    /// chunk's header is checked against the table before any level is decompressed. Errors
    /// name the pack: [`PackError::InvalidMaterial`] when the table and the chunk disagree (or
    /// there is no such texture), [`PackError::InvalidTexture`] wrapping the chunk's own error
    /// (checksum, KTX2 header, mip chain, zstd frames) otherwise.
    pub fn texture(&self, index: u32) -> Result<TextureImage> {
        let fail = |reason: String| PackError::InvalidMaterial {
            path: self.path().to_path_buf(),
            reason,
        };
        let entry = *self.textures().get(index as usize).ok_or_else(|| {
            fail(format!(
                "texture {index} asked for, the pack has {}",
                self.textures().len()
            ))
        })?;
        let chunk = self
            .find(ChunkKind::MaterialTexture, NO_BASE_VIEW, index)
            .ok_or_else(|| fail(format!("texture {index} has no chunk")))?;
        let wrap = |e: PackError| PackError::InvalidTexture {
            path: self.path().to_path_buf(),
            index,
            source: Box::new(e),
        };
        let bytes = self.chunk_bytes(chunk).map_err(wrap)?;
        let info = crate::texture::inspect_texture(&bytes)
            .map_err(|e| wrap(e.in_chunk(self.entries()[chunk].chunk_ref(chunk))))?;
        if (info.width, info.height, info.levels, info.colour_space)
            != (entry.width, entry.height, entry.levels, entry.colour_space)
        {
            return Err(fail(format!(
                "texture {index}: the table says {} × {}, {} levels, {:?}; the chunk {} × {}, {} levels, {:?}",
                entry.width,
                entry.height,
                entry.levels,
                entry.colour_space,
                info.width,
                info.height,
                info.levels,
                info.colour_space
            )));
        }
        match self.chunk(chunk).map_err(wrap)? {
            crate::Chunk::Texture(t) => Ok(t),
            _ => unreachable!("decoded by kind"),
        }
    }

    /// The stored bytes of texture `index`'s chunk: a complete KTX2 file (checksum verified),
    /// e.g. for Bevy's KTX2 loader (give it `is_srgb` = the entry's
    /// [`ColourSpace::is_srgb`]).
    pub fn texture_ktx2(&self, index: u32) -> Result<Vec<u8>> {
        let chunk = self
            .find(ChunkKind::MaterialTexture, NO_BASE_VIEW, index)
            .ok_or(PackError::ChunkNotFound {
                kind: ChunkKind::MaterialTexture,
                base_view: NO_BASE_VIEW,
                key: index,
            })?;
        self.chunk_bytes(chunk)
    }
}
