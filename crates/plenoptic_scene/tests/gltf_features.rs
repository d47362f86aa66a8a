//! The glTF features of architectural exports: `alphaMode`/`alphaCutoff`,
//! `KHR_texture_transform`, sampler wrap modes and `COLOR_0`, through the builder (round trip)
//! and through hand-written files (encodings, malformed input, warnings).

mod common;

use common::{expect_error, f32_bytes, triangle, try_load};
use glam::{Vec2, Vec3, Vec4};
use plenoptic_scene::builder::shapes::plane;
use plenoptic_scene::builder::{MaterialDesc, SceneBuilder};
use plenoptic_scene::{AlphaMode, Scene, UvTransform, WrapMode, load_slice};
use serde_json::{Value, json};

fn close4(a: Vec4, b: Vec4, eps: f32) -> bool {
    a.abs_diff_eq(b, eps)
}

/// A builder scene: a textured quad with vertex colours under a MASK material with a texture
/// transform on all its textures, and a BLEND pane.
fn featured() -> SceneBuilder {
    let mut b = SceneBuilder::new();
    let rgba: Vec<u8> = vec![
        255, 255, 255, 255, 0, 0, 0, 0, //
        128, 128, 128, 64, 255, 0, 0, 255,
    ];
    let tex = b.add_texture_rgba8(2, 2, rgba);
    b.set_texture_wrap(tex, WrapMode::ClampToEdge, WrapMode::MirroredRepeat)
        .unwrap();
    let plain = b.add_texture_rgba8(1, 1, vec![128, 128, 255, 255]);
    let transform = UvTransform {
        offset: Vec2::new(0.25, -0.5),
        rotation: 0.3,
        scale: Vec2::new(2.0, 0.5),
    };
    let cut = b.add_material(
        MaterialDesc::diffuse(Vec3::ONE)
            .named("leaves")
            .base_color_texture(tex)
            .normal_texture(plain)
            .emissive_texture(plain)
            .alpha_mode(AlphaMode::Mask { cutoff: 0.3 })
            .texture_transform(transform),
    );
    let glass = b.add_material(
        MaterialDesc::diffuse(Vec3::splat(0.9))
            .named("glass")
            .base_color_alpha(Vec4::new(0.9, 0.9, 0.9, 0.12))
            .alpha_mode(AlphaMode::Blend),
    );
    let mut quad = plane(Vec2::ONE, 1);
    quad.colors = (0..quad.positions.len())
        .map(|i| Vec4::new(1.0, 0.5, i as f32 / 8.0, 0.75))
        .collect();
    b.add_object("Leaves", quad, cut, Default::default());
    b.add_object("Pane", plane(Vec2::ONE, 1), glass, Default::default());
    b
}

#[test]
fn builder_round_trip_keeps_alpha_transforms_wraps_and_colours() {
    let b = featured();
    let scene = b.build_scene().unwrap();
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    let leaves =
        &scene.materials[scene.objects[scene.object_by_name("Leaves").unwrap() as usize].material];
    assert_eq!(leaves.alpha_mode, AlphaMode::Mask { cutoff: 0.3 });
    let base = leaves.base_color_texture.unwrap();
    assert_eq!(
        (base.wrap_s, base.wrap_t),
        (WrapMode::ClampToEdge, WrapMode::MirroredRepeat)
    );
    for r in [
        base,
        leaves.normal_texture.unwrap(),
        leaves.emissive_texture.unwrap(),
    ] {
        assert!(r.transform.offset.abs_diff_eq(Vec2::new(0.25, -0.5), 1e-6));
        assert!((r.transform.rotation - 0.3).abs() < 1e-6);
        assert!(r.transform.scale.abs_diff_eq(Vec2::new(2.0, 0.5), 1e-6));
    }
    let normal = leaves.normal_texture.unwrap();
    assert_eq!(
        (normal.wrap_s, normal.wrap_t),
        (WrapMode::Repeat, WrapMode::Repeat)
    );
    // Texture alpha survives as linear alpha (not sRGB-decoded).
    let texels = &scene.textures[base.texture].texels;
    assert!((texels[1].w - 0.0).abs() < 1e-6 && (texels[2].w - 64.0 / 255.0).abs() < 1e-6);

    let mesh = &scene.meshes[scene.objects[0].mesh];
    assert_eq!(mesh.colors.len(), mesh.positions.len());
    for (i, c) in mesh.colors.iter().enumerate() {
        assert!(close4(*c, Vec4::new(1.0, 0.5, i as f32 / 8.0, 0.75), 1e-6));
    }
    let pane = &scene.materials[scene.objects[1].material];
    assert_eq!(pane.alpha_mode, AlphaMode::Blend);
    assert!((pane.base_color.w - 0.12).abs() < 1e-6);
    assert!(scene.meshes[scene.objects[1].mesh].colors.is_empty());

    let text = b.to_gltf_string().unwrap();
    let doc: Value = serde_json::from_str(&text).unwrap();
    assert!(
        doc["extensionsUsed"]
            .as_array()
            .unwrap()
            .contains(&json!("KHR_texture_transform"))
    );
    assert_eq!(doc["samplers"][0], json!({"wrapS": 33071, "wrapT": 33648}));
}

