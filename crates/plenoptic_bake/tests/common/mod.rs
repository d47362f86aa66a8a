//! Tiny test scenes and recipes.
#![allow(dead_code)]

pub mod sunlit_room;

use std::path::{Path, PathBuf};

use glam::Vec3;
use plenoptic_scene::Track;
use plenoptic_scene::builder::{LightDesc, MaterialDesc, NodeDesc, SceneBuilder};

/// Adds a closed room (six wall slabs) centred at `c` with inner half-size `h`.
pub fn room(
    b: &mut SceneBuilder,
    name: &str,
    c: Vec3,
    h: f32,
    mat: plenoptic_scene::builder::MaterialHandle,
) {
    let w = 0.2;
    for (i, axis) in [Vec3::X, Vec3::Y, Vec3::Z].into_iter().enumerate() {
        let size = Vec3::splat(2.0 * h + 2.0 * w) - axis * (2.0 * h + w);
        let mesh = b.add_box(format!("{name}-wall{i}"), size, mat);
        for s in [-1.0f32, 1.0] {
            b.add_node(
                NodeDesc::new(format!("{name}-wall{i}{}", if s < 0.0 { "n" } else { "p" }))
                    .mesh(mesh)
                    .translation(c + axis * s * (h + 0.5 * w)),
            );
        }
    }
}

/// Two closed rooms: A around (-5, 0, 0) with a box moving across it, B around (5, 0, 0) with
/// a static box and a point light. Nothing in B sees A.
pub fn two_rooms() -> SceneBuilder {
    let mut b = SceneBuilder::new();
    let grey = b.add_material(MaterialDesc::diffuse(Vec3::splat(0.6)));
    let red = b.add_material(MaterialDesc::diffuse(Vec3::new(0.8, 0.2, 0.2)));
    room(&mut b, "A", Vec3::new(-5.0, 0.0, 0.0), 2.0, grey);
    room(&mut b, "B", Vec3::new(5.0, 0.0, 0.0), 2.0, grey);
    let cube = b.add_box("cube", Vec3::splat(0.8), red);
    let mover = b.add_node(
        NodeDesc::new("mover")
            .mesh(cube)
            .translation(Vec3::new(-6.2, -1.0, 0.0)),
    );
    b.animate_translation(
        mover,
        Track::linear([
            (0.0, Vec3::new(-6.2, -1.0, 0.0)),
            (1.0, Vec3::new(-3.8, -1.0, 0.0)),
        ]),
    );
    b.add_node(
        NodeDesc::new("still")
            .mesh(cube)
            .translation(Vec3::new(5.0, -1.2, 1.0)),
    );
    b.add_node(
        NodeDesc::new("lamp")
            .light(LightDesc::point(Vec3::ONE, 20.0))
            .translation(Vec3::new(5.0, 1.5, 0.0)),
    );
    b
}

/// One closed room around the origin with a static box and a point light.
pub fn static_room() -> SceneBuilder {
    let mut b = SceneBuilder::new();
    let grey = b.add_material(MaterialDesc::diffuse(Vec3::splat(0.6)));
    room(&mut b, "R", Vec3::ZERO, 2.0, grey);
    let cube = b.add_box("cube", Vec3::splat(0.8), grey);
    b.add_node(
        NodeDesc::new("still")
            .mesh(cube)
            .translation(Vec3::new(0.5, -1.2, 0.5)),
    );
    b.add_node(
        NodeDesc::new("lamp")
            .light(LightDesc::point(Vec3::ONE, 20.0))
            .translation(Vec3::new(0.0, 1.5, 0.0)),
    );
    b
}

/// Quality overrides for tests: tiny images, few samples.
pub const TINY: &str = r#"
preset = "draft"
id_image_size = 12
range_image_size = 8
samples_per_pixel = 1
ambient_samples = 8
ambient_rms = 0.5
temporal_volume_samples = 120
max_specular_depth = 1
max_time_depth = 3
max_space_depth = 1
"#;

/// Writes `scene.glb` and `recipe.toml` into `dir`; returns the recipe's path.
/// `view` is the `[view_space]` body, `quality` extra `[quality]` lines (after [`TINY`]).
pub fn write_recipe(dir: &Path, scene: &SceneBuilder, view: &str, quality: &str) -> PathBuf {
    write_recipe_with(dir, scene, view, quality, "")
}

