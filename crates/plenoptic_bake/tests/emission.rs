//! Emission at screen resolution (docs/architecture.md, "Pack v2", **Reconstruction**: a pixel
//! is albedo × lighting *plus emission* plus the view-dependent part). A wall panel emits
//! through a fine checker texture (8 cm squares) seen from 2 m; the bake's cubes are 16 px,
//! so a cube texel spans several squares and emission stored in the cubes would blur the
//! checker to grey. Pack 4 leaves the emission to the runtime, which takes the material's
//! emissive factor × texture at each pixel's own UV: the checker shows with the path
//! tracer's contrast. Frames go to `target/tmp/emission/`.

mod common;

use glam::{Vec2, Vec3};
use plenoptic_eval::metrics::corrected_relative_lrms;
use plenoptic_recon::{Camera, Mode, Reconstructor};
use plenoptic_scene::builder::{MaterialDesc, NodeDesc, SceneBuilder};
use plenoptic_trace::Image;
use plenoptic_trace::image::luminance;

/// Checker squares along each side of the texture (about 3 pixels each in the frame).
const SQUARES: u32 = 24;
/// Texels per square along each side: bilinear filtering then blends squares only at their
/// edges, not at the centres the test measures.
const TEXELS: u32 = 4;
/// The panel's side (m): squares of 8 cm.
const SIDE: f32 = 1.92;
/// The sRGB bytes of the bright and dark squares (linear 1.0 and 0.033).
const BRIGHT: u8 = 255;
const DARK: u8 = 50;

fn checker() -> Vec<u8> {
    let n = SQUARES * TEXELS;
    (0..n * n)
        .flat_map(|i| {
            let v = if ((i % n) / TEXELS + (i / n) / TEXELS).is_multiple_of(2) {
                BRIGHT
            } else {
                DARK
            };
            [v, v, v, 255]
        })
        .collect()
}

/// A floor and, above it, an upright panel at z = −1.5 facing +z whose emission is the checker.
fn scene() -> SceneBuilder {
    let mut b = SceneBuilder::new();
    let grey = b.add_material(MaterialDesc::diffuse(Vec3::splat(0.5)));
    let tex = b.add_texture_rgba8(SQUARES * TEXELS, SQUARES * TEXELS, checker());
    let glow = b.add_material(
        MaterialDesc::diffuse(Vec3::splat(0.2))
            .emissive(Vec3::ONE, 2.0)
            .emissive_texture(tex),
    );
    let floor = b.add_plane("floor", Vec2::splat(6.0), 1, grey);
    b.add_node(NodeDesc::new("floor").mesh(floor));
    let panel = b.add_plane("panel", Vec2::splat(SIDE), 1, glow);
    b.add_node(
        NodeDesc::new("panel")
            .mesh(panel)
            .translation(Vec3::new(0.0, 1.2, -1.5))
            .rotation(glam::Quat::from_rotation_x(std::f32::consts::FRAC_PI_2)),
    );
    b
}

/// Mean luminance of the panel pixels at the centres of the bright squares and of the dark
/// ones (the middle half of a square, away from its edges): `[bright, dark]`.
fn square_means(camera: &Camera, object: &[u32], panel: u32, pixels: &[Vec3]) -> [f64; 2] {
    let basis = camera.basis();
    let w = camera.width as usize;
    let mut sums = [(0.0, 0usize); 2];
    for (j, c) in pixels.iter().enumerate() {
        if object[j] != panel {
            continue;
        }
        let d = basis.direction((j % w) as f32 + 0.5, (j / w) as f32 + 0.5);
        if d.z >= -1e-3 {
            continue;
        }
        let p = basis.position + d * ((-1.5 - basis.position.z) / d.z);
        let (u, v) = (
            (p.x / SIDE + 0.5) * SQUARES as f32,
            ((p.y - 1.2) / SIDE + 0.5) * SQUARES as f32,
        );
        let centred = |x: f32| (0.25..=0.75).contains(&(x - x.floor()));
        if !(centred(u) && centred(v)) {
            continue;
        }
        let parity = ((u.floor() + v.floor()) as i64).rem_euclid(2) as usize;
        sums[parity].0 += f64::from(luminance(*c));
        sums[parity].1 += 1;
    }
    assert!(sums.iter().all(|s| s.1 > 20), "square pixels: {sums:?}");
    let means = sums.map(|(s, n)| s / n as f64);
    [means[0].max(means[1]), means[0].min(means[1])]
}

