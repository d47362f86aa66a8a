//! Malformed glTF must give a `SceneError` naming the file and the element, never a panic;
//! unsupported features give warnings naming the node.

mod common;

use std::path::Path;

use common::{expect_error, f32_bytes, triangle, try_load, write};
use plenoptic_scene::{SceneError, load};
use serde_json::{Value, json};

#[test]
fn the_base_triangle_loads() {
    let (doc, bin) = triangle();
    let scene = try_load(&doc, &bin).unwrap();
    assert_eq!(scene.meshes[0].triangles, vec![[0, 1, 2]]);
}

#[test]
fn missing_buffer_file() {
    let (mut doc, bin) = triangle();
    doc["buffers"][0]["uri"] = json!("missing%20data.bin");
    let err = expect_error(&doc, &bin, &["buffer 0", "missing data.bin"]);
    assert!(matches!(err, SceneError::Resource { .. }));
}

#[test]
fn external_buffer_file_loads() {
    let (mut doc, bin) = triangle();
    doc["buffers"][0]["uri"] = json!("tri.bin");
    let (dir, path) = write(&doc, &bin);
    std::fs::write(dir.path().join("tri.bin"), &bin).unwrap();
    assert_eq!(load(&path).unwrap().objects.len(), 1);
}

#[test]
fn buffer_data_too_short() {
    let (mut doc, bin) = triangle();
    doc["buffers"][0]["byteLength"] = json!(4400);
    expect_error(&doc, &bin, &["buffer 0", "4400", "44 bytes"]);
}

#[test]
fn bad_base64() {
    let (mut doc, bin) = triangle();
    doc["buffers"][0]["uri"] = json!("data:application/octet-stream;base64,AA!A");
    expect_error(&doc, &bin, &["buffer 0", "base64"]);
}

#[test]
fn index_out_of_range() {
    let (doc, mut bin) = triangle();
    bin[40..42].copy_from_slice(&7u16.to_le_bytes());
    expect_error(
        &doc,
        &bin,
        &["accessor 1: index 7 out of range for 3 vertices"],
    );
}

#[test]
fn recursive_nodes() {
    let (mut doc, bin) = triangle();
    doc["nodes"] = json!([{"name": "A", "children": [1]}, {"name": "B", "children": [0]}]);
    expect_error(&doc, &bin, &["is its own ancestor"]);

    doc["nodes"] = json!([{"name": "Self", "children": [0]}]);
    expect_error(&doc, &bin, &["node 0", "is its own ancestor"]);
}

#[test]
fn node_with_two_parents() {
    let (mut doc, bin) = triangle();
    doc["scenes"] = json!([{"nodes": [0, 1]}]);
    doc["nodes"] = json!([{"children": [2]}, {"children": [2]}, {"mesh": 0}]);
    expect_error(&doc, &bin, &["node 2", "more than one parent"]);
}

#[test]
fn root_that_is_a_child() {
    let (mut doc, bin) = triangle();
    doc["scenes"] = json!([{"nodes": [0, 1]}]);
    doc["nodes"] = json!([{"children": [1]}, {"mesh": 0}]);
    expect_error(&doc, &bin, &["scene 0", "node 1 is listed as a root"]);
}

#[test]
fn wrong_json_types() {
    let (mut doc, bin) = triangle();
    doc["accessors"][0]["count"] = json!("three");
    let err = expect_error(&doc, &bin, &["invalid type", "line"]);
    assert!(matches!(err, SceneError::Parse { .. }));

    let (_dir, path) = write(&json!({"asset": {"version": "2.0"}}), &[]);
    std::fs::write(&path, "{ not json").unwrap();
    assert!(load(&path).unwrap_err().to_string().contains("scene.gltf"));
}

#[test]
fn non_finite_positions() {
    let (doc, mut bin) = triangle();
    bin[12..16].copy_from_slice(&f32::NAN.to_le_bytes());
    expect_error(
        &doc,
        &bin,
        &["accessor 0", "POSITION", "non-finite", "element 1"],
    );
    let (doc, mut bin) = triangle();
    bin[32..36].copy_from_slice(&f32::INFINITY.to_le_bytes());
    expect_error(&doc, &bin, &["accessor 0", "non-finite", "element 2"]);
}

#[test]
fn no_scene() {
    let (mut doc, bin) = triangle();
    let root = doc.as_object_mut().unwrap();
    root.remove("scene");
    root.remove("scenes");
    expect_error(&doc, &bin, &["scene", "no scene"]);
}

