//! A sunlit interior against the path tracer: a closed room whose one window is glazed as CAD
//! exporters write glass (a pane 1 cm thick, `alphaMode: BLEND`, alpha 0.12), the sun shining
//! through it onto the floor. The path tracer's shadow rays pass each of the pane's two
//! surfaces with probability 0.88 (coverage, `plenoptic_trace::alpha`); the bake leaves the
//! sun's direct light to the runtime, whose shadow rays must pass the pane the same way
//! (`plenoptic_recon::shadow`, `PlacedShadows::transmittance`), or the sun patch is lost
//! and the room is lit by its bounces alone.
//!
//! Checked on the geometry-assisted frame: the sunlit floor pixels' mean luminance within 5 %
//! of the reference's, the whole frame's within 3 %. Frames go to
//! `target/tmp/sunlit_interior/`.

mod common;

use glam::{Quat, Vec3, Vec4};
use plenoptic_recon::{Camera, Mode, Reconstructor};
use plenoptic_scene::AlphaMode;
use plenoptic_scene::builder::{LightDesc, MaterialDesc, NodeDesc, SceneBuilder};
use plenoptic_trace::image::luminance;

/// Inner half-size of the room, and its walls' thickness.
const HALF: f32 = 2.0;
const WALL: f32 = 0.2;
/// The window in the +x wall: y and z extents.
const WINDOW_Y: (f32, f32) = (-0.6, 0.9);
const WINDOW_Z: (f32, f32) = (-1.3, 1.3);

/// Where the sunlight travels: in through the window, down onto the floor.
fn sun_direction() -> Vec3 {
    Vec3::new(-1.0, -1.1, 0.25).normalize()
}

/// A box of `size` centred at `c`.
fn slab(b: &mut SceneBuilder, name: &str, c: Vec3, size: Vec3, mat: MaterialDesc) {
    let mat = b.add_material(mat);
    let mesh = b.add_box(name, size, mat);
    b.add_node(NodeDesc::new(name).mesh(mesh).translation(c));
}

/// The room: floor, ceiling, three plain walls, the +x wall around the window, the pane in
/// the window, a table on the floor, and the sun.
fn scene() -> SceneBuilder {
    let mut b = SceneBuilder::new();
    let plaster = MaterialDesc::diffuse(Vec3::splat(0.7));
    let floor = MaterialDesc::diffuse(Vec3::new(0.55, 0.45, 0.35));
    let outer = 2.0 * HALF + 2.0 * WALL;
    let d = HALF + 0.5 * WALL;
    slab(
        &mut b,
        "floor",
        Vec3::new(0.0, -d, 0.0),
        Vec3::new(outer, WALL, outer),
        floor,
    );
    slab(
        &mut b,
        "ceiling",
        Vec3::new(0.0, d, 0.0),
        Vec3::new(outer, WALL, outer),
        plaster.clone(),
    );
    slab(
        &mut b,
        "wall_w",
        Vec3::new(-d, 0.0, 0.0),
        Vec3::new(WALL, outer, outer),
        plaster.clone(),
    );
    slab(
        &mut b,
        "wall_s",
        Vec3::new(0.0, 0.0, -d),
        Vec3::new(outer, outer, WALL),
        plaster.clone(),
    );
    slab(
        &mut b,
        "wall_n",
        Vec3::new(0.0, 0.0, d),
        Vec3::new(outer, outer, WALL),
        plaster.clone(),
    );
    // The +x wall as four pieces around the window.
    let (y0, y1) = WINDOW_Y;
    let (z0, z1) = WINDOW_Z;
    let pieces = [
        ("wall_e_below", (-HALF, y0), (-HALF, HALF)),
        ("wall_e_above", (y1, HALF), (-HALF, HALF)),
        ("wall_e_left", (y0, y1), (-HALF, z0)),
        ("wall_e_right", (y0, y1), (z1, HALF)),
    ];
    for (name, (ya, yb), (za, zb)) in pieces {
        let c = Vec3::new(d, 0.5 * (ya + yb), 0.5 * (za + zb));
        slab(
            &mut b,
            name,
            c,
            Vec3::new(WALL, yb - ya, zb - za),
            plaster.clone(),
        );
    }
    let glazing = MaterialDesc::diffuse(Vec3::splat(0.9))
        .base_color_alpha(Vec4::new(0.9, 0.95, 0.95, 0.12))
        .alpha_mode(AlphaMode::Blend)
        .double_sided(true)
        .named("glazing");
    let pane = Vec3::new(d, 0.5 * (y0 + y1), 0.5 * (z0 + z1));
    slab(
        &mut b,
        "pane",
        pane,
        Vec3::new(0.01, y1 - y0, z1 - z0),
        glazing,
    );
    let wood = MaterialDesc::diffuse(Vec3::new(0.5, 0.3, 0.15));
    slab(
        &mut b,
        "table",
        Vec3::new(-0.9, -1.3, 1.0),
        Vec3::new(0.8, 0.08, 0.8),
        wood,
    );
    b.add_node(
        NodeDesc::new("sun")
            .light(LightDesc::directional(Vec3::ONE, 4.0))
            .rotation(Quat::from_rotation_arc(Vec3::NEG_Z, sun_direction())),
    );
    b
}

