//! The scene's materials as the pack stores them (docs/architecture.md, "Pack v2",
//! **Materials**; pack format 1.2, `docs/pack-format.md` "Materials"): the materials the
//! objects use, their textures as RGBA8 with full mip chains, and the proxies' UVs and
//! tangents.
//!
//! - Materials: one pack material per scene material that an object uses, in order of first
//!   use by object id; objects without a usable material get none.
//! - Textures: a scene texture is decoded linear RGBA; the pack stores it as 8-bit sRGB (base
//!   colour, emissive) or 8-bit linear (metallic-roughness, normal), so an 8-bit source image
//!   comes back byte for byte. Textures are deduplicated on their stored level 0 and colour
//!   space: several materials (or glTF textures) sharing one image share one chunk. Sides
//!   above [`MAX_TEXTURE_SIDE`] are halved (2×2 box) until they fit.
//! - `KHR_texture_transform` stays per texture binding in the material (each texture of a
//!   material may have its own), and the proxies keep the file's TEXCOORD_0.
//! - Tangents: the scene's (the file's TANGENT, or what the importer computed for a normal
//!   map); a mesh with UVs and no tangents gets them from [`plenoptic_scene::Mesh::uv_tangents`],
//!   the same method, so the runtime shades normal maps with the tracer's tangent frames.

use std::collections::HashMap;

use plenoptic_pack::texture::next_mip;
use plenoptic_pack::{
    AlphaMode, ColourSpace, MAX_TEXTURE_SIDE, MaterialEntry, ProxyAttributes, TextureBinding,
    TextureEntry, TextureImage, UvTransform, WrapMode,
};
use plenoptic_scene::{Scene, TextureRef};

use crate::error::Result;

/// What [`pack_materials`] gives: the manifest's tables and the texture chunks' contents.
#[derive(Debug, Default)]
pub struct PackMaterials {
    /// The manifest's `textures` table; entry `i` is `images[i]`.
    pub textures: Vec<TextureEntry>,
    /// The texture chunks, with mip chains.
    pub images: Vec<TextureImage>,
    /// The manifest's `materials` table.
    pub materials: Vec<MaterialEntry>,
    /// Per scene object (by index), its pack material.
    pub object_material: Vec<Option<u32>>,
}

/// Builds the materials and textures of `scene` (see the module doc).
pub fn pack_materials(scene: &Scene) -> Result<PackMaterials> {
    let mut out = PackMaterials::default();
    let mut material_of_scene: HashMap<usize, u32> = HashMap::new();
    let mut textures = TextureTable::default();
    for o in &scene.objects {
        let Some(m) = scene.materials.get(o.material) else {
            out.object_material.push(None);
            continue;
        };
        let index = match material_of_scene.get(&o.material) {
            Some(&i) => i,
            None => {
                let mut bind = |r: &Option<TextureRef>, space| -> Result<Option<TextureBinding>> {
                    let Some(r) = r else { return Ok(None) };
                    let Some(texture) = textures.index(scene, r.texture, space, &mut out)? else {
                        return Ok(None);
                    };
                    Ok(Some(binding(r, texture)))
                };
                let entry = MaterialEntry {
                    name: m.name.clone(),
                    base_colour: m.base_color,
                    base_colour_texture: bind(&m.base_color_texture, ColourSpace::Srgb)?,
                    metallic: m.metallic,
                    roughness: m.roughness,
                    metallic_roughness_texture: bind(
                        &m.metallic_roughness_texture,
                        ColourSpace::Linear,
                    )?,
                    normal_texture: bind(&m.normal_texture, ColourSpace::Linear)?,
                    normal_scale: m.normal_scale,
                    emissive: m.emissive,
                    emissive_texture: bind(&m.emissive_texture, ColourSpace::Srgb)?,
                    transmission: m.transmission,
                    ior: m.ior,
                    thickness: m.thickness.max(0.0),
                    double_sided: m.double_sided,
                    alpha_mode: match m.alpha_mode {
                        plenoptic_scene::AlphaMode::Opaque => AlphaMode::Opaque,
                        plenoptic_scene::AlphaMode::Mask { cutoff } => AlphaMode::Mask { cutoff },
                        plenoptic_scene::AlphaMode::Blend => AlphaMode::Blend,
                    },
                };
                out.materials.push(entry);
                let i = (out.materials.len() - 1) as u32;
                material_of_scene.insert(o.material, i);
                i
            }
        };
        out.object_material.push(Some(index));
    }
    Ok(out)
}

