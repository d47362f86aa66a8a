//! Builder-made scenes through bytes and the importer: geometry, materials, lights, cameras,
//! hierarchy, object ids, names and paths.

use glam::{Quat, Vec2, Vec3, Vec4};
use plenoptic_scene::builder::{
    CameraDesc, LightDesc, MaterialDesc, NodeDesc, SceneBuilder, shapes,
};
use plenoptic_scene::{LightKind, Mesh, Scene, Track, Trs, load};

fn close(a: Vec3, b: Vec3) -> bool {
    a.abs_diff_eq(b, 1e-5)
}

/// A small house: floor, a house with a door (two primitives) and a window, a lamp, a camera.
fn house() -> SceneBuilder {
    let mut b = SceneBuilder::new();
    let white = b.add_material(MaterialDesc::diffuse(Vec3::splat(0.8)).named("white"));
    let glass = b.add_material(
        MaterialDesc::glass(1.45)
            .named("glass")
            .double_sided(true)
            .thickness(0.02),
    );
    let lamp = b.add_material(
        MaterialDesc::emitter(Vec3::new(1.0, 0.9, 0.8), 20.0)
            .named("lamp")
            .metallic(0.25)
            .roughness(0.75),
    );
    let gold = b.add_material(MaterialDesc::metal(Vec3::new(1.0, 0.8, 0.3), 0.2).named("gold"));
    let floor = b.add_plane("floor", Vec2::splat(10.0), 3, white);
    b.add_node(NodeDesc::new("Floor").mesh(floor));
    let house = b.add_node(
        NodeDesc::new("House")
            .translation(Vec3::new(1.0, 0.0, 0.0))
            .rotation(Quat::from_rotation_y(0.5))
            .as_matrix(),
    );
    let door = b.add_mesh_primitives(
        "door",
        vec![
            (shapes::cuboid(Vec3::new(1.0, 2.0, 0.1)), white),
            (shapes::cuboid(Vec3::splat(0.1)), gold),
        ],
    );
    b.add_node(
        NodeDesc::new("Door")
            .parent(house)
            .mesh(door)
            .translation(Vec3::Z),
    );
    let window = b.add_box("window", Vec3::new(1.0, 1.0, 0.02), glass);
    b.add_node(
        NodeDesc::new("Window")
            .parent(house)
            .mesh(window)
            .scale(Vec3::splat(2.0)),
    );
    let bulb = b.add_sphere("bulb", 0.1, 12, lamp);
    b.add_node(
        NodeDesc::new("Lamp")
            .mesh(bulb)
            .translation(Vec3::new(0.0, 3.0, 0.0))
            .light(
                LightDesc::point(Vec3::new(1.0, 0.5, 0.25), 100.0)
                    .named("bulb")
                    .range(20.0),
            ),
    );
    b.add_node(NodeDesc::new("Spot").parent(house).light(LightDesc::spot(
        Vec3::ONE,
        50.0,
        0.2,
        0.4,
    )));
    b.add_node(NodeDesc::new("Sun").light(LightDesc::directional(Vec3::ONE, 3.0)));
    b.add_node(
        NodeDesc::new("Eye")
            .translation(Vec3::new(0.0, 1.6, 5.0))
            .camera(CameraDesc::perspective(0.8).named("eye").aspect_ratio(1.5)),
    );
    b
}