#[test]
fn accessor_out_of_buffer_bounds() {
    let (mut doc, bin) = triangle();
    doc["accessors"][0]["count"] = json!(1000);
    expect_error(
        &doc,
        &bin,
        &["accessor 0", "1000 elements", "bufferView 0 of 36 bytes"],
    );

    // A count that would overflow or exhaust memory is refused before allocating.
    doc["accessors"][0]["count"] = json!(4_000_000_000u64);
    expect_error(&doc, &bin, &["accessor 0", "exceed bufferView"]);

    let (mut doc, bin) = triangle();
    doc["accessors"][0]["byteOffset"] = json!(8);
    expect_error(&doc, &bin, &["accessor 0", "offset 8"]);

    let (mut doc, bin) = triangle();
    doc["bufferViews"][0]["byteLength"] = json!(400);
    expect_error(
        &doc,
        &bin,
        &["bufferView 0", "exceeds buffer 0 of 44 bytes"],
    );
}

#[test]
fn unsupported_component_types() {
    // Not a glTF component type at all (5130 is GL_DOUBLE).
    let (mut doc, bin) = triangle();
    doc["accessors"][0]["componentType"] = json!(5130);
    expect_error(&doc, &bin, &["accessors[0].componentType"]);

    // A glTF type that positions may not use.
    let (mut doc, bin) = triangle();
    doc["accessors"][0]["componentType"] = json!(5123);
    expect_error(
        &doc,
        &bin,
        &["accessor 0", "unsupported component type U16 for POSITION"],
    );

    // Float indices.
    let (mut doc, bin) = triangle();
    doc["accessors"][1]["componentType"] = json!(5126);
    doc["accessors"][1]["count"] = json!(1);
    expect_error(
        &doc,
        &bin,
        &["accessor 1", "unsupported component type F32 for indices"],
    );
}

#[test]
fn indices_not_a_multiple_of_three() {
    let (mut doc, bin) = triangle();
    doc["accessors"][1]["count"] = json!(2);
    expect_error(&doc, &bin, &["accessor 1", "not a multiple of 3"]);
}

#[test]
fn truncated_glb() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("scene.glb");
    std::fs::write(&path, b"glTF\x02\0\0\0\xff\0\0\0").unwrap();
    let msg = load(&path).unwrap_err().to_string();
    assert!(msg.contains("scene.glb"), "{msg}");
}

#[test]
fn missing_file() {
    let err = load(Path::new("/nonexistent/scene.gltf")).unwrap_err();
    assert!(matches!(err, SceneError::Io { .. }));
    assert!(err.to_string().contains("scene.gltf"));
}

/// Animation sampler over the base buffer extended with `times` and `values`.
fn animated(times: &[f32], values: &[f32], interpolation: &str) -> (Value, Vec<u8>) {
    let (mut doc, mut bin) = triangle();
    let t0 = bin.len();
    bin.extend(f32_bytes(times));
    let v0 = bin.len();
    bin.extend(f32_bytes(values));
    doc["buffers"][0]["byteLength"] = json!(bin.len());
    let views = doc["bufferViews"].as_array_mut().unwrap();
    views.push(json!({"buffer": 0, "byteOffset": t0, "byteLength": times.len() * 4}));
    views.push(json!({"buffer": 0, "byteOffset": v0, "byteLength": values.len() * 4}));
    let accessors = doc["accessors"].as_array_mut().unwrap();
    accessors.push(
        json!({"bufferView": 2, "componentType": 5126, "count": times.len(), "type": "SCALAR"}),
    );
    accessors.push(
        json!({"bufferView": 3, "componentType": 5126, "count": values.len() / 3, "type": "VEC3"}),
    );
    doc["animations"] = json!([{
        "channels": [{"sampler": 0, "target": {"node": 0, "path": "translation"}}],
        "samplers": [{"input": 2, "output": 3, "interpolation": interpolation}]
    }]);
    (doc, bin)
}