#[test]
fn builder_rejects_bad_colours_and_cutoffs() {
    let mut b = SceneBuilder::new();
    let m = b.add_material(MaterialDesc::default());
    let mut quad = plane(Vec2::ONE, 1);
    quad.colors = vec![Vec4::ONE; 2];
    b.add_object("Q", quad, m, Default::default());
    let e = b.build_scene().unwrap_err().to_string();
    assert!(e.contains("2 colors for 4 positions"), "{e}");

    let mut b = SceneBuilder::new();
    let m = b.add_material(MaterialDesc::default().alpha_mode(AlphaMode::Mask { cutoff: -1.0 }));
    b.add_object("Q", plane(Vec2::ONE, 1), m, Default::default());
    let e = b.build_scene().unwrap_err().to_string();
    assert!(e.contains("alpha cutoff -1"), "{e}");
}

/// The base triangle with a COLOR_0 accessor (index 2) of `component_type`, `ty`, normalised
/// or not, over `bytes`, declaring `count` elements.
fn with_colors(
    component_type: u32,
    ty: &str,
    normalized: bool,
    bytes: &[u8],
    count: usize,
) -> (Value, Vec<u8>) {
    let (mut doc, mut bin) = triangle();
    let offset = bin.len();
    bin.extend_from_slice(bytes);
    while bin.len() % 4 != 0 {
        bin.push(0);
    }
    doc["buffers"][0]["byteLength"] = json!(bin.len());
    doc["bufferViews"]
        .as_array_mut()
        .unwrap()
        .push(json!({"buffer": 0, "byteOffset": offset, "byteLength": bytes.len()}));
    doc["accessors"].as_array_mut().unwrap().push(json!({
        "bufferView": 2, "componentType": component_type, "count": count, "type": ty,
        "normalized": normalized
    }));
    doc["meshes"][0]["primitives"][0]["attributes"]["COLOR_0"] = json!(2);
    (doc, bin)
}

fn colors(scene: &Scene) -> &[Vec4] {
    &scene.meshes[0].colors
}