fn check_house(scene: &Scene) {
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    // Depth first from the roots in document order: Floor, House, Door, Window, Spot, Lamp…
    let names: Vec<&str> = scene.nodes.iter().map(|n| n.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "Floor", "House", "Door", "Window", "Spot", "Lamp", "Sun", "Eye"
        ]
    );
    for (i, n) in scene.nodes.iter().enumerate() {
        assert!(n.parent.is_none_or(|p| p < i), "parents precede children");
    }
    let objects: Vec<(&str, &str)> = scene
        .objects
        .iter()
        .map(|o| (o.name.as_str(), o.node_path.as_str()))
        .collect();
    assert_eq!(
        objects,
        [
            ("Floor", "/Floor"),
            ("Door#0", "/House/Door"),
            ("Door#1", "/House/Door"),
            ("Window", "/House/Window"),
            ("Lamp", "/Lamp"),
        ]
    );
    let tris: Vec<usize> = scene
        .objects
        .iter()
        .map(|o| scene.meshes[o.mesh].triangles.len())
        .collect();
    assert_eq!(tris, [18, 12, 12, 12, 2 * 12 * 5]);
    assert_eq!(scene.triangle_count(), 18 + 36 + 120);

    let material = |object: &str| {
        &scene.materials[scene.objects[scene.object_by_name(object).unwrap() as usize].material]
    };
    let glass = material("Window");
    assert_eq!(glass.name, "glass");
    assert_eq!(
        (
            glass.transmission,
            glass.ior,
            glass.thickness,
            glass.double_sided
        ),
        (1.0, 1.45, 0.02, true)
    );
    let lamp = material("Lamp");
    // No KHR_materials_volume: glTF's thin-walled default.
    assert_eq!(lamp.thickness, 0.0);
    assert!(close(lamp.emissive, Vec3::new(20.0, 18.0, 16.0)));
    assert_eq!((lamp.metallic, lamp.roughness), (0.25, 0.75));
    assert_eq!(lamp.base_color, Vec4::new(0.0, 0.0, 0.0, 1.0));
    assert_eq!(material("Door#1").name, "gold");
    assert_eq!(material("Door#1").metallic, 1.0);
    assert_eq!(material("Floor").base_color, Vec4::new(0.8, 0.8, 0.8, 1.0));

    // Hierarchy: the door is 1 along the house's rotated z axis.
    let door = scene.object_by_name("Door#0").unwrap();
    let expect = Vec3::new(1.0, 0.0, 0.0) + Quat::from_rotation_y(0.5) * Vec3::Z;
    assert!(close(
        scene.object_transform(door, 0.0).translation.into(),
        expect
    ));
    let window = scene.object_by_name("Window").unwrap();
    let m = scene.object_transform(window, 0.0);
    assert!(close(
        m.transform_vector3(Vec3::X),
        Quat::from_rotation_y(0.5) * Vec3::X * 2.0
    ));
    assert!(!scene.object_is_animated(door));

    assert_eq!(scene.lights.len(), 3);
    let bulb = &scene.lights[scene.lights.iter().position(|l| l.name == "bulb").unwrap()];
    assert_eq!(bulb.kind, LightKind::Point);
    assert_eq!((bulb.intensity, bulb.range), (100.0, Some(20.0)));
    assert!(close(bulb.color, Vec3::new(1.0, 0.5, 0.25)));
    assert_eq!(scene.nodes[bulb.node].name, "Lamp");
    let spot = scene
        .lights
        .iter()
        .find(|l| matches!(l.kind, LightKind::Spot { .. }))
        .unwrap();
    assert_eq!(
        spot.kind,
        LightKind::Spot {
            inner_cone_angle: 0.2,
            outer_cone_angle: 0.4
        }
    );
    let sun = scene
        .lights
        .iter()
        .position(|l| l.kind == LightKind::Directional)
        .unwrap();
    assert!(close(scene.placed_light(sun, 0.0).direction, Vec3::NEG_Z));

    assert_eq!(scene.cameras.len(), 1);
    let cam = &scene.cameras[0];
    assert_eq!(
        (cam.name.as_str(), cam.yfov, cam.aspect_ratio),
        ("eye", 0.8, Some(1.5))
    );
    assert_eq!(scene.nodes[cam.node].name, "Eye");
}

#[test]
fn house_round_trips_through_glb_and_gltf() {
    let b = house();
    check_house(&b.build_scene().unwrap());

    let dir = tempfile::tempdir().unwrap();
    let glb = dir.path().join("house.glb");
    b.write_glb(&glb).unwrap();
    let from_glb = load(&glb).unwrap();
    check_house(&from_glb);
    let gltf = dir.path().join("house.gltf");
    b.write_gltf(&gltf).unwrap();
    let from_gltf = load(&gltf).unwrap();
    assert_eq!(from_glb, from_gltf, "both containers give the same scene");
    // Ids are stable: loading again gives the same objects.
    assert_eq!(load(&glb).unwrap().objects, from_glb.objects);
}

#[test]
fn geometry_survives_exactly() {
    let mut b = SceneBuilder::new();
    let m = b.add_material(MaterialDesc::default());
    let sphere = shapes::uv_sphere(2.0, 10);
    b.add_object("Ball", sphere.clone(), m, Trs::default());
    let scene = b.build_scene().unwrap();
    let mesh = &scene.meshes[0];
    assert!(mesh.positions == sphere.positions);
    assert!(mesh.uvs == sphere.uvs);
    assert!(mesh.triangles == sphere.triangles);
    // Normals are renormalised on import.
    assert!(
        mesh.normals
            .iter()
            .zip(&sphere.normals)
            .all(|(a, b)| close(*a, *b))
    );
}

