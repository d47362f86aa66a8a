//! Normal maps at the runtime (docs/architecture.md, "Pack v2", **Materials**): a
//! sunlit floor whose normal map tilts alternate stripes towards and away from the sun. The
//! sun's direct light is left to the runtime (pack 3), which bends each pixel's shading normal
//! as the path tracer does, so the stripes show at screen resolution with the tracer's
//! contrast; without the normal map the floor would be one flat grey (contrast 1). A mirrored
//! copy (negative scale) must lean its stripes the mirrored way, as the tracer leans them.
//! Frames go to `target/tmp/normal_map/`.

mod common;

use glam::{Quat, Vec2, Vec3};
use plenoptic_eval::metrics::corrected_relative_lrms;
use plenoptic_recon::{Camera, Mode, Reconstructor};
use plenoptic_scene::builder::{LightDesc, MaterialDesc, NodeDesc, SceneBuilder};
use plenoptic_trace::Image;
use plenoptic_trace::image::luminance;

/// One floor: how its stripes lean, how its node is placed and where the sunlight travels.
#[derive(Clone, Copy)]
struct Case {
    /// The stripes lean along the tangent (u, x) or, when false, along the bitangent (v).
    along_tangent: bool,
    /// The node's scale: (1, 1, −1) mirrors the floor, as exporters write mirrored copies.
    scale: Vec3,
    /// Where the sunlight travels.
    sun: Vec3,
}

/// The stripes lean towards and away from a sun from −x.
const FACING_THE_SUN: Case = Case {
    along_tangent: true,
    scale: Vec3::ONE,
    sun: Vec3::new(0.5, -1.0, 0.3),
};

/// Texels of the normal map along u; stripes are two texels wide, so that between the
/// centres of a stripe's two texels the bilinear normal is the stripe's own.
const TEXELS: u32 = 32;
/// Floor side (m): u runs along x from −SIDE/2 to SIDE/2.
const SIDE: f32 = 6.0;

/// The tangent-space normal of stripe `s`: even stripes lean 35° towards +tangent (+x, away
/// from the sun of [`FACING_THE_SUN`], which shines from −x), odd ones 35° towards −x; along
/// the bitangent instead unless `along_tangent`.
fn stripe_normal(s: u32, along_tangent: bool) -> Vec3 {
    let (sin, cos) = 35f32.to_radians().sin_cos();
    let lean = if s.is_multiple_of(2) { sin } else { -sin };
    if along_tangent {
        Vec3::new(lean, 0.0, cos)
    } else {
        Vec3::new(0.0, lean, cos)
    }
}

/// A `TEXELS × 4` linear normal map of the stripes.
fn normal_map(along_tangent: bool) -> Vec<u8> {
    let byte = |v: f32| ((v * 0.5 + 0.5) * 255.0).round() as u8;
    (0..4)
        .flat_map(|_| {
            (0..TEXELS).flat_map(move |i| {
                let n = stripe_normal(i / 2, along_tangent);
                [byte(n.x), byte(n.y), byte(n.z), 255]
            })
        })
        .collect()
}

fn scene(case: Case) -> SceneBuilder {
    let mut b = SceneBuilder::new();
    let map = b.add_texture_rgba8(TEXELS, 4, normal_map(case.along_tangent));
    let floor = b.add_material(MaterialDesc::diffuse(Vec3::splat(0.6)).normal_texture(map));
    let plane = b.add_plane("floor", Vec2::splat(SIDE), 1, floor);
    b.add_node(NodeDesc::new("floor").mesh(plane).scale(case.scale));
    b.add_node(
        NodeDesc::new("sun")
            .light(LightDesc::directional(Vec3::ONE, 3.0))
            .rotation(Quat::from_rotation_arc(Vec3::NEG_Z, case.sun.normalize())),
    );
    b
}

/// Mean luminance of `pixels` over the floor pixels of each stripe parity (even, odd), only
/// where the stripe's normal is its own (the middle of the stripe).
fn stripe_means(camera: &Camera, object: &[u32], floor: u32, pixels: &[Vec3]) -> [f64; 2] {
    let basis = camera.basis();
    let w = camera.width as usize;
    let mut sums = [(0.0, 0usize); 2];
    for (j, c) in pixels.iter().enumerate() {
        if object[j] != floor {
            continue;
        }
        let d = basis.direction((j % w) as f32 + 0.5, (j / w) as f32 + 0.5);
        if d.y >= -1e-3 {
            continue;
        }
        let p = basis.position + d * (-basis.position.y / d.y);
        let x = (p.x / SIDE + 0.5) * TEXELS as f32 / 2.0;
        let f = x - x.floor();
        if !(0.3..=0.7).contains(&f) {
            continue;
        }
        let parity = (x.floor() as i64).rem_euclid(2) as usize;
        sums[parity].0 += f64::from(luminance(*c));
        sums[parity].1 += 1;
    }
    assert!(sums.iter().all(|s| s.1 > 20), "stripe pixels: {sums:?}");
    sums.map(|(s, n)| s / n as f64)
}

