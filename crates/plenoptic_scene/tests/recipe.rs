//! Bake recipes: a valid round trip, every preset, overrides, and one error per key.

use std::path::Path;

use glam::{Quat, Vec2, Vec3};
use plenoptic_scene::RecipeError;
use plenoptic_scene::recipe::{Preset, Quality, Recipe, ViewSpace};

const VALID: &str = r#"
output = "out/house.pack"

[[scene]]
file = "house.glb"
translation = [1.0, 0.0, -2.0]
rotation_deg = [0.0, 90.0, 0.0]
scale = [2.0, 2.0, 2.0]

[[scene]]
file = "props/chair.gltf"
rotation = [0.0, 0.0, 0.0, 2.0]

[view_space]
kind = "rectangle"
min = [-2.0, -3.0]
max = [2.0, 3.0]
y = 1.6

[time]
start = 0.0
end = 10.0
frame_rate = 30.0

[quality]
preset = "preview"
q = 0.93
range_image_size = 768
"#;

#[test]
fn valid_recipe_validates_and_round_trips() {
    let base = Path::new("/bakes");
    let raw = Recipe::parse(VALID, "recipe.toml").unwrap();
    let again = Recipe::parse(&raw.to_toml_string(), "again.toml").unwrap();
    assert_eq!(raw, again, "TOML round trip");

    let recipe = raw.validate("recipe.toml", base).unwrap();
    assert_eq!(recipe, again.validate("recipe.toml", base).unwrap());
    assert_eq!(recipe.output, base.join("out/house.pack"));
    assert_eq!(recipe.scenes.len(), 2);
    assert_eq!(recipe.scenes[0].path, base.join("house.glb"));
    assert_eq!(recipe.scenes[1].path, base.join("props/chair.gltf"));
    let t = recipe.scenes[0].transform;
    assert_eq!(t.translation, Vec3::new(1.0, 0.0, -2.0));
    assert_eq!(t.scale, Vec3::splat(2.0));
    // 90° of yaw: x → −z.
    assert!((t.rotation * Vec3::X).abs_diff_eq(Vec3::NEG_Z, 1e-6));
    // Quaternions are normalised.
    assert_eq!(recipe.scenes[1].transform.rotation, Quat::IDENTITY);
    assert_eq!(
        recipe.view_space,
        ViewSpace::Rectangle {
            min: Vec2::new(-2.0, -3.0),
            max: Vec2::new(2.0, 3.0),
            y: 1.6
        }
    );
    assert_eq!(recipe.view_space.corners().len(), 4);
    assert_eq!(recipe.time.frame_count(), 301);
    // Preset with overrides.
    let expected = Quality {
        q: 0.93,
        range_image_size: 768,
        ..Quality::preview()
    };
    assert_eq!(recipe.quality, expected);
}

#[test]
fn from_path_resolves_against_the_recipe_directory() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("recipe.toml");
    std::fs::write(&path, VALID).unwrap();
    let recipe = Recipe::from_path(&path).unwrap();
    assert_eq!(recipe.scenes[0].path, dir.path().join("house.glb"));
    let missing = Recipe::from_path(&dir.path().join("nope.toml")).unwrap_err();
    assert!(matches!(missing, RecipeError::Io { .. }));
}

#[test]
fn every_preset_validates() {
    let mut previous: Option<Quality> = None;
    for preset in Preset::ALL {
        let text = VALID
            .replace(
                "preset = \"preview\"",
                &format!("preset = \"{}\"", preset.name()),
            )
            .replace("q = 0.93\n", "")
            .replace("range_image_size = 768\n", "");
        let recipe = Recipe::from_str_named(&text, "recipe.toml", Path::new(".")).unwrap();
        assert_eq!(recipe.quality, preset.quality());
        assert_eq!(Preset::from_name(preset.name()), Some(preset));
        // Each preset costs more than the previous one.
        if let Some(p) = previous {
            let q = preset.quality();
            assert!(q.q > p.q && q.range_image_size > p.range_image_size);
            assert!(q.samples_per_pixel > p.samples_per_pixel);
        }
        previous = Some(preset.quality());
    }
    // No preset: production.
    let text = VALID.replace("preset = \"preview\"\n", "");
    let recipe = Recipe::from_str_named(&text, "recipe.toml", Path::new(".")).unwrap();
    assert_eq!(
        recipe.quality.samples_per_pixel,
        Quality::production().samples_per_pixel
    );
    assert_eq!(recipe.quality.q, 0.93);
}

