//! Serialisation of the builder's materials: factors, alpha mode and cutoff, textures with
//! `KHR_texture_transform`, and the material extensions (emissive strength, transmission, IOR).

use serde_json::{Map, Value, json};

use super::write::{check_finite, invalid};
use super::{SceneBuilder, TextureHandle};
use crate::error::Result;
use crate::model::{AlphaMode, UvTransform};

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
