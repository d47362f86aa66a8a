//! The baker's materials (pack 1.2): a glTF scene with a textured material (a 64×64 checker
//! generated here) goes through the importer and the baker's material tables into a pack, and
//! comes back equal: factors, bindings with their transform, the texture's level 0 byte for
//! byte, its full mip chain gamma-correctly filtered, shared images stored once, and the
//! proxies' UVs and tangents.

mod common;

use glam::{Vec2, Vec3, Vec4};
use plenoptic_bake::materials::{pack_materials, proxy_attributes};
use plenoptic_bake::write::proxy_meshes;
use plenoptic_pack::texture::linear_to_srgb;
use plenoptic_pack::*;
use plenoptic_scene::builder::{MaterialDesc, NodeDesc, SceneBuilder};

fn checker(n: u32) -> Vec<u8> {
    (0..n * n)
        .flat_map(|i| {
            let v = if (i % n + i / n).is_multiple_of(2) {
                0
            } else {
                255
            };
            [v, v, v, 255]
        })
        .collect()
}

fn scene(dir: &std::path::Path) -> plenoptic_scene::Scene {
    let mut b = SceneBuilder::new();
    let tex = b.add_texture_rgba8(64, 64, checker(64));
    // The same pixels again as a second image: stored once.
    let copy = b.add_texture_rgba8(64, 64, checker(64));
    let mr: Vec<u8> = (0..16 * 16)
        .flat_map(|i| [0, i as u8, 255 - i as u8, 255])
        .collect();
    let mr = b.add_texture_rgba8(16, 16, mr);
    let normal = b.add_texture_rgba8(4, 4, [128u8, 128, 255, 255].repeat(16));
    let tiles = b.add_material(
        MaterialDesc::diffuse(Vec3::new(0.9, 0.8, 0.7))
            .named("tiles")
            .base_color_texture(tex)
            .metallic_roughness_texture(mr)
            .normal_texture(normal)
            .roughness(0.5)
            .texture_transform(plenoptic_scene::UvTransform {
                offset: Vec2::new(0.5, 0.0),
                rotation: 0.0,
                scale: Vec2::splat(4.0),
            }),
    );
    let other = b.add_material(
        MaterialDesc::emitter(Vec3::new(1.0, 0.5, 0.25), 3.0)
            .named("sign")
            .base_color_texture(copy)
            .emissive_texture(tex),
    );
    let floor = b.add_plane("floor", Vec2::splat(2.0), 2, tiles);
    let sign = b.add_box("sign", Vec3::new(1.0, 0.5, 0.1), other);
    b.add_node(NodeDesc::new("floor").mesh(floor));
    b.add_node(NodeDesc::new("sign").mesh(sign).translation(Vec3::Y));
    let path = dir.join("scene.glb");
    b.write_glb(&path).unwrap();
    plenoptic_scene::load(&path).unwrap()
}

