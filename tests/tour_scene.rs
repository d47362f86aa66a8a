//! The architectural tour (`examples/architectural_tour`): the scene generator, the committed
//! `tour.glb`, the bake recipe and the camera path agree with each other and with what the
//! tour promises (rooms, atrium, daylight, mirror, glass, columns, furniture, moving things).

#[allow(dead_code)]
#[path = "../examples/architectural_tour/scene.rs"]
mod scene;

use std::path::{Path, PathBuf};

use glam::Vec3;
use plenoptic_recon::CameraPath;
use plenoptic_scene::Scene;
use plenoptic_scene::recipe::{Recipe, ViewSpace};

fn assets() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/architectural_tour/assets")
}

fn committed_scene() -> (Vec<u8>, Scene) {
    let bytes = std::fs::read(assets().join("tour.glb")).expect("tour.glb is committed");
    let scene = plenoptic_scene::load_slice(&bytes, "tour.glb", None).expect("tour.glb imports");
    (bytes, scene)
}

#[test]
fn committed_glb_is_what_the_generator_writes() {
    let a = scene::build().to_glb_bytes().unwrap();
    let b = scene::build().to_glb_bytes().unwrap();
    assert_eq!(a, b, "the generator is deterministic");
    let (committed, _) = committed_scene();
    assert!(
        committed == a,
        "examples/architectural_tour/assets/tour.glb is stale: delete it and run the \
         architectural_tour example to regenerate it"
    );
}

#[test]
fn scene_has_the_promised_elements() {
    let (_, scene) = committed_scene();
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    let names: Vec<&str> = scene.objects.iter().map(|o| o.name.as_str()).collect();
    let has = |name: &str| {
        assert!(
            scene.object_by_name(name).is_some(),
            "no object {name} in {names:?}"
        )
    };
    let count = |prefix: &str| names.iter().filter(|n| n.starts_with(prefix)).count();

    // Two rooms and an atrium, each with a floor.
    for part in ["RoomA", "RoomB", "Atrium"] {
        has(&format!("{part}_Floor"));
        assert!(count(part) >= 5, "{part} is too empty");
    }
    // Daylight: windows and a skylight, and a directional sun.
    assert!(count("Windows_") + count("Atrium_Window") + count("RoomB_Window") >= 3);
    has("Atrium_Skylight_Frame");
    let sun = scene
        .lights
        .iter()
        .position(|l| l.name == scene::SUN)
        .expect("a sun");
    assert_eq!(
        scene.lights[sun].kind,
        plenoptic_scene::LightKind::Directional
    );
    // Mirror and glass.
    let material = |name: &str| {
        &scene.materials[scene.objects[scene.object_by_name(name).unwrap() as usize].material]
    };
    has("RoomA_Mirror");
    let m = material("RoomA_Mirror");
    assert!(m.metallic > 0.99 && m.roughness < 0.02, "{m:?}");
    has("RoomB_GlassVitrine");
    let g = material("RoomB_GlassVitrine");
    assert!(g.transmission > 0.99 && (g.ior - 1.5).abs() < 1e-3, "{g:?}");
    // Textures made in code on the floors, the walls, the benches and the steel.
    for name in [
        "RoomA_Floor",
        "Atrium_Floor",
        "RoomB_Floor",
        "Atrium_Wall_North",
        "RoomA_Wall_South",
        "Atrium_Bench_0",
        "Atrium_Skylight_Frame",
    ] {
        let m = material(name);
        assert!(
            m.base_color_texture.is_some(),
            "{name} is untextured: {m:?}"
        );
    }
    assert!(
        scene.textures.len() >= 7,
        "{} textures",
        scene.textures.len()
    );
    // Columns and stairs.
    assert_eq!(count("Atrium_Column_"), 4);
    has("Atrium_Stairs");
    // Furniture.
    for name in [
        "RoomA_Table",
        "RoomA_Bench_0",
        "RoomA_Bookshelf",
        "RoomB_Table",
        "RoomB_Shelf_0",
        "Atrium_Bench_0",
    ] {
        has(name);
    }
    // Moderate size, so that a draft bake takes minutes.
    let tris = scene.triangle_count();
    assert!((1_000..=50_000).contains(&tris), "{tris} triangles");
}

#[test]
fn animated_things_move_and_the_sun_turns() {
    let (_, scene) = committed_scene();
    let (a, b) = scene.animation_range();
    assert!(a <= 0.0 && b >= 10.0, "animation range {a}..{b}");
    for name in scene::ANIMATED_OBJECTS {
        let id = scene
            .object_by_name(name)
            .unwrap_or_else(|| panic!("no {name}"));
        assert!(scene.object_is_animated(id), "{name} is not animated");
        // Some vertex of the object moves between t = 0 and t = 5.
        let mesh = &scene.meshes[scene.objects[id as usize].mesh];
        let (m0, m5) = (
            scene.object_transform(id, 0.0),
            scene.object_transform(id, 5.0),
        );
        let moved = mesh
            .positions
            .iter()
            .map(|&p| m0.transform_point3(p).distance(m5.transform_point3(p)))
            .fold(0.0f32, f32::max);
        assert!(
            moved > 0.05,
            "{name} moves only {moved} m between t = 0 and 5"
        );
    }
    // The child orb turns with the sculpture.
    let orb = scene.object_by_name("Atrium_Sculpture_Orb").unwrap();
    assert!(scene.object_is_animated(orb));

    let sun = scene
        .lights
        .iter()
        .position(|l| l.name == scene::SUN)
        .unwrap();
    let d0 = scene.placed_light(sun, 0.0).direction;
    let d5 = scene.placed_light(sun, 5.0).direction;
    let d14 = scene.placed_light(sun, scene::DURATION).direction;
    assert!(d0.dot(d5) < 0.995 && d0.dot(d14) < 0.9, "{d0} {d5} {d14}");
    for t in [0.0, 3.5, 7.0, 10.5, 14.0] {
        let d = scene.placed_light(sun, t).direction;
        // Downwards and from the south (+z), through the windows and the skylight.
        assert!(d.y < -0.4 && d.z < 0.0, "sun direction {d} at {t}");
        assert!(d.distance(scene::sun_direction(t)) < 0.02);
    }
}