#[test]
fn emissive_textures_show_at_screen_resolution() {
    let dir = tempfile::tempdir().unwrap();
    let quality = "range_image_size = 16\nsamples_per_pixel = 2\nambient_samples = 16";
    let view = "kind = \"segment\"\na = [-0.5, 1.2, 0.5]\nb = [0.5, 1.2, 0.5]";
    let recipe = common::write_recipe(dir.path(), &scene(), view, quality);
    plenoptic_bake::bake_recipe(&recipe, &plenoptic_bake::BakeOptions::default()).unwrap();
    let scene = plenoptic_scene::load(&dir.path().join("scene.glb")).unwrap();
    let camera = Camera::look_at(
        Vec3::new(0.1, 1.2, 0.5),
        Vec3::new(0.0, 1.2, -1.5),
        Vec3::Y,
        50f32.to_radians(),
        128,
        72,
    )
    .unwrap();
    let (a, b) = common::reference_halves(&scene, &camera, 0.5, 16, 11);
    let rec = Reconstructor::open(dir.path().join("out/scene.pack")).unwrap();
    assert!(rec.pack().runtime_emission(), "pack 4 leaves the emission");
    let (frame, _) = rec.render(&camera, 0.5, Mode::GeometryAssisted).unwrap();
    let panel = rec
        .pack()
        .manifest()
        .objects
        .iter()
        .find(|o| o.name == "panel")
        .unwrap()
        .id;
    let mean: Vec<Vec3> = a
        .pixels
        .iter()
        .zip(&b.pixels)
        .map(|(x, y)| (*x + *y) * 0.5)
        .collect();
    let [rb, rd] = square_means(&camera, &frame.object, panel, &mean);
    let [cb, cd] = square_means(&camera, &frame.object, panel, &frame.radiance);
    // The error on the panel's pixels alone.
    let on_panel = |img: &[Vec3]| Image {
        width: frame.width,
        height: frame.height,
        pixels: img
            .iter()
            .zip(&frame.object)
            .map(|(c, &o)| if o == panel { *c } else { Vec3::ZERO })
            .collect(),
    };
    let recon = on_panel(&frame.radiance);
    let lrms = corrected_relative_lrms(&recon, &on_panel(&a.pixels), &on_panel(&b.pixels));
    let ratio = recon.mean_luminance() / on_panel(&mean).mean_luminance();
    common::save_frames("emission", "", &a, &frame);
    println!(
        "bright / dark squares: reference {rb:.4} / {rd:.4} = {:.2}, runtime {cb:.4} / {cd:.4} \
         = {:.2}; on the panel corrected relative LRMS {:.4}, mean luminance ratio {ratio:.4}",
        rb / rd,
        cb / cd,
        lrms.corrected
    );
    // 2.0 against 0.064 emitted plus what the dark squares reflect: about 29 : 1.
    assert!(
        rb / rd > 10.0,
        "the reference shows the checker: {}",
        rb / rd
    );
    assert!(
        ((cb / cd) / (rb / rd) - 1.0).abs() < 0.15,
        "runtime contrast {} against the reference's {}",
        cb / cd,
        rb / rd
    );
    assert!(
        (cb / rb - 1.0).abs() < 0.05 && (cd / rd - 1.0).abs() < 0.15,
        "bright squares {cb} against {rb}, dark ones {cd} against {rd}"
    );
    assert!(
        lrms.corrected < 0.1,
        "corrected relative LRMS {}",
        lrms.corrected
    );
    assert!((ratio - 1.0).abs() < 0.05, "mean luminance ratio {ratio}");
}