#[test]
fn animation_times_must_increase_and_be_finite() {
    let (doc, bin) = animated(&[0.0, 1.0, 1.0], &[0.0; 9], "LINEAR");
    expect_error(
        &doc,
        &bin,
        &["accessor 2", "animation 0 channel 0", "increase strictly"],
    );
    let (doc, bin) = animated(&[0.0, f32::NAN], &[0.0; 6], "LINEAR");
    expect_error(&doc, &bin, &["accessor 2", "non-finite"]);
    // Cubic splines need three values per key.
    let (doc, bin) = animated(&[0.0, 1.0], &[0.0; 6], "CUBICSPLINE");
    expect_error(&doc, &bin, &["accessor 3", "2 output values for 2 keys"]);
    let (doc, bin) = animated(&[0.0, 1.0], &[0.0; 6], "LINEAR");
    assert!(try_load(&doc, &bin).unwrap().nodes[0].track.is_some());
}

#[test]
fn skin_and_morph_targets_warn_naming_the_node() {
    let (mut doc, mut bin) = triangle();
    // Morph target: displacement accessor reuses the positions; skin with one joint.
    doc["meshes"][0]["primitives"][0]["targets"] = json!([{"POSITION": 0}]);
    let ibm = bin.len();
    bin.extend(f32_bytes(&glam::Mat4::IDENTITY.to_cols_array()));
    doc["buffers"][0]["byteLength"] = json!(bin.len());
    doc["bufferViews"]
        .as_array_mut()
        .unwrap()
        .push(json!({"buffer": 0, "byteOffset": ibm, "byteLength": 64}));
    doc["accessors"]
        .as_array_mut()
        .unwrap()
        .push(json!({"bufferView": 2, "componentType": 5126, "count": 1, "type": "MAT4"}));
    doc["skins"] = json!([{"joints": [1], "inverseBindMatrices": 2}]);
    doc["nodes"] = json!([
        {"name": "Body", "mesh": 0, "skin": 0, "children": [1]},
        {"name": "Bone"}
    ]);
    let scene = try_load(&doc, &bin).unwrap();
    assert_eq!(scene.objects.len(), 1, "geometry kept at rest pose");
    let warnings = scene.warnings.join("\n");
    assert!(warnings.contains("node 'Body': skinning"), "{warnings}");
    assert!(
        warnings.contains("node 'Body': morph targets"),
        "{warnings}"
    );
}

#[test]
fn non_triangle_primitives_and_orthographic_cameras_warn() {
    let (mut doc, bin) = triangle();
    doc["meshes"][0]["primitives"][0]["mode"] = json!(1);
    doc["cameras"] = json!([{"type": "orthographic", "orthographic": {"xmag": 1, "ymag": 1, "znear": 0.1, "zfar": 10}}]);
    doc["nodes"][0]["camera"] = json!(0);
    let scene = try_load(&doc, &bin).unwrap();
    assert!(scene.objects.is_empty() && scene.cameras.is_empty());
    let warnings = scene.warnings.join("\n");
    assert!(
        warnings.contains("node 'Tri': mesh 0 primitive 0: mode Lines"),
        "{warnings}"
    );
    assert!(
        warnings.contains("node 'Tri': camera 0 is orthographic"),
        "{warnings}"
    );
}

#[test]
fn invalid_references_are_validation_errors() {
    let (mut doc, bin) = triangle();
    doc["nodes"][0]["mesh"] = json!(7);
    expect_error(&doc, &bin, &["nodes[0].mesh"]);
}

#[test]
fn sparse_accessors_substitute_and_check_their_indices() {
    let (mut doc, mut bin) = triangle();
    let i0 = bin.len();
    bin.extend([1u8, 0, 0, 0]);
    let v0 = bin.len();
    bin.extend(f32_bytes(&[2.0, 0.0, 0.0]));
    doc["buffers"][0]["byteLength"] = json!(bin.len());
    let views = doc["bufferViews"].as_array_mut().unwrap();
    views.push(json!({"buffer": 0, "byteOffset": i0, "byteLength": 1}));
    views.push(json!({"buffer": 0, "byteOffset": v0, "byteLength": 12}));
    doc["accessors"][0]["sparse"] = json!({
        "count": 1,
        "indices": {"bufferView": 2, "componentType": 5121},
        "values": {"bufferView": 3}
    });
    let scene = try_load(&doc, &bin).unwrap();
    assert_eq!(scene.meshes[0].positions[1], glam::Vec3::new(2.0, 0.0, 0.0));

    bin[i0] = 9;
    expect_error(
        &doc,
        &bin,
        &["accessor 0", "sparse index 9 out of range for 3 elements"],
    );
    doc["accessors"][0]["sparse"]["count"] = json!(50);
    expect_error(
        &doc,
        &bin,
        &["accessor 0", "sparse data of 50 elements exceeds"],
    );
}