/// [`write_recipe`] with `extra` tables (`[sky]`, `[[light_group]]`, …) after `[quality]`.
pub fn write_recipe_with(
    dir: &Path,
    scene: &SceneBuilder,
    view: &str,
    quality: &str,
    extra: &str,
) -> PathBuf {
    scene.write_glb(&dir.join("scene.glb")).unwrap();
    // Later lines override earlier ones with the same key.
    let mut lines: Vec<(String, String)> = Vec::new();
    for line in TINY.lines().chain(quality.lines()) {
        if let Some((k, v)) = line.split_once('=') {
            let (k, v) = (k.trim().to_owned(), v.trim().to_owned());
            match lines.iter_mut().find(|(key, _)| *key == k) {
                Some(entry) => entry.1 = v,
                None => lines.push((k, v)),
            }
        }
    }
    let quality: String = lines.iter().map(|(k, v)| format!("{k} = {v}\n")).collect();
    let text = format!(
        "output = \"out/scene.pack\"\n\n[[scene]]\nfile = \"scene.glb\"\n\n[view_space]\n{view}\n\n\
         [time]\nstart = 0.0\nend = 1.0\nframe_rate = 8.0\n\n[quality]\n{quality}\n{extra}"
    );
    let path = dir.join("recipe.toml");
    std::fs::write(&path, text).unwrap();
    path
}

/// A segment from the centre of room A to the centre of room B.
pub const ROOMS_SEGMENT: &str = "kind = \"segment\"\na = [-5.0, 0.0, 0.0]\nb = [5.0, 0.0, 0.0]";

/// A segment inside room A.
pub const ROOM_A_SEGMENT: &str = "kind = \"segment\"\na = [-5.5, 0.5, -0.5]\nb = [-4.5, 0.5, 0.5]";

/// A rectangle inside room A.
pub const ROOM_A_RECT: &str =
    "kind = \"rectangle\"\nmin = [-6.0, -1.0]\nmax = [-4.0, 1.0]\ny = 0.3";

/// A segment inside the static room.
pub const STATIC_SEGMENT: &str = "kind = \"segment\"\na = [-1.0, 0.5, -1.0]\nb = [1.0, 0.5, 1.0]";

/// A path-traced reference of `camera` over `scene` at time `t` as two independent halves of
/// `spp / 2` samples each (seeds `seed` and `seed + 1`), for variance-corrected comparisons.
pub fn reference_halves(
    scene: &plenoptic_scene::Scene,
    camera: &plenoptic_recon::Camera,
    t: f32,
    spp: u32,
    seed: u64,
) -> (plenoptic_trace::Image<Vec3>, plenoptic_trace::Image<Vec3>) {
    use plenoptic_trace::{PathTracer, PathTracerSettings, SceneAccel};
    let accel = SceneAccel::new(scene).unwrap();
    let placed = accel.at_time(t);
    let pinhole = plenoptic_eval::camera::to_pinhole(camera).unwrap();
    let half = |seed| {
        PathTracer::new(PathTracerSettings {
            samples_per_pixel: (spp / 2).max(1),
            max_depth: 16,
            rr_start_depth: 5,
            seed,
            environment_sampling: true,
        })
        .render(&placed, &pinhole)
        .radiance()
    };
    (half(seed), half(seed + 1))
}

/// Writes the reference and the reconstruction as `{prefix}reference.png` and
/// `{prefix}recon.png` into `target/tmp/{dir}/`, both at the exposure that puts the
/// reference's mean luminance at 0.5.
pub fn save_frames(
    dir: &str,
    prefix: &str,
    reference: &plenoptic_trace::Image<Vec3>,
    recon: &plenoptic_recon::Frame,
) {
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join(dir);
    std::fs::create_dir_all(&out).unwrap();
    let exposure = 0.5 / reference.mean_luminance() as f32;
    reference
        .save_png(out.join(format!("{prefix}reference.png")), exposure)
        .unwrap();
    plenoptic_trace::Image {
        width: recon.width,
        height: recon.height,
        pixels: recon.radiance.clone(),
    }
    .save_png(out.join(format!("{prefix}recon.png")), exposure)
    .unwrap();
}