#[test]
fn unknown_keys_are_rejected() {
    for (from, to, key) in [
        ("output =", "outptu = \"x\"\noutput =", "outptu"),
        (
            "scale = [2.0, 2.0, 2.0]",
            "scael = [2.0, 2.0, 2.0]",
            "scael",
        ),
        ("y = 1.6", "y = 1.6\nz = 2.0", "`z`"),
        ("frame_rate = 30.0", "framerate = 30.0", "framerate"),
        ("q = 0.93", "quality = 0.93", "`quality`"),
    ] {
        let text = VALID.replacen(from, to, 1);
        let err = Recipe::from_str_named(&text, "recipe.toml", Path::new(".")).unwrap_err();
        let msg = err.to_string();
        assert!(matches!(err, RecipeError::Parse { .. }), "{msg}");
        assert!(
            msg.starts_with("recipe.toml: ") && msg.contains("unknown field") && msg.contains(key),
            "{msg}"
        );
    }
}

/// Replaces `from` by `to` in the valid recipe and expects a validation error on `key`.
fn expect_invalid(from: &str, to: &str, key: &str, problem: &str) {
    let text = VALID.replacen(from, to, 1);
    assert_ne!(text, VALID, "{from:?} not found");
    let err = Recipe::from_str_named(&text, "recipe.toml", Path::new(".")).unwrap_err();
    let msg = err.to_string();
    match &err {
        RecipeError::Invalid { key: k, .. } => assert_eq!(k, key, "{msg}"),
        other => panic!("expected a validation error on {key}, got {other}"),
    }
    assert!(msg.starts_with(&format!("recipe.toml: {key}: ")), "{msg}");
    assert!(msg.contains(problem), "{msg}");
}

#[test]
fn each_validation_error_names_its_key() {
    expect_invalid(
        "output = \"out/house.pack\"",
        "output = \"\"",
        "output",
        "must name",
    );
    expect_invalid(
        "file = \"house.glb\"",
        "file = \"\"",
        "scene[0].file",
        "must name",
    );
    expect_invalid(
        "translation = [1.0, 0.0, -2.0]",
        "translation = [nan, 0.0, 0.0]",
        "scene[0].translation",
        "finite",
    );
    expect_invalid(
        "rotation_deg = [0.0, 90.0, 0.0]",
        "rotation_deg = [0.0, 90.0, 0.0]\nrotation = [0.0, 0.0, 0.0, 1.0]",
        "scene[0].rotation",
        "not both",
    );
    expect_invalid(
        "rotation = [0.0, 0.0, 0.0, 2.0]",
        "rotation = [0.0, 0.0, 0.0, 0.0]",
        "scene[1].rotation",
        "zero",
    );
    expect_invalid(
        "rotation_deg = [0.0, 90.0, 0.0]",
        "rotation_deg = [0.0, inf, 0.0]",
        "scene[0].rotation_deg",
        "finite",
    );
    expect_invalid(
        "scale = [2.0, 2.0, 2.0]",
        "scale = [2.0, 0.0, 2.0]",
        "scene[0].scale",
        "zero",
    );
    expect_invalid(
        "kind = \"rectangle\"",
        "kind = \"sphere\"",
        "view_space.kind",
        "unknown kind",
    );
    expect_invalid(
        "max = [2.0, 3.0]",
        "max = [2.0, -3.0]",
        "view_space.max",
        "must be greater than view_space.min on every axis",
    );
    expect_invalid(
        "max = [2.0, 3.0]",
        "max = [2.0, 3.0, 4.0]",
        "view_space.max",
        "2 components",
    );
    expect_invalid("y = 1.6\n", "", "view_space.y", "required");
    expect_invalid(
        "y = 1.6",
        "y = 1.6\na = [0.0, 0.0, 0.0]",
        "view_space.a",
        "not used by kind = \"rectangle\"",
    );
    expect_invalid(
        "start = 0.0",
        "start = 11.0",
        "time.end",
        "before time.start",
    );
    expect_invalid("start = 0.0", "start = nan", "time.start", "finite");
    expect_invalid(
        "frame_rate = 30.0",
        "frame_rate = 0.0",
        "time.frame_rate",
        "positive",
    );
    expect_invalid(
        "preset = \"preview\"",
        "preset = \"ultra\"",
        "quality.preset",
        "unknown preset",
    );
    expect_invalid("q = 0.93", "q = 1.5", "quality.q", "[0, 1]");
    expect_invalid(
        "range_image_size = 768",
        "range_image_size = 0",
        "quality.range_image_size",
        "must be in",
    );
    expect_invalid(
        "q = 0.93",
        "ambient_rms = -1.0",
        "quality.ambient_rms",
        "positive",
    );
    expect_invalid(
        "q = 0.93",
        "max_time_depth = 99",
        "quality.max_time_depth",
        "at most",
    );
    let no_scene = VALID
        .replace("[[scene]]\nfile = \"props/chair.gltf\"\nrotation = [0.0, 0.0, 0.0, 2.0]\n", "")
        .replace("[[scene]]\nfile = \"house.glb\"\ntranslation = [1.0, 0.0, -2.0]\nrotation_deg = [0.0, 90.0, 0.0]\nscale = [2.0, 2.0, 2.0]\n", "");
    let err = Recipe::from_str_named(&no_scene, "recipe.toml", Path::new(".")).unwrap_err();
    assert!(err.to_string().starts_with("recipe.toml: scene: "), "{err}");
}