fn binding(r: &TextureRef, texture: u32) -> TextureBinding {
    let wrap = |w| match w {
        plenoptic_scene::WrapMode::Repeat => WrapMode::Repeat,
        plenoptic_scene::WrapMode::ClampToEdge => WrapMode::ClampToEdge,
        plenoptic_scene::WrapMode::MirroredRepeat => WrapMode::MirroredRepeat,
    };
    TextureBinding {
        texture,
        wrap_s: wrap(r.wrap_s),
        wrap_t: wrap(r.wrap_t),
        transform: (!r.transform.is_identity()).then_some(UvTransform {
            offset: r.transform.offset,
            rotation: r.transform.rotation,
            scale: r.transform.scale,
        }),
    }
}

/// Deduplication of textures: by (scene texture, colour space), then by stored content.
#[derive(Default)]
struct TextureTable {
    by_reference: HashMap<(usize, ColourSpace), Option<u32>>,
    by_content: HashMap<(ColourSpace, u32, u32, u64), Vec<u32>>,
}

impl TextureTable {
    /// The pack texture of scene texture `texture` in `space`; `None` when the scene has no
    /// such texture (or it is empty).
    fn index(
        &mut self,
        scene: &Scene,
        texture: usize,
        space: ColourSpace,
        out: &mut PackMaterials,
    ) -> Result<Option<u32>> {
        if let Some(&i) = self.by_reference.get(&(texture, space)) {
            return Ok(i);
        }
        let image = match scene.textures.get(texture) {
            Some(t) if t.width > 0 && t.height > 0 => Some(stored_image(t, space)?),
            _ => None,
        };
        let index = image.map(|image| {
            let level0 = &image.levels[0];
            let key = (
                space,
                level0.width,
                level0.height,
                plenoptic_pack::checksum(&level0.texels),
            );
            let same = self.by_content.entry(key).or_default();
            if let Some(&i) = same
                .iter()
                .find(|&&i| out.images[i as usize].levels[0] == *level0)
            {
                return i;
            }
            out.textures.push(TextureEntry {
                width: level0.width,
                height: level0.height,
                levels: image.levels.len() as u32,
                colour_space: space,
            });
            out.images.push(image);
            let i = (out.images.len() - 1) as u32;
            same.push(i);
            i
        });
        self.by_reference.insert((texture, space), index);
        Ok(index)
    }
}

/// A scene texture (linear RGBA) as a pack texture in `space`, halved until it fits.
fn stored_image(t: &plenoptic_scene::Texture, space: ColourSpace) -> Result<TextureImage> {
    let mut bytes = Vec::with_capacity(t.texels.len() * 4);
    for c in &t.texels {
        let rgb = c.truncate().to_array().map(|v| match space {
            ColourSpace::Srgb => plenoptic_pack::texture::linear_to_srgb(v),
            ColourSpace::Linear => v,
        });
        for v in rgb.into_iter().chain([c.w]) {
            bytes.push((v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8);
        }
    }
    let mut level = plenoptic_pack::TextureLevel {
        width: t.width,
        height: t.height,
        texels: bytes,
    };
    while level.width > MAX_TEXTURE_SIDE || level.height > MAX_TEXTURE_SIDE {
        level = next_mip(space, &level);
    }
    Ok(TextureImage::with_mips(
        space,
        level.width,
        level.height,
        level.texels,
    )?)
}

/// The UVs and tangents of every proxy mesh whose mesh has UVs (see the module doc); object
/// ids as the proxies'.
pub fn proxy_attributes(scene: &Scene) -> Vec<ProxyAttributes> {
    crate::write::proxied_objects(scene)
        .filter(|(_, mesh)| mesh.uvs.len() == mesh.positions.len())
        .map(|(object_id, mesh)| {
            let tangents = if mesh.tangents.len() == mesh.positions.len() {
                mesh.tangents.clone()
            } else {
                mesh.uv_tangents()
            };
            ProxyAttributes {
                object_id,
                uvs: mesh.uvs.clone(),
                tangents,
            }
        })
        .collect()
}
