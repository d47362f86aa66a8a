//! glTF materials to [`Material`]s: factors, `alphaMode`/`alphaCutoff`, the extensions
//! plenoptic reads, and texture references with their sampler's wrap modes and
//! `KHR_texture_transform`; textures are decoded once per image and colour space.
//!
//! `KHR_texture_transform` is read from the raw JSON of each textureInfo (the `gltf` crate
//! exposes it for some texture references but not for the normal texture), so all four
//! textures the tracer samples are handled by one code path.

use std::collections::HashMap;

use glam::{Vec2, Vec3, Vec4};
use gltf::texture::{MagFilter, WrappingMode};
use serde_json::Value;

use super::data::Data;
use super::mesh::srgb_to_linear;
use crate::error::Result;
use crate::model::{AlphaMode, Material, Texture, TextureRef, UvTransform, WrapMode};

/// Materials and their decoded textures, each texture decoded once per colour space.
#[derive(Default)]
pub(super) struct Materials {
    pub(super) textures: Vec<Texture>,
    cache: HashMap<(usize, bool), usize>,
}

/// One texture reference of a material as the file gives it.
struct Info<'a> {
    texture: gltf::Texture<'a>,
    tex_coord: u32,
    /// The textureInfo's JSON object, for its extensions.
    raw: Option<&'a Value>,
    srgb: bool,
    what: &'static str,
}

impl Materials {
    /// Converts a glTF material; `raw` is its JSON object (for extensions of texture
    /// references); `warnings` collects what is not supported.
    pub(super) fn convert(
        &mut self,
        data: &Data,
        material: &gltf::Material,
        raw: Option<&Value>,
        warnings: &mut Vec<String>,
    ) -> Result<Material> {
        let label = match material.index() {
            Some(i) => match material.name() {
                Some(name) => format!("material {i} '{name}'"),
                None => format!("material {i}"),
            },
            None => "default material".to_owned(),
        };
        let pbr = material.pbr_metallic_roughness();
        let strength = material.emissive_strength().unwrap_or(1.0);
        let factors = [pbr.metallic_factor(), pbr.roughness_factor(), strength];
        if factors
            .iter()
            .chain(&pbr.base_color_factor())
            .chain(&material.emissive_factor())
            .any(|v| !v.is_finite())
        {
            return Err(data.err(label, "non-finite factor"));
        }
        let alpha_mode = match material.alpha_mode() {
            gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
            gltf::material::AlphaMode::Blend => AlphaMode::Blend,
            gltf::material::AlphaMode::Mask => {
                let cutoff = material.alpha_cutoff().unwrap_or(0.5);
                // JSON cannot hold NaN, but a hand-built document can; the schema's minimum
                // is 0. Both are errors rather than a guess.
                if !cutoff.is_finite() || cutoff < 0.0 {
                    return Err(data.err(
                        label,
                        format!("alphaCutoff {cutoff} must be a finite number ≥ 0"),
                    ));
                }
                if cutoff > 1.0 {
                    warnings.push(format!(
                        "{label}: alphaCutoff {cutoff} > 1 cuts the whole surface away"
                    ));
                }
                AlphaMode::Mask { cutoff }
            }
        };
        let raw_pbr = raw.and_then(|m| m.get("pbrMetallicRoughness"));
        let infos = [
            pbr.base_color_texture().map(|i| Info {
                texture: i.texture(),
                tex_coord: i.tex_coord(),
                raw: child(raw_pbr, "baseColorTexture"),
                srgb: true,
                what: "base colour texture",
            }),
            pbr.metallic_roughness_texture().map(|i| Info {
                texture: i.texture(),
                tex_coord: i.tex_coord(),
                raw: child(raw_pbr, "metallicRoughnessTexture"),
                srgb: false,
                what: "metallic-roughness texture",
            }),
            material.emissive_texture().map(|i| Info {
                texture: i.texture(),
                tex_coord: i.tex_coord(),
                raw: child(raw, "emissiveTexture"),
                srgb: true,
                what: "emissive texture",
            }),
            material.normal_texture().map(|i| Info {
                texture: i.texture(),
                tex_coord: i.tex_coord(),
                raw: child(raw, "normalTexture"),
                srgb: false,
                what: "normal texture",
            }),
        ];
        let mut refs = [None; 4];
        for (slot, info) in refs.iter_mut().zip(infos) {
            if let Some(info) = info {
                *slot = Some(self.reference(data, &label, &info, warnings)?);
            }
        }
        let [
            base_color_texture,
            metallic_roughness_texture,
            emissive_texture,
            normal_texture,
        ] = refs;
        let normal_scale = material.normal_texture().map_or(1.0, |n| n.scale());
        let base = pbr.base_color_factor();
        Ok(Material {
            name: material.name().unwrap_or_default().to_owned(),
            base_color: Vec4::from_array(base),
            base_color_texture,
            metallic: pbr.metallic_factor(),
            roughness: pbr.roughness_factor(),
            metallic_roughness_texture,
            emissive: Vec3::from_array(material.emissive_factor()) * strength,
            emissive_texture,
            normal_texture,
            normal_scale,
            transmission: material
                .transmission()
                .map_or(0.0, |t| t.transmission_factor()),
            ior: material.ior().unwrap_or(1.5),
            thickness: material
                .volume()
                .map_or(0.0, |v| v.thickness_factor().max(0.0)),
            double_sided: material.double_sided(),
            alpha_mode,
        })
    }