#[test]
fn recipe_and_camera_path_fit_the_scene() {
    let recipe = Recipe::from_path(&assets().join("tour.toml")).expect("tour.toml is valid");
    assert_eq!(recipe.scenes.len(), 1);
    assert!(recipe.scenes[0].path.ends_with("tour.glb"));
    assert!(recipe.time.duration() >= 10.0);
    let ViewSpace::Rectangle { min, max, y } = recipe.view_space else {
        panic!(
            "the tour's view space is a rectangle: {:?}",
            recipe.view_space
        )
    };
    assert!((y - scene::EYE_HEIGHT).abs() < 1e-4);
    // Over the walkable floor, inside the building.
    assert!(min.x >= -12.0 && max.x <= 12.0 && min.y >= -6.0 && max.y <= 6.0);

    let path = CameraPath::load(assets().join("tour_path.json")).expect("tour_path.json");
    let (s0, s1) = path.time_range();
    assert!(s1 - s0 >= 10.0, "the path lasts {} s", s1 - s0);
    let mut rooms = [false; 3];
    for (i, k) in path.keyframes.iter().enumerate() {
        let p = Vec3::from_array(k.position);
        assert!(
            p.x >= min.x && p.x <= max.x && p.z >= min.y && p.z <= max.y,
            "keyframe {i} at {p} is outside the view space {min}..{max}"
        );
        assert!(
            (p.y - y).abs() < 1e-4,
            "keyframe {i} at {p} is off the eye height"
        );
        let st = k.scene_time.unwrap_or(k.time);
        assert!(st >= recipe.time.start && st <= recipe.time.end);
        rooms[if p.x < -4.0 {
            0
        } else if p.x > 4.0 {
            2
        } else {
            1
        }] = true;
    }
    assert_eq!(
        rooms, [true; 3],
        "the path visits room A, the atrium and room B"
    );
    // Every frame of the path stays in the view space too (Catmull-Rom may overshoot).
    for s in path.frames() {
        let p = s.camera.position;
        assert!(
            p.x >= min.x - 1e-3
                && p.x <= max.x + 1e-3
                && p.z >= min.y - 1e-3
                && p.z <= max.y + 1e-3,
            "frame {} at {p} leaves the view space",
            s.index
        );
        // Through the walls between the rooms only by the doorways, and through room B's
        // doorway only while the sliding door is open (2.5 s to 10 s).
        if (p.x + 4.0).abs() < 0.3 {
            assert!(
                p.z.abs() < 1.2,
                "frame {} at {p} walks through a wall",
                s.index
            );
        }
        if (p.x - 4.0).abs() < 0.3 {
            assert!(
                p.z.abs() < 0.8,
                "frame {} at {p} walks through a wall",
                s.index
            );
            assert!(
                (2.5..=10.0).contains(&s.scene_time),
                "frame {} at {p} walks through the closed door at t = {}",
                s.index,
                s.scene_time
            );
        }
    }
}

#[test]
fn the_recipe_lights_the_tour_with_a_sun_study_and_a_sky() {
    let (recipe, scene) = plenoptic_bake::input::load_recipe(&assets().join("tour.toml"))
        .expect("tour.toml and tour.glb load");
    let sun = scene.sun.as_ref().expect("the recipe has a sun study");
    assert!(sun.track.is_some(), "the sun follows the study's track");
    assert_eq!(
        scene.lights[sun.light].name,
        scene::SUN,
        "it drives the glb's own sun"
    );
    assert!(
        matches!(
            scene.environment,
            plenoptic_scene::Environment::Sky(plenoptic_pack::plenoptic_sky::SkyParams {
                ground: true,
                ..
            })
        ),
        "the windows show a Hosek–Wilkie sky, and its ground below the horizon"
    );
    for t in [recipe.time.start, 7.0, recipe.time.end] {
        let d = scene.placed_light(sun.light, t).direction;
        // Above the horizon, and from the south (+z) all day, so that it shines in through
        // the south windows.
        assert!(d.y < -0.05 && d.z < 0.0, "sun direction {d} at {t}");
    }
    // The east window's pane is glazing as exporters write it.
    let pane = scene
        .objects
        .iter()
        .position(|o| o.name == "RoomB_Window_East_Pane")
        .expect("the east window has a pane");
    let material = &scene.materials[scene.objects[pane].material];
    assert_eq!(material.alpha_mode, plenoptic_scene::AlphaMode::Blend);
    assert!((material.base_color.w - 0.12).abs() < 1e-3);
}
