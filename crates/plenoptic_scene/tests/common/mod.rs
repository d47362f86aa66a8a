//! Helpers shared by the integration tests that write glTF by hand: base64 buffers, a base
//! triangle document, and loading with an expected error.
#![allow(dead_code)]

use std::path::PathBuf;

use plenoptic_scene::{Scene, SceneError, load};
use serde_json::{Value, json};

pub fn base64(data: &[u8]) -> String {
    const A: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for c in data.chunks(3) {
        let n = (u32::from(c[0]) << 16)
            | (u32::from(*c.get(1).unwrap_or(&0)) << 8)
            | u32::from(*c.get(2).unwrap_or(&0));
        for i in 0..4 {
            out.push(if i <= c.len() {
                A[(n >> (18 - 6 * i) & 63) as usize] as char
            } else {
                '='
            });
        }
    }
    out
}

/// One triangle: accessor 0 positions (view 0, 36 bytes), accessor 1 u16 indices (view 1).
pub fn triangle() -> (Value, Vec<u8>) {
    let mut bin: Vec<u8> = [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    bin.extend([0u16, 1, 2].iter().flat_map(|v| v.to_le_bytes()));
    bin.extend([0, 0]);
    let doc = json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"name": "Tri", "mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
             "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}
        ],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 36},
            {"buffer": 0, "byteOffset": 36, "byteLength": 6}
        ],
        "buffers": [{"byteLength": 44}]
    });
    (doc, bin)
}

/// Writes `doc` as `scene.gltf` in a fresh directory, with `bin` embedded as a data: URI.
pub fn write(doc: &Value, bin: &[u8]) -> (tempfile::TempDir, PathBuf) {
    let mut doc = doc.clone();
    if doc["buffers"].is_array() && doc["buffers"][0].get("uri").is_none() {
        doc["buffers"][0]["uri"] = json!(format!(
            "data:application/octet-stream;base64,{}",
            base64(bin)
        ));
    }
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("scene.gltf");
    std::fs::write(&path, serde_json::to_string_pretty(&doc).unwrap()).unwrap();
    (dir, path)
}

pub fn try_load(doc: &Value, bin: &[u8]) -> Result<Scene, SceneError> {
    let (_dir, path) = write(doc, bin);
    load(&path)
}

/// Loads and expects an error whose message names the file and contains every `needle`.
pub fn expect_error(doc: &Value, bin: &[u8], needles: &[&str]) -> SceneError {
    let err = try_load(doc, bin).expect_err("malformed input must fail");
    let msg = err.to_string();
    assert!(msg.contains("scene.gltf"), "names the file: {msg}");
    for needle in needles {
        assert!(msg.contains(needle), "expected {needle:?} in: {msg}");
    }
    err
}

pub fn f32_bytes(values: &[f32]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}
