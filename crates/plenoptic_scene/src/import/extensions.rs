//! glTF extensions: which ones plenoptic reads, warnings that name the elements using the
//! others, and the document's raw JSON for extension data the `gltf` crate does not expose.
//!
//! Extensions listed in `extensionsRequired` that plenoptic does not read are rejected by the
//! `gltf` crate's validation (an error naming `extensionsRequired[i]`); ones only in
//! `extensionsUsed` are ignored with a warning per extension naming the materials, textures,
//! meshes, nodes, images and samplers that carry it.

use serde_json::Value;

/// The extensions the importer reads; every other one is ignored with a warning.
pub const SUPPORTED_EXTENSIONS: &[&str] = &[
    "KHR_lights_punctual",
    "KHR_materials_emissive_strength",
    "KHR_materials_transmission",
    "KHR_materials_ior",
    "KHR_materials_volume",
    "KHR_texture_transform",
];

/// The document's JSON as a generic value: the JSON chunk of a GLB or the whole text. `None`
/// when it cannot be had (the typed parse has already succeeded, so this does not happen for
/// valid input).
pub(super) fn raw_json(bytes: &[u8]) -> Option<Value> {
    if bytes.starts_with(b"glTF") {
        let glb = gltf::Glb::from_slice(bytes).ok()?;
        serde_json::from_slice(&glb.json).ok()
    } else {
        serde_json::from_slice(bytes).ok()
    }
}

/// Where extension `name` appears: element labels such as `material 2 'Glass'`.
fn users(raw: &Value, name: &str) -> Vec<String> {
    let mut out = Vec::new();
    for (key, label) in [
        ("materials", "material"),
        ("textures", "texture"),
        ("images", "image"),
        ("samplers", "sampler"),
        ("meshes", "mesh"),
        ("nodes", "node"),
        ("cameras", "camera"),
    ] {
        let Some(items) = raw.get(key).and_then(Value::as_array) else {
            continue;
        };
        for (i, item) in items.iter().enumerate() {
            if mentions(item, name, 0) {
                match item.get("name").and_then(Value::as_str) {
                    Some(n) => out.push(format!("{label} {i} '{n}'")),
                    None => out.push(format!("{label} {i}")),
                }
            }
        }
    }
    out
}

/// Whether `value` has an `extensions` object with key `name` at any depth (bounded: glTF
/// nests textureInfos two levels inside a material and primitives inside meshes).
fn mentions(value: &Value, name: &str, depth: u32) -> bool {
    if depth > 6 {
        return false;
    }
    match value {
        Value::Object(map) => {
            if map
                .get("extensions")
                .and_then(Value::as_object)
                .is_some_and(|e| e.contains_key(name))
            {
                return true;
            }
            map.values().any(|v| mentions(v, name, depth + 1))
        }
        Value::Array(items) => items.iter().any(|v| mentions(v, name, depth + 1)),
        _ => false,
    }
}

/// One warning per unsupported extension in `extensionsUsed`, naming the elements that use it.
pub(super) fn unsupported_warnings(document: &gltf::Document, raw: Option<&Value>) -> Vec<String> {
    let mut warnings = Vec::new();
    for name in document.extensions_used() {
        if SUPPORTED_EXTENSIONS.contains(&name) {
            continue;
        }
        let users = raw.map(|r| users(r, name)).unwrap_or_default();
        let place = if users.is_empty() {
            String::new()
        } else {
            const SHOWN: usize = 8;
            let more = users.len().saturating_sub(SHOWN);
            let mut list = users[..users.len().min(SHOWN)].join(", ");
            if more > 0 {
                list.push_str(&format!(" and {more} more"));
            }
            format!(" (used by {list})")
        };
        warnings.push(format!(
            "extensionsUsed: {name} is not supported and is ignored{place}"
        ));
    }
    warnings
}
