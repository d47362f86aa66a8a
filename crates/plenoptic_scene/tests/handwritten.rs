//! A small glTF written by hand (not by our builder), in the spirit of Khronos' `Box.gltf`:
//! an embedded base64 buffer, a node matrix, the extensions plenoptic reads, two scenes.

#![allow(
    clippy::excessive_precision,
    reason = "hand-computed constants, written to 8 digits"
)]
use std::f32::consts::FRAC_1_SQRT_2;

use glam::{Quat, Vec3, Vec4};
use plenoptic_scene::{LightKind, load};

/// Buffer (108 bytes): positions of the unit square in the xy plane (0..48), normals +Z
/// (48..96), u16 indices 0 1 2 0 2 3 (96..108).
const GLTF: &str = r#"{
  "asset": {"version": "2.0", "generator": "hand"},
  "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_emissive_strength"],
  "scene": 0,
  "scenes": [{"nodes": [0, 2, 3]}, {"nodes": [4]}],
  "nodes": [
    {"name": "Root", "children": [1],
     "matrix": [0, 0, -2, 0,  0, 2, 0, 0,  2, 0, 0, 0,  0, 0, -1, 1]},
    {"name": "Quad", "mesh": 0, "translation": [0.5, 0, 0]},
    {"name": "Lamp", "mesh": 1, "translation": [0, 3, 0],
     "rotation": [-0.70710678, 0, 0, 0.70710678],
     "extensions": {"KHR_lights_punctual": {"light": 0}}},
    {"camera": 0, "translation": [0, 1, 5]},
    {"name": "Other", "mesh": 0}
  ],
  "meshes": [
    {"name": "square", "primitives": [
      {"attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 2, "material": 0}
    ]},
    {"name": "tri", "primitives": [{"attributes": {"POSITION": 3}}]}
  ],
  "materials": [
    {"name": "Orange", "doubleSided": true,
     "pbrMetallicRoughness": {"baseColorFactor": [1, 0.5, 0, 1], "metallicFactor": 0,
                              "roughnessFactor": 0.4},
     "emissiveFactor": [1, 1, 1],
     "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 5}}}
  ],
  "cameras": [{"type": "perspective", "name": "view",
               "perspective": {"yfov": 0.7, "aspectRatio": 1.5, "znear": 0.1}}],
  "extensions": {"KHR_lights_punctual": {"lights": [
    {"type": "spot", "name": "downlight", "color": [1, 0.9, 0.8], "intensity": 10, "range": 7,
     "spot": {"innerConeAngle": 0.1, "outerConeAngle": 0.5}}
  ]}},
  "accessors": [
    {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
     "min": [0, 0, 0], "max": [1, 1, 0]},
    {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3"},
    {"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"},
    {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
     "min": [0, 0, 0], "max": [1, 1, 0]}
  ],
  "bufferViews": [
    {"buffer": 0, "byteOffset": 0, "byteLength": 48, "target": 34962},
    {"buffer": 0, "byteOffset": 48, "byteLength": 48, "target": 34962},
    {"buffer": 0, "byteOffset": 96, "byteLength": 12, "target": 34963}
  ],
  "buffers": [{"byteLength": 108, "uri": "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAACAPwAAgD8AAAAAAAAAAAAAgD8AAAAAAAAAAAAAAAAAAIA/AAAAAAAAAAAAAIA/AAAAAAAAAAAAAIA/AAAAAAAAAAAAAIA/AAABAAIAAAACAAMA"}]
}"#;

#[test]
fn hand_written_gltf_imports() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("box.gltf");
    std::fs::write(&path, GLTF).unwrap();
    let scene = load(&path).unwrap();
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);

    // Default scene only; unnamed nodes are called node{index}.
    let names: Vec<&str> = scene.nodes.iter().map(|n| n.name.as_str()).collect();
    assert_eq!(names, ["Root", "Quad", "Lamp", "node3"]);
    assert_eq!(scene.nodes[1].parent, Some(0));

    // The matrix decomposes into scale 2, 90° about y, translation (0, 0, -1).
    let root = scene.nodes[0].rest;
    assert!(root.scale.abs_diff_eq(Vec3::splat(2.0), 1e-6));
    assert!(root.rotation.abs_diff_eq(
        Quat::from_xyzw(0.0, FRAC_1_SQRT_2, 0.0, FRAC_1_SQRT_2),
        1e-6
    ));
    assert!(
        root.translation
            .abs_diff_eq(Vec3::new(0.0, 0.0, -1.0), 1e-6)
    );

    // Objects: the square under Root, the triangle at the lamp.
    assert_eq!(scene.objects.len(), 2);
    let quad = &scene.objects[0];
    assert_eq!(
        (quad.name.as_str(), quad.node_path.as_str()),
        ("Quad", "/Root/Quad")
    );
    let mesh = &scene.meshes[quad.mesh];
    assert_eq!(mesh.triangles, vec![[0, 1, 2], [0, 2, 3]]);
    assert_eq!(mesh.positions[2], Vec3::new(1.0, 1.0, 0.0));
    assert_eq!(mesh.normals, vec![Vec3::Z; 4]);
    assert!(mesh.uvs.is_empty() && mesh.tangents.is_empty());
    // Vertex (1, 1, 0): child offset → (1.5, 1, 0); ×2 → (3, 2, 0); x → −z → (0, 2, −3);
    // plus (0, 0, −1).
    let world = scene
        .object_transform(0, 0.0)
        .transform_point3(mesh.positions[2]);
    assert!(
        world.abs_diff_eq(Vec3::new(0.0, 2.0, -4.0), 1e-5),
        "{world}"
    );

    let material = &scene.materials[quad.material];
    assert_eq!(material.name, "Orange");
    assert_eq!(material.base_color, Vec4::new(1.0, 0.5, 0.0, 1.0));
    assert_eq!((material.metallic, material.roughness), (0.0, 0.4));
    assert_eq!(material.emissive, Vec3::splat(5.0));
    assert!(material.double_sided);
    assert_eq!((material.transmission, material.ior), (0.0, 1.5));

    // The triangle has no normals (computed: +Z), no indices and glTF's default material.
    let tri = &scene.objects[1];
    assert_eq!(tri.name, "Lamp");
    let tri_mesh = &scene.meshes[tri.mesh];
    assert_eq!(tri_mesh.triangles, vec![[0, 1, 2]]);
    assert_eq!(tri_mesh.normals, vec![Vec3::Z; 3]);
    let default = &scene.materials[tri.material];
    assert_eq!((default.metallic, default.roughness), (1.0, 1.0));

    let light = &scene.lights[0];
    assert_eq!(light.name, "downlight");
    assert_eq!(
        light.kind,
        LightKind::Spot {
            inner_cone_angle: 0.1,
            outer_cone_angle: 0.5
        }
    );
    assert_eq!((light.intensity, light.range), (10.0, Some(7.0)));
    assert_eq!(light.color, Vec3::new(1.0, 0.9, 0.8));
    let placed = scene.placed_light(0, 0.0);
    assert!(placed.position.abs_diff_eq(Vec3::new(0.0, 3.0, 0.0), 1e-6));
    assert!(
        placed.direction.abs_diff_eq(Vec3::NEG_Y, 1e-6),
        "{}",
        placed.direction
    );

    let camera = &scene.cameras[0];
    assert_eq!(
        (camera.name.as_str(), camera.yfov, camera.aspect_ratio),
        ("view", 0.7, Some(1.5))
    );
    assert_eq!(scene.nodes[camera.node].name, "node3");
}