#[test]
fn segment_and_box_view_spaces() {
    let segment = VALID.replace(
        "kind = \"rectangle\"\nmin = [-2.0, -3.0]\nmax = [2.0, 3.0]\ny = 1.6",
        "kind = \"segment\"\na = [0.0, 1.6, 0.0]\nb = [4.0, 1.6, 0.0]",
    );
    let recipe = Recipe::from_str_named(&segment, "recipe.toml", Path::new(".")).unwrap();
    assert_eq!(
        recipe.view_space,
        ViewSpace::Segment {
            a: Vec3::new(0.0, 1.6, 0.0),
            b: Vec3::new(4.0, 1.6, 0.0)
        }
    );
    let same = segment.replace("b = [4.0, 1.6, 0.0]", "b = [0.0, 1.6, 0.0]");
    let err = Recipe::from_str_named(&same, "recipe.toml", Path::new(".")).unwrap_err();
    assert!(
        err.to_string().contains("view_space.b: must differ"),
        "{err}"
    );

    let cube = VALID.replace(
        "kind = \"rectangle\"\nmin = [-2.0, -3.0]\nmax = [2.0, 3.0]\ny = 1.6",
        "kind = \"box\"\nmin = [-1.0, 1.0, -1.0]\nmax = [1.0, 2.0, 1.0]",
    );
    let recipe = Recipe::from_str_named(&cube, "recipe.toml", Path::new(".")).unwrap();
    assert_eq!(recipe.view_space.corners().len(), 8);
    let flat = cube.replace("max = [1.0, 2.0, 1.0]", "max = [1.0, 1.0, 1.0]");
    let err = Recipe::from_str_named(&flat, "recipe.toml", Path::new(".")).unwrap_err();
    assert_eq!(
        err.to_string(),
        "recipe.toml: view_space.max: must be greater than view_space.min on every axis"
    );
}

#[test]
fn wrong_types_are_parse_errors_with_a_location() {
    let text = VALID.replace("frame_rate = 30.0", "frame_rate = \"thirty\"");
    let err = Recipe::from_str_named(&text, "recipe.toml", Path::new(".")).unwrap_err();
    let msg = err.to_string();
    assert!(matches!(err, RecipeError::Parse { .. }));
    assert!(msg.contains("recipe.toml") && msg.contains("line"), "{msg}");
}