#[test]
fn a_textured_scene_round_trips_through_the_pack() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene(dir.path());
    let mats = pack_materials(&scene).unwrap();
    let path = dir.path().join("m.pack");
    let mut w = PackWriter::create(&path).unwrap();
    for mesh in proxy_meshes(&scene) {
        w.add_proxy_mesh(&mesh).unwrap();
    }
    let attributes = proxy_attributes(&scene);
    for a in &attributes {
        w.add_proxy_attributes(a).unwrap();
    }
    for (i, image) in mats.images.iter().enumerate() {
        w.add_texture(i as u32, image).unwrap();
    }
    let mut m = Manifest::new(
        TimeRange {
            start: 0.0,
            end: 1.0,
        },
        1.0,
    );
    for (i, material) in mats.object_material.iter().enumerate() {
        m.objects.push(ObjectEntry {
            id: i as u32 + 1,
            name: scene.objects[i].name.clone(),
            node_path: scene.objects[i].node_path.clone(),
            motion: Motion::Static,
            proxy_mesh: Some(i as u32 + 1),
            material: *material,
            coverage: None,
        });
    }
    m.textures = mats.textures.clone();
    m.materials = mats.materials.clone();
    w.finish(&m).unwrap();
    let r = PackReader::open(&path).unwrap();

    // Textures: the checker once (sRGB), though two images and three slots of two materials
    // use it; then the metallic-roughness texture and the normal map (linear).
    let spaces: Vec<_> = r.textures().iter().map(|t| t.colour_space).collect();
    assert_eq!(
        spaces,
        [ColourSpace::Srgb, ColourSpace::Linear, ColourSpace::Linear]
    );
    let tiles = r.object_material(1).expect("floor has a material");
    assert_eq!(tiles.name, "tiles");
    assert_eq!(tiles.base_colour, Vec4::new(0.9, 0.8, 0.7, 1.0));
    assert_eq!(tiles.roughness, 0.5);
    let base = tiles.base_colour_texture.unwrap();
    assert_eq!(base.texture, 0);
    assert_eq!(
        base.transform,
        Some(UvTransform {
            offset: Vec2::new(0.5, 0.0),
            rotation: 0.0,
            scale: Vec2::splat(4.0),
        })
    );
    assert_eq!(tiles.metallic_roughness_texture.unwrap().texture, 1);
    assert_eq!(tiles.normal_texture.unwrap().texture, 2);
    let sign = r.object_material(2).expect("sign has a material");
    assert_eq!(sign.name, "sign");
    assert_eq!(sign.base_colour_texture.unwrap().texture, 0, "deduplicated");
    assert_eq!(sign.emissive_texture.unwrap().texture, 0, "deduplicated");
    assert!(
        (sign.emissive - Vec3::new(3.0, 1.5, 0.75))
            .abs()
            .max_element()
            < 1e-6
    );

    // The checker: level 0 exact, 7 levels, every coarser texel the linear-light mean.
    let t = r.texture(0).unwrap();
    assert_eq!(t.levels.len(), 7);
    assert_eq!(t.levels[0].texels, checker(64));
    let grey = 255.0 * linear_to_srgb(0.5);
    for level in &t.levels[1..] {
        for px in level.texels.chunks_exact(4) {
            assert!((px[0] as f32 - grey).abs() <= 1.0, "{px:?}");
            assert_eq!(px[3], 255);
        }
    }
    assert_eq!(r.texture(2).unwrap().levels.len(), 3);

    // UVs and tangents: one per proxy vertex, unit tangents with w = ±1.
    for o in &r.manifest().objects {
        let mesh = r.proxy_mesh(o.id).unwrap();
        let a = r.proxy_attributes(o.id).unwrap().expect("shapes have UVs");
        assert_eq!(a.uvs.len(), mesh.positions.len());
        assert_eq!(a.tangents.len(), mesh.positions.len());
        for (t, n) in a.tangents.iter().zip(mesh.normals.as_ref().unwrap()) {
            assert!((t.truncate().length() - 1.0).abs() < 1e-4);
            assert!(t.truncate().dot(*n).abs() < 1e-4, "tangent ⟂ normal");
        }
    }
    let floor = scene.object_by_name("floor").unwrap() as usize;
    assert_eq!(
        attributes[floor].uvs,
        scene.meshes[scene.objects[floor].mesh].uvs
    );
}

#[test]
fn a_bake_of_a_textured_scene_writes_its_textures() {
    let dir = tempfile::tempdir().unwrap();
    let mut b = common::static_room();
    let tex = b.add_texture_rgba8(64, 64, checker(64));
    let tiles = b.add_material(MaterialDesc::diffuse(Vec3::ONE).base_color_texture(tex));
    let floor = b.add_plane("rug", Vec2::splat(1.5), 1, tiles);
    b.add_node(
        NodeDesc::new("rug")
            .mesh(floor)
            .translation(Vec3::new(0.0, -1.9, 0.0)),
    );
    let recipe = common::write_recipe(dir.path(), &b, common::STATIC_SEGMENT, "q = 0.0");
    plenoptic_bake::bake_recipe(&recipe, &plenoptic_bake::BakeOptions::default()).unwrap();
    let pack = PackReader::open(dir.path().join("out/scene.pack")).unwrap();
    let m = pack.manifest();
    assert_eq!(pack.textures().len(), 1);
    let rug = m.objects.iter().find(|o| o.name == "rug").unwrap();
    let material = pack.object_material(rug.id).unwrap();
    assert_eq!(material.base_colour_texture.unwrap().texture, 0);
    let t = pack.texture(0).unwrap();
    assert_eq!(t.levels.len(), 7);
    assert_eq!(t.levels[0].texels, checker(64));
    assert!(m.stats.bytes["textures"] > 0);
    eprintln!(
        "textured static room: pack {} bytes, texture chunk {} bytes, attributes {} bytes",
        pack.file_length(),
        m.stats.bytes["textures"],
        m.stats.bytes["proxy_attributes"]
    );
}