/// Whether the sun reaches floor point `p` through the window opening (the pane aside).
fn sunlit(p: Vec3) -> bool {
    let towards = -sun_direction();
    // Where the ray towards the sun crosses the wall's inner face.
    let s = (HALF - p.x) / towards.x;
    let q = p + towards * s;
    let (y0, y1) = WINDOW_Y;
    let (z0, z1) = WINDOW_Z;
    p.y < -HALF + 1e-2 && (y0..y1).contains(&q.y) && (z0..z1).contains(&q.z)
}

#[test]
fn sun_through_a_glazed_window_lights_the_floor_as_the_path_tracer_does() {
    let dir = tempfile::tempdir().unwrap();
    let quality = "range_image_size = 32\nsamples_per_pixel = 8\nambient_samples = 64\n\
                   ambient_rms = 0.1\nmax_specular_depth = 2";
    let view = "kind = \"segment\"\na = [-1.2, 0.0, -1.0]\nb = [-0.4, 0.0, 0.6]";
    let recipe = common::write_recipe(dir.path(), &scene(), view, quality);
    plenoptic_bake::bake_recipe(&recipe, &plenoptic_bake::BakeOptions::default()).unwrap();
    let scene = plenoptic_scene::load(&dir.path().join("scene.glb")).unwrap();
    let (width, height) = (160, 90);
    let camera = Camera::look_at(
        Vec3::new(-1.6, 0.4, -1.5),
        Vec3::new(0.4, -1.6, 0.4),
        Vec3::Y,
        75f32.to_radians(),
        width,
        height,
    )
    .unwrap();
    let t = 0.5;
    let (a, b) = common::reference_halves(&scene, &camera, t, 256, 7);
    let rec = Reconstructor::open(dir.path().join("out/scene.pack")).unwrap();
    assert!(
        rec.runtime_sun().is_some(),
        "the bake leaves the sun to the runtime"
    );
    let (frame, _) = rec.render(&camera, t, Mode::GeometryAssisted).unwrap();
    common::save_frames("sunlit_interior", "", &a, &frame);

    let basis = camera.basis();
    let w = width as usize;
    let point = |j: usize| {
        let d = basis.direction((j % w) as f32 + 0.5, (j / w) as f32 + 0.5);
        basis.position + d * frame.depth[j]
    };
    let lit: Vec<usize> = (0..frame.radiance.len())
        .filter(|&j| frame.depth[j].is_finite() && sunlit(point(j)))
        .collect();
    let all: Vec<usize> = (0..frame.radiance.len()).collect();
    let mean = |img: &dyn Fn(usize) -> Vec3, which: &[usize]| {
        which
            .iter()
            .map(|&j| f64::from(luminance(img(j))))
            .sum::<f64>()
            / which.len() as f64
    };
    let reference = |j: usize| 0.5 * (a.pixels[j] + b.pixels[j]);
    let ours = |j: usize| frame.radiance[j];
    let lit_ratio = mean(&ours, &lit) / mean(&reference, &lit);
    let frame_ratio = mean(&ours, &all) / mean(&reference, &all);
    println!(
        "sunlit floor ({} of {} pixels): mean luminance {lit_ratio:.4} of the path tracer's; \
         whole frame {frame_ratio:.4}",
        lit.len(),
        all.len()
    );
    assert!(
        lit.len() > 400,
        "the sun patch is in view: {} pixels",
        lit.len()
    );
    assert!(
        (lit_ratio - 1.0).abs() < 0.05,
        "sunlit pixels: {lit_ratio:.4}"
    );
    assert!(
        (frame_ratio - 1.0).abs() < 0.03,
        "whole frame: {frame_ratio:.4}"
    );
}
