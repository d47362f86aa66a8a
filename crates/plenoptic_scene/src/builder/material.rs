//! The builder's materials ([`MaterialDesc`]) and their serialisation: factors, alpha mode
//! and cutoff, textures with `KHR_texture_transform`, and the material extensions (emissive
//! strength, transmission, IOR).

use glam::{Vec3, Vec4};
use serde_json::{Map, Value, json};

use super::write::{check_finite, invalid};
use super::{SceneBuilder, TextureHandle};
use crate::error::Result;
use crate::model::{AlphaMode, UvTransform};

/// A material of the builder (glTF metallic-roughness plus emissive strength, transmission
/// and IOR). Fields are public; the chaining methods set them one by one.
#[derive(Debug, Clone, PartialEq)]
pub struct MaterialDesc {
    /// Name written to the file.
    pub name: String,
    /// Linear base colour and alpha.
    pub base_color: Vec4,
    /// Base colour texture (sRGB).
    pub base_color_texture: Option<TextureHandle>,
    /// Metalness in [0, 1].
    pub metallic: f32,
    /// Perceptual roughness in [0, 1].
    pub roughness: f32,
    /// Metallic (blue) and roughness (green) texture.
    pub metallic_roughness_texture: Option<TextureHandle>,
    /// Emissive colour; components above 1 are folded into the strength when written.
    pub emissive: Vec3,
    /// `KHR_materials_emissive_strength` multiplier.
    pub emissive_strength: f32,
    /// Emissive texture (sRGB).
    pub emissive_texture: Option<TextureHandle>,
    /// Tangent-space normal map.
    pub normal_texture: Option<TextureHandle>,
    /// `KHR_materials_transmission` factor in [0, 1].
    pub transmission: f32,
    /// `KHR_materials_ior`.
    pub ior: f32,
    /// `KHR_materials_volume` thickness factor (m in the mesh's space): 0 writes no volume,
    /// a thin-walled surface; above 0 the mesh bounds a refracting solid.
    pub thickness: f32,
    /// Whether back faces are shaded too.
    pub double_sided: bool,
    /// glTF `alphaMode` (and `alphaCutoff` for [`AlphaMode::Mask`]).
    pub alpha_mode: AlphaMode,
    /// `KHR_texture_transform` written on every texture of the material; `None` (or the
    /// identity) writes none.
    pub texture_transform: Option<UvTransform>,
}

impl Default for MaterialDesc {
    fn default() -> Self {
        Self {
            name: String::new(),
            base_color: Vec4::ONE,
            base_color_texture: None,
            metallic: 0.0,
            roughness: 0.5,
            metallic_roughness_texture: None,
            emissive: Vec3::ZERO,
            emissive_strength: 1.0,
            emissive_texture: None,
            normal_texture: None,
            transmission: 0.0,
            ior: 1.5,
            thickness: 0.0,
            double_sided: false,
            alpha_mode: AlphaMode::Opaque,
            texture_transform: None,
        }
    }
}

impl MaterialDesc {
    /// A rough dielectric (roughness 1) with linear base colour `color`.
    pub fn diffuse(color: Vec3) -> Self {
        Self {
            base_color: color.extend(1.0),
            roughness: 1.0,
            ..Self::default()
        }
    }

    /// A metal of colour `color` and roughness `roughness`.
    pub fn metal(color: Vec3, roughness: f32) -> Self {
        Self {
            base_color: color.extend(1.0),
            metallic: 1.0,
            roughness,
            ..Self::default()
        }
    }

    /// A black emitter of radiance `color · strength`.
    pub fn emitter(color: Vec3, strength: f32) -> Self {
        Self {
            base_color: Vec4::new(0.0, 0.0, 0.0, 1.0),
            emissive: color,
            emissive_strength: strength,
            ..Self::default()
        }
    }

    /// Clear glass: full transmission, smooth, IOR `ior`.
    pub fn glass(ior: f32) -> Self {
        Self {
            roughness: 0.0,
            transmission: 1.0,
            ior,
            ..Self::default()
        }
    }

    /// Sets the name.
    pub fn named(mut self, name: impl Into<String>) -> Self {
        self.name = name.into();
        self
    }
    /// Sets the linear base colour (alpha 1).
    pub fn base_color(mut self, color: Vec3) -> Self {
        self.base_color = color.extend(1.0);
        self
    }
    /// Sets metalness.
    pub fn metallic(mut self, metallic: f32) -> Self {
        self.metallic = metallic;
        self
    }
    /// Sets perceptual roughness.
    pub fn roughness(mut self, roughness: f32) -> Self {
        self.roughness = roughness;
        self
    }
    /// Sets the emissive colour and strength.
    pub fn emissive(mut self, color: Vec3, strength: f32) -> Self {
        self.emissive = color;
        self.emissive_strength = strength;
        self
    }
    /// Sets transmission and IOR.
    pub fn transmission(mut self, transmission: f32, ior: f32) -> Self {
        self.transmission = transmission;
        self.ior = ior;
        self
    }
    /// Makes a transmissive material a refracting solid of about `thickness` (m)
    /// (`KHR_materials_volume`); 0 keeps it a thin wall.
    pub fn thickness(mut self, thickness: f32) -> Self {
        self.thickness = thickness;
        self
    }
    /// Sets double-sidedness.
    pub fn double_sided(mut self, double_sided: bool) -> Self {
        self.double_sided = double_sided;
        self
    }
    /// Sets the base colour texture.
    pub fn base_color_texture(mut self, texture: TextureHandle) -> Self {
        self.base_color_texture = Some(texture);
        self
    }
    /// Sets the metallic-roughness texture.
    pub fn metallic_roughness_texture(mut self, texture: TextureHandle) -> Self {
        self.metallic_roughness_texture = Some(texture);
        self
    }
    /// Sets the emissive texture.
    pub fn emissive_texture(mut self, texture: TextureHandle) -> Self {
        self.emissive_texture = Some(texture);
        self
    }
    /// Sets the normal map.
    pub fn normal_texture(mut self, texture: TextureHandle) -> Self {
        self.normal_texture = Some(texture);
        self
    }
    /// Sets the linear base colour with its alpha.
    pub fn base_color_alpha(mut self, color: Vec4) -> Self {
        self.base_color = color;
        self
    }
    /// Sets the alpha mode: [`AlphaMode::Mask`] with a cutoff, or [`AlphaMode::Blend`]
    /// (coverage).
    pub fn alpha_mode(mut self, mode: AlphaMode) -> Self {
        self.alpha_mode = mode;
        self
    }
    /// Sets the `KHR_texture_transform` of all the material's textures.
    pub fn texture_transform(mut self, transform: UvTransform) -> Self {
        self.texture_transform = Some(transform);
        self
    }
}