#[test]
fn color_0_in_every_encoding() {
    // Normalised unsigned bytes, RGBA.
    let (doc, bin) = with_colors(
        5121,
        "VEC4",
        true,
        &[255, 0, 51, 255, 0, 255, 0, 128, 0, 0, 255, 0],
        3,
    );
    let scene = try_load(&doc, &bin).unwrap();
    let c = colors(&scene);
    assert!(close4(c[0], Vec4::new(1.0, 0.0, 0.2, 1.0), 1e-6));
    assert!(close4(c[1], Vec4::new(0.0, 1.0, 0.0, 128.0 / 255.0), 1e-6));
    assert!(close4(c[2], Vec4::new(0.0, 0.0, 1.0, 0.0), 1e-6));

    // Normalised unsigned shorts, RGB: alpha is 1.
    let shorts: Vec<u8> = [65535u16, 0, 0, 0, 32768, 0, 0, 0, 65535]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let (doc, bin) = with_colors(5123, "VEC3", true, &shorts, 3);
    let scene = try_load(&doc, &bin).unwrap();
    let c = colors(&scene);
    assert!(close4(
        c[1],
        Vec4::new(0.0, 32768.0 / 65535.0, 0.0, 1.0),
        1e-6
    ));
    assert!(close4(c[2], Vec4::new(0.0, 0.0, 1.0, 1.0), 1e-6));

    // Floats, RGBA.
    let floats = f32_bytes(&[
        0.25, 0.5, 0.75, 0.5, 1.0, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.25,
    ]);
    let (doc, bin) = with_colors(5126, "VEC4", false, &floats, 3);
    let scene = try_load(&doc, &bin).unwrap();
    let c = colors(&scene);
    assert!(close4(c[0], Vec4::new(0.25, 0.5, 0.75, 0.5), 1e-7));
    assert!(close4(c[2], Vec4::new(0.0, 0.0, 0.0, 0.25), 1e-7));
}

#[test]
fn malformed_color_0_is_an_error_naming_the_accessor() {
    let floats = f32_bytes(&[0.5; 12]);
    let (doc, bin) = with_colors(5126, "VEC4", false, &floats, 2);
    expect_error(
        &doc,
        &bin,
        &["accessor 2", "COLOR_0 has 2 elements for 3 positions"],
    );

    let (doc, bin) = with_colors(5121, "VEC4", false, &[9; 12], 3);
    expect_error(&doc, &bin, &["accessor 2", "COLOR_0", "U8"]);

    let (doc, bin) = with_colors(5126, "VEC2", false, &floats[..24], 3);
    expect_error(&doc, &bin, &["accessor 2", "COLOR_0 must be Vec3 or Vec4"]);

    let bad = f32_bytes(&[0.5, 0.5, 0.5, 2.0, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5]);
    let (doc, bin) = with_colors(5126, "VEC4", false, &bad, 3);
    expect_error(&doc, &bin, &["accessor 2", "outside [0, 1]"]);

    // Too short for its count: the accessor bounds check, not a panic.
    let (doc, bin) = with_colors(5126, "VEC4", false, &floats[..40], 3);
    expect_error(&doc, &bin, &["accessor 2"]);
}

fn with_material(material: Value) -> (Value, Vec<u8>) {
    let (mut doc, bin) = triangle();
    doc["materials"] = json!([material]);
    doc["meshes"][0]["primitives"][0]["material"] = json!(0);
    (doc, bin)
}

#[test]
fn alpha_modes_and_cutoffs() {
    let (doc, bin) = with_material(json!({"alphaMode": "MASK"}));
    let scene = try_load(&doc, &bin).unwrap();
    assert_eq!(
        scene.materials[0].alpha_mode,
        AlphaMode::Mask { cutoff: 0.5 }
    );

    let (doc, bin) = with_material(json!({"alphaMode": "BLEND", "alphaCutoff": 0.2}));
    let scene = try_load(&doc, &bin).unwrap();
    assert_eq!(scene.materials[0].alpha_mode, AlphaMode::Blend);

    let (doc, bin) =
        with_material(json!({"name": "Fence", "alphaMode": "MASK", "alphaCutoff": -0.5}));
    expect_error(&doc, &bin, &["material 0 'Fence'", "alphaCutoff -0.5"]);

    let (doc, bin) = with_material(json!({"alphaMode": "MASK", "alphaCutoff": 1.5}));
    let scene = try_load(&doc, &bin).unwrap();
    assert!(
        scene.warnings[0].contains("material 0: alphaCutoff 1.5"),
        "{:?}",
        scene.warnings
    );

    let (doc, bin) = with_material(json!({"alphaMode": "SOMETIMES"}));
    expect_error(&doc, &bin, &["alphaMode"]);
}