    /// The reference of one textureInfo: decoded texture, wrap modes, transform.
    fn reference(
        &mut self,
        data: &Data,
        label: &str,
        info: &Info,
        warnings: &mut Vec<String>,
    ) -> Result<TextureRef> {
        let what = info.what;
        let (transform, override_set) = texture_transform(data, label, what, info.raw)?;
        let set = override_set.unwrap_or(info.tex_coord);
        if set != 0 {
            warnings.push(format!(
                "{label}: {what} uses TEXCOORD_{set}; only set 0 is imported, the texture is sampled with it"
            ));
        }
        let sampler = info.texture.sampler();
        let wrap = |mode: WrappingMode| match mode {
            WrappingMode::Repeat => WrapMode::Repeat,
            WrappingMode::ClampToEdge => WrapMode::ClampToEdge,
            WrappingMode::MirroredRepeat => WrapMode::MirroredRepeat,
        };
        if sampler.mag_filter() == Some(MagFilter::Nearest) {
            warnings.push(format!(
                "{label}: {what}: texture {} asks for NEAREST magnification; sampled bilinearly",
                info.texture.index()
            ));
        }
        Ok(TextureRef {
            texture: self.texture(data, &info.texture, info.srgb)?,
            wrap_s: wrap(sampler.wrap_s()),
            wrap_t: wrap(sampler.wrap_t()),
            transform,
        })
    }

    /// The index of the decoded image of `texture` in `srgb` or linear space.
    fn texture(&mut self, data: &Data, texture: &gltf::Texture, srgb: bool) -> Result<usize> {
        let image = texture.source();
        let key = (image.index(), srgb);
        if let Some(&index) = self.cache.get(&key) {
            return Ok(index);
        }
        let element = format!("image {}", image.index());
        let bytes = match image.source() {
            gltf::image::Source::View { view, .. } => data.view_bytes(&view)?.to_vec(),
            gltf::image::Source::Uri { uri, .. } => data.resolve_uri(&element, uri)?,
        };
        let decoded = image::load_from_memory(&bytes)
            .map_err(|e| data.err(&element, format!("cannot decode: {e}")))?;
        let rgba = decoded.to_rgba32f();
        let (width, height) = rgba.dimensions();
        let texels = rgba
            .pixels()
            .map(|p| {
                let [r, g, b, a] = p.0;
                if srgb {
                    Vec4::new(srgb_to_linear(r), srgb_to_linear(g), srgb_to_linear(b), a)
                } else {
                    Vec4::new(r, g, b, a)
                }
            })
            .collect();
        self.textures.push(Texture {
            width,
            height,
            texels,
        });
        let index = self.textures.len() - 1;
        self.cache.insert(key, index);
        Ok(index)
    }
}

/// Member `key` of a JSON object, if both exist.
fn child<'v>(parent: Option<&'v Value>, key: &str) -> Option<&'v Value> {
    parent.and_then(|p| p.get(key))
}

/// `KHR_texture_transform` of a textureInfo's JSON: the transform and the `texCoord` override.
fn texture_transform(
    data: &Data,
    label: &str,
    what: &str,
    raw: Option<&Value>,
) -> Result<(UvTransform, Option<u32>)> {
    let Some(ext) = raw
        .and_then(|i| i.get("extensions"))
        .and_then(|e| e.get("KHR_texture_transform"))
    else {
        return Ok((UvTransform::IDENTITY, None));
    };
    let bad =
        |problem: String| data.err(format!("{label}: {what}: KHR_texture_transform"), problem);
    let number = |v: &Value, key: &str| -> Result<f32> {
        match v.as_f64() {
            Some(x) if x.is_finite() && (x as f32).is_finite() => Ok(x as f32),
            _ => Err(bad(format!("{key} must be a finite number, found {v}"))),
        }
    };
    let pair = |key: &str, default: Vec2| -> Result<Vec2> {
        match ext.get(key) {
            None => Ok(default),
            Some(Value::Array(a)) if a.len() == 2 => {
                Ok(Vec2::new(number(&a[0], key)?, number(&a[1], key)?))
            }
            Some(v) => Err(bad(format!(
                "{key} must be an array of 2 numbers, found {v}"
            ))),
        }
    };
    let transform = UvTransform {
        offset: pair("offset", Vec2::ZERO)?,
        rotation: match ext.get("rotation") {
            None => 0.0,
            Some(v) => number(v, "rotation")?,
        },
        scale: pair("scale", Vec2::ONE)?,
    };
    let tex_coord = match ext.get("texCoord") {
        None => None,
        Some(v) => Some(
            v.as_u64()
                .and_then(|n| u32::try_from(n).ok())
                .ok_or_else(|| {
                    bad(format!(
                        "texCoord must be a non-negative integer, found {v}"
                    ))
                })?,
        ),
    };
    Ok((transform, tex_coord))
}