/// The `materials` array; the extensions it uses are added to `used`.
pub(super) fn materials(b: &SceneBuilder, used: &mut Vec<String>) -> Result<Vec<Value>> {
    let mut materials = Vec::new();
    let mut add_used = |name: &str| {
        if !used.iter().any(|u| u == name) {
            used.push(name.to_owned());
        }
    };
    for (i, m) in b.materials.iter().enumerate() {
        let element = format!("material {i} '{}'", m.name);
        check_finite(
            &element,
            "factors",
            &[
                m.base_color.x,
                m.base_color.y,
                m.base_color.z,
                m.base_color.w,
                m.metallic,
                m.roughness,
                m.emissive.x,
                m.emissive.y,
                m.emissive.z,
                m.emissive_strength,
                m.transmission,
                m.ior,
                m.thickness,
            ],
        )?;
        let transform = m.texture_transform.filter(|t| !t.is_identity());
        if let Some(t) = transform {
            check_finite(
                &element,
                "texture transform",
                &[t.offset.x, t.offset.y, t.rotation, t.scale.x, t.scale.y],
            )?;
            add_used("KHR_texture_transform");
        }
        let tex = |h: Option<TextureHandle>| -> Result<Option<Value>> {
            match h {
                None => Ok(None),
                Some(h) if h.0 < b.textures.len() => {
                    let mut info = json!({"index": h.0});
                    if let Some(t) = transform {
                        info["extensions"] = json!({"KHR_texture_transform": transform_json(t)});
                    }
                    Ok(Some(info))
                }
                Some(h) => Err(invalid(
                    &element,
                    format!("texture handle {} from another builder", h.0),
                )),
            }
        };
        let mut pbr = json!({
            "baseColorFactor": m.base_color.to_array(),
            "metallicFactor": m.metallic,
            "roughnessFactor": m.roughness,
        });
        if let Some(t) = tex(m.base_color_texture)? {
            pbr["baseColorTexture"] = t;
        }
        if let Some(t) = tex(m.metallic_roughness_texture)? {
            pbr["metallicRoughnessTexture"] = t;
        }
        let mut mat = json!({"pbrMetallicRoughness": pbr, "doubleSided": m.double_sided});
        if !m.name.is_empty() {
            mat["name"] = json!(m.name);
        }
        match m.alpha_mode {
            AlphaMode::Opaque => {}
            AlphaMode::Blend => mat["alphaMode"] = json!("BLEND"),
            AlphaMode::Mask { cutoff } => {
                if !cutoff.is_finite() || cutoff < 0.0 {
                    return Err(invalid(
                        &element,
                        format!("alpha cutoff {cutoff} must be a finite number ≥ 0"),
                    ));
                }
                mat["alphaMode"] = json!("MASK");
                mat["alphaCutoff"] = json!(cutoff);
            }
        }
        let peak = m.emissive.max_element();
        let (factor, strength) = if peak > 1.0 {
            (m.emissive / peak, m.emissive_strength * peak)
        } else {
            (m.emissive, m.emissive_strength)
        };
        mat["emissiveFactor"] = json!(factor.to_array());
        if let Some(t) = tex(m.emissive_texture)? {
            mat["emissiveTexture"] = t;
        }
        if let Some(t) = tex(m.normal_texture)? {
            mat["normalTexture"] = t;
        }
        let mut ext = Map::new();
        if strength != 1.0 {
            ext.insert(
                "KHR_materials_emissive_strength".into(),
                json!({"emissiveStrength": strength}),
            );
        }
        if m.transmission != 0.0 {
            ext.insert(
                "KHR_materials_transmission".into(),
                json!({"transmissionFactor": m.transmission}),
            );
        }
        if m.ior != 1.5 {
            ext.insert("KHR_materials_ior".into(), json!({"ior": m.ior}));
        }
        if m.thickness > 0.0 {
            ext.insert(
                "KHR_materials_volume".into(),
                json!({"thicknessFactor": m.thickness}),
            );
        }
        for key in ext.keys() {
            add_used(key);
        }
        if !ext.is_empty() {
            mat["extensions"] = Value::Object(ext);
        }
        materials.push(mat);
    }
    Ok(materials)
}

fn transform_json(t: UvTransform) -> Value {
    json!({
        "offset": t.offset.to_array(),
        "rotation": t.rotation,
        "scale": t.scale.to_array(),
    })
}