/// Bakes `case`, renders it at the runtime and against the path tracer, writes the frames
/// to `target/tmp/normal_map/{name}_*.png` and returns (the reference's contrast, the
/// runtime's contrast, corrected relative LRMS, mean-luminance ratio), each contrast the odd
/// stripes' mean over the even ones'.
fn run(case: Case, name: &str) -> (f64, f64, f64, f64) {
    let dir = tempfile::tempdir().unwrap();
    let quality = "range_image_size = 16\nsamples_per_pixel = 2\nambient_samples = 16";
    let view = "kind = \"segment\"\na = [-0.5, 1.2, -1.5]\nb = [0.5, 1.2, -1.5]";
    let recipe = common::write_recipe(dir.path(), &scene(case), view, quality);
    plenoptic_bake::bake_recipe(&recipe, &plenoptic_bake::BakeOptions::default()).unwrap();
    let scene = plenoptic_scene::load(&dir.path().join("scene.glb")).unwrap();
    let camera = Camera::look_at(
        Vec3::new(0.2, 1.4, -2.0),
        Vec3::new(0.2, 0.0, 0.4),
        Vec3::Y,
        50f32.to_radians(),
        96,
        54,
    )
    .unwrap();
    let (a, b) = common::reference_halves(&scene, &camera, 0.5, 32, 7);
    let rec = Reconstructor::open(dir.path().join("out/scene.pack")).unwrap();
    assert!(
        rec.runtime_sun().is_some(),
        "the sun is left to the runtime"
    );
    let (frame, _) = rec.render(&camera, 0.5, Mode::GeometryAssisted).unwrap();
    let floor = rec.pack().manifest().objects[0].id;
    let mean: Vec<Vec3> = a
        .pixels
        .iter()
        .zip(&b.pixels)
        .map(|(x, y)| (*x + *y) * 0.5)
        .collect();
    let [re, ro] = stripe_means(&camera, &frame.object, floor, &mean);
    let [ce, co] = stripe_means(&camera, &frame.object, floor, &frame.radiance);
    let recon = Image {
        width: frame.width,
        height: frame.height,
        pixels: frame.radiance.clone(),
    };
    let lrms = corrected_relative_lrms(&recon, &a, &b);
    let ratio = recon.mean_luminance() / (0.5 * (a.mean_luminance() + b.mean_luminance()));
    common::save_frames("normal_map", &format!("{name}_"), &a, &frame);
    println!(
        "{name}: odd stripes / even: reference {ro:.4} / {re:.4} = {:.3}, runtime {co:.4} / \
         {ce:.4} = {:.3}; corrected relative LRMS {:.4}, mean luminance ratio {ratio:.4}",
        ro / re,
        co / ce,
        lrms.corrected
    );
    (ro / re, co / ce, lrms.corrected, ratio)
}

#[test]
fn normal_maps_bend_the_runtime_suns_light_as_the_tracer_does() {
    let (reference, runtime, _, ratio) = run(FACING_THE_SUN, "plain");
    // The odd stripes lean towards the sun: cos 0.93 against 0.45 for the even ones.
    assert!(
        reference > 1.6,
        "the reference shows the stripes: {reference}"
    );
    assert!(
        (runtime / reference - 1.0).abs() < 0.1,
        "runtime contrast {runtime} against the reference's {reference}"
    );
    assert!((ratio - 1.0).abs() < 0.05, "mean luminance ratio {ratio}");
}

/// A mirrored floor (scale z = −1) whose stripes lean along the bitangent, under a sun from
/// −z: which stripes face the sun depends on the bitangent's handedness, which the mirror
/// flips. The runtime must flip it as the tracer does (or the contrast comes out inverted).
#[test]
fn a_mirrored_normal_map_leans_the_same_way_at_the_runtime() {
    let case = Case {
        along_tangent: false,
        scale: Vec3::new(1.0, 1.0, -1.0),
        sun: Vec3::new(0.3, -1.0, 0.5),
    };
    let (reference, runtime, _, ratio) = run(case, "mirrored");
    // One parity faces the sun, the other leans away from it.
    assert!(
        reference.max(1.0 / reference) > 1.4,
        "the reference shows the stripes: {reference}"
    );
    assert!(
        (runtime / reference - 1.0).abs() < 0.1,
        "runtime contrast {runtime} against the reference's {reference}"
    );
    assert!((ratio - 1.0).abs() < 0.05, "mean luminance ratio {ratio}");
}
