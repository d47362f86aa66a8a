//! Thin objects that no cube texel centre meets (geometry-assisted fallbacks, after the
//! same-object hole fill): a window's mullion seen from the base views across a room. Its
//! pixels have no accepted lookup, and the cube in the point's direction shows the sky behind
//! the mullion: read there, the tour's mullions would glow. The runtime takes the nearest
//! texels of the object itself around the lookup, else of any surface at the point's distance
//! (the wall around the window; `neighbour.rs` in `plenoptic_recon`, whose unit tests cover an
//! opening wider than this one). Frames go to `target/tmp/thin_objects/`.

mod common;

use glam::{Vec2, Vec3};
use plenoptic_recon::{Camera, Mode, Reconstructor};
use plenoptic_scene::builder::{MaterialDesc, NodeDesc, SceneBuilder};
use plenoptic_trace::image::luminance;

/// The window in the wall at z = −2: x from −0.6 to 0.6, y from 0.8 to 2.0.
const WINDOW: (Vec2, Vec2) = (Vec2::new(-0.6, 0.8), Vec2::new(0.6, 2.0));
/// The mullion's width (m) and its centre's x.
const MULLION: (f32, f32) = (0.05, 0.11);

/// A floor, a wall at z = −2 with a window open to a bright uniform sky, and a mullion
/// splitting the window.
fn scene() -> SceneBuilder {
    let mut b = SceneBuilder::new();
    let grey = b.add_material(MaterialDesc::diffuse(Vec3::splat(0.6)));
    let dark = b.add_material(MaterialDesc::diffuse(Vec3::splat(0.3)));
    let floor = b.add_plane("floor", Vec2::splat(8.0), 1, grey);
    b.add_node(NodeDesc::new("floor").mesh(floor));
    let (lo, hi) = WINDOW;
    let (x0, x1, top) = (-3.0f32, 3.0f32, 3.0f32);
    // The wall around the window: left, right, below, above (0.1 m thick).
    for (name, a, c) in [
        ("wall_left", Vec2::new(x0, 0.0), Vec2::new(lo.x, top)),
        ("wall_right", Vec2::new(hi.x, 0.0), Vec2::new(x1, top)),
        ("wall_below", Vec2::new(lo.x, 0.0), Vec2::new(hi.x, lo.y)),
        ("wall_above", Vec2::new(lo.x, hi.y), Vec2::new(hi.x, top)),
    ] {
        let size = c - a;
        let mesh = b.add_box(name, Vec3::new(size.x, size.y, 0.1), grey);
        let centre = (a + c) * 0.5;
        b.add_node(
            NodeDesc::new(name)
                .mesh(mesh)
                .translation(Vec3::new(centre.x, centre.y, -2.0)),
        );
    }
    let (width, x) = MULLION;
    let mullion = b.add_box("mullion", Vec3::new(width, hi.y - lo.y, 0.1), dark);
    b.add_node(
        NodeDesc::new("mullion")
            .mesh(mullion)
            .translation(Vec3::new(x, (lo.y + hi.y) * 0.5, -2.0)),
    );
    b
}

#[test]
fn a_mullion_no_texel_centre_meets_is_not_shown_as_the_sky() {
    let dir = tempfile::tempdir().unwrap();
    let quality = "range_image_size = 16\nsamples_per_pixel = 4\nambient_samples = 32";
    let view = "kind = \"segment\"\na = [-0.5, 1.3, 1.5]\nb = [0.5, 1.3, 1.5]";
    let recipe = common::write_recipe(dir.path(), &scene(), view, quality);
    let mut text = std::fs::read_to_string(&recipe).unwrap();
    text.push_str("\n[sky]\nkind = \"uniform\"\ncolor = [3.0, 3.0, 3.0]\n");
    std::fs::write(&recipe, text).unwrap();
    plenoptic_bake::bake_recipe(&recipe, &plenoptic_bake::BakeOptions::default()).unwrap();
    // The scene as the bake saw it: with the recipe's sky.
    let (_, scene) = plenoptic_bake::input::load_recipe(&recipe).unwrap();
    let camera = Camera::look_at(
        Vec3::new(0.2, 1.3, 1.0),
        Vec3::new(0.05, 1.4, -2.0),
        Vec3::Y,
        30f32.to_radians(),
        256,
        144,
    )
    .unwrap();
    let (a, b) = common::reference_halves(&scene, &camera, 0.5, 32, 5);
    let rec = Reconstructor::open(dir.path().join("out/scene.pack")).unwrap();
    let (frame, report) = rec.render(&camera, 0.5, Mode::GeometryAssisted).unwrap();
    let mullion = rec
        .pack()
        .manifest()
        .objects
        .iter()
        .find(|o| o.name == "mullion")
        .unwrap()
        .id;
    // Its pixels away from its edges (a reference pixel at an edge holds some sky).
    let w = frame.width as usize;
    let on: Vec<usize> = (2..frame.object.len() - 2)
        .filter(|&j| (j - 2..=j + 2).all(|k| frame.object[k] == mullion) && j % w >= 2)
        .collect();
    assert!(on.len() > 80, "mullion pixels: {}", on.len());
    let mean = |img: &[Vec3]| {
        on.iter()
            .map(|&j| f64::from(luminance(img[j])))
            .sum::<f64>()
            / on.len() as f64
    };
    let reference = 0.5 * (mean(&a.pixels) + mean(&b.pixels));
    let runtime = mean(&frame.radiance);
    let sky = 3.0;
    common::save_frames("thin_objects", "", &a, &frame);
    println!(
        "mullion ({} pixels): runtime {runtime:.4}, reference {reference:.4} (ratio {:.3}; the \
         sky behind it {sky}); fallbacks {:?}",
        on.len(),
        runtime / reference,
        report.fallback
    );
    // The mullion is lit by the room's light, far below the sky it stands against.
    assert!(
        reference < 0.3 * sky,
        "the reference's mullion: {reference}"
    );
    assert!(
        (runtime / reference - 1.0).abs() < 0.35,
        "the runtime's mullion {runtime} against the reference's {reference}"
    );
}