#[test]
fn missing_normals_are_computed_and_big_spheres_work() {
    let mut b = SceneBuilder::new();
    let m = b.add_material(MaterialDesc::default());
    let mut tri = Mesh {
        positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
        triangles: vec![[0, 1, 2]],
        ..Mesh::default()
    };
    b.add_object("Tri", tri.clone(), m, Trs::default());
    let big = b.add_sphere("big", 1.0, 320, m);
    b.add_node(NodeDesc::new("Big").mesh(big));
    let scene = b.build_scene().unwrap();
    tri.normals = vec![Vec3::Z; 3];
    assert_eq!(scene.meshes[0], tri);
    assert!(scene.meshes[1].triangles.len() >= 100_000);
}

#[test]
fn builder_rejects_bad_input() {
    let mut b = SceneBuilder::new();
    let m = b.add_material(MaterialDesc::default());
    let mesh = Mesh {
        positions: vec![Vec3::ZERO, Vec3::X, Vec3::NAN],
        triangles: vec![[0, 1, 2]],
        ..Mesh::default()
    };
    b.add_object("Bad", mesh, m, Trs::default());
    let e = b.build_scene().unwrap_err().to_string();
    assert!(e.contains("'Bad'") && e.contains("non-finite"), "{e}");

    let mut b = SceneBuilder::new();
    let m = b.add_material(MaterialDesc::default());
    let mesh = Mesh {
        positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
        triangles: vec![[0, 1, 3]],
        ..Mesh::default()
    };
    b.add_object("Bad", mesh, m, Trs::default());
    let e = b.build_scene().unwrap_err().to_string();
    assert!(e.contains("index 3 out of range for 3 vertices"), "{e}");
}

#[test]
fn textures_import_in_their_colour_space() {
    let mut b = SceneBuilder::new();
    // 2×1: sRGB 188 ≈ linear 0.5; 255 → 1.
    let texture = b.add_texture_rgba8(2, 1, vec![188, 0, 255, 255, 255, 255, 255, 128]);
    let m = b.add_material(
        MaterialDesc::default()
            .base_color_texture(texture)
            .metallic_roughness_texture(texture)
            .normal_texture(texture),
    );
    b.add_object("Quad", shapes::plane(Vec2::ONE, 1), m, Trs::default());
    let scene = b.build_scene().unwrap();
    let mat = &scene.materials[0];
    let base = &scene.textures[mat.base_color_texture.unwrap().texture];
    let linear = &scene.textures[mat.metallic_roughness_texture.unwrap().texture];
    assert_eq!(
        mat.normal_texture, mat.metallic_roughness_texture,
        "one decode per colour space"
    );
    assert_eq!((base.width, base.height), (2, 1));
    assert!(
        (base.texels[0].x - 0.5029).abs() < 1e-3,
        "{}",
        base.texels[0]
    );
    assert!((linear.texels[0].x - 188.0 / 255.0).abs() < 1e-6);
    assert!(
        (base.texels[1].w - 128.0 / 255.0).abs() < 1e-6,
        "alpha stays linear"
    );
    // A normal map asks for tangents: computed from the UVs, perpendicular to the normal.
    let mesh = &scene.meshes[0];
    assert_eq!(mesh.tangents.len(), mesh.positions.len());
    for (t, n) in mesh.tangents.iter().zip(&mesh.normals) {
        assert!(t.truncate().dot(*n).abs() < 1e-5 && t.w.abs() == 1.0);
        assert!(close(t.truncate(), Vec3::X));
    }
}

#[test]
fn animated_builder_scene() {
    let mut b = SceneBuilder::new();
    let m = b.add_material(MaterialDesc::default());
    let node = b.add_object("Mover", shapes::cuboid(Vec3::ONE), m, Trs::default());
    b.animate_translation(node, Track::linear([(0.0, Vec3::ZERO), (1.0, Vec3::X)]))
        .animate_scale(
            node,
            Track::step([(0.0, Vec3::ONE), (0.5, Vec3::splat(2.0))]),
        );
    let scene = b.build_scene().unwrap();
    let id = scene.object_by_name("Mover").unwrap();
    assert!(scene.object_is_animated(id));
    assert_eq!(scene.animation_range(), (0.0, 1.0));
    let m = scene.object_transform(id, 0.75);
    assert!(close(m.translation.into(), Vec3::new(0.75, 0.0, 0.0)));
    assert!(close(
        m.transform_vector3(Vec3::X),
        Vec3::new(2.0, 0.0, 0.0)
    ));
}