/// The featured builder scene as glTF JSON, edited by `edit`, then loaded.
fn edited(edit: impl FnOnce(&mut Value)) -> Result<Scene, plenoptic_scene::SceneError> {
    let mut doc: Value = serde_json::from_str(&featured().to_gltf_string().unwrap()).unwrap();
    edit(&mut doc);
    let text = serde_json::to_string(&doc).unwrap();
    load_slice(text.as_bytes(), "house.gltf", None)
}

#[test]
fn texture_transform_texcoord_override_and_bad_values() {
    let scene = edited(|doc| {
        doc["materials"][0]["normalTexture"]["extensions"]["KHR_texture_transform"] =
            json!({"offset": [0.5, 0.5], "texCoord": 1});
    })
    .unwrap();
    let normal = scene.materials[0].normal_texture.unwrap();
    assert_eq!(normal.transform.offset, Vec2::splat(0.5));
    assert_eq!(normal.transform.scale, Vec2::ONE);
    assert_eq!(normal.transform.rotation, 0.0);
    assert!(
        scene
            .warnings
            .iter()
            .any(|w| w.contains("material 0 'leaves': normal texture uses TEXCOORD_1")),
        "{:?}",
        scene.warnings
    );

    let e = edited(|doc| {
        doc["materials"][0]["normalTexture"]["extensions"]["KHR_texture_transform"] =
            json!({"scale": [1.0]});
    })
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("house.gltf")
            && e.contains("normal texture: KHR_texture_transform")
            && e.contains("scale"),
        "{e}"
    );

    let e = edited(|doc| {
        doc["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["extensions"]
            ["KHR_texture_transform"]["rotation"] = json!("a quarter turn");
    })
    .unwrap_err()
    .to_string();
    assert!(e.contains("house.gltf"), "{e}");
}

#[test]
fn unsupported_extensions_warn_naming_the_element_and_required_ones_fail() {
    let scene = edited(|doc| {
        doc["materials"][1]["extensions"] =
            json!({"KHR_materials_volume": {"thicknessFactor": 0.01},
                   "KHR_materials_clearcoat": {"clearcoatFactor": 1.0}});
        doc["extensionsUsed"] = json!([
            "KHR_texture_transform",
            "KHR_materials_volume",
            "KHR_materials_clearcoat",
            "EXT_mesh_gpu_instancing"
        ]);
    })
    .unwrap();
    let w = scene.warnings.join("\n");
    assert!(
        w.contains("extensionsUsed: KHR_materials_clearcoat is not supported and is ignored (used by material 1 'glass')"),
        "{w}"
    );
    // The volume is read: the glass is a solid 1 cm thick rather than a thin wall.
    assert!(!w.contains("KHR_materials_volume"), "{w}");
    assert_eq!(scene.materials[1].thickness, 0.01);
    assert!(
        w.contains("EXT_mesh_gpu_instancing is not supported"),
        "{w}"
    );
    assert!(!w.contains("KHR_texture_transform"), "{w}");

    let e = edited(|doc| {
        doc["extensionsUsed"] = json!(["KHR_texture_transform", "KHR_materials_clearcoat"]);
        doc["extensionsRequired"] = json!(["KHR_materials_clearcoat"]);
    })
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("house.gltf") && e.contains("extensionsRequired"),
        "{e}"
    );

    // Requiring the texture transform is fine: it is read.
    let scene = edited(|doc| {
        doc["extensionsRequired"] = json!(["KHR_texture_transform"]);
    })
    .unwrap();
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
}

#[test]
fn nearest_filtering_warns() {
    let scene = edited(|doc| {
        doc["samplers"][0]["magFilter"] = json!(9728);
    })
    .unwrap();
    assert!(
        scene
            .warnings
            .iter()
            .any(|w| w
                .contains("material 0 'leaves': base colour texture: texture 0 asks for NEAREST")),
        "{:?}",
        scene.warnings
    );
}
