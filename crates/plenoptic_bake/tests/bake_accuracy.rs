//! The bake's lighting at base views against the reference path tracer (docs/architecture.md,
//! "Pack v2": the baked lighting agrees with the path tracer within its noise). A camera at a base view at one of its time keys sees what the range
//! images hold: the multi-stage renderer over the bake's ambient field. Its frame is compared
//! with a path-traced reference rendered as two independent halves, so that the reference's
//! own noise is subtracted from the error (`plenoptic_eval::metrics`; docs/architecture.md,
//! "Measuring against a noisy reference"). The figures: docs/bake-accuracy.md.

use std::path::Path;

use glam::{Quat, Vec3};
use plenoptic_bake::denoise::{DenoiseSettings, LightingCube, denoise};
use plenoptic_bake::plan::ambient;
use plenoptic_bake::render::final_gather_rays;
use plenoptic_eval::metrics::corrected_relative_lrms;
use plenoptic_scene::Scene;
use plenoptic_scene::recipe::Quality;
use plenoptic_trace::image::luminance;
use plenoptic_trace::{
    AmbientField, Image, MultiStageRenderer, MultiStageSettings, PathTracer, PathTracerSettings,
    PinholeCamera, SceneAccel,
};

/// What one base-view frame measured.
#[derive(Debug, Clone, Copy)]
struct Figures {
    /// Mean luminance of the bake's frame over the reference's.
    mean_ratio: f64,
    /// Fraction of 8×8 blocks whose mean is within 5 % of the reference's.
    blocks_within: f64,
    /// Relative LRMS with the reference's variance subtracted.
    corrected_lrms: f64,
    /// Relative LRMS of the reference's own noise (of the mean of the halves).
    noise_floor: f64,
}

fn lum(img: &Image<Vec3>) -> Vec<f64> {
    img.pixels
        .iter()
        .map(|&c| f64::from(luminance(c)))
        .collect()
}

impl std::fmt::Display for Figures {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "mean {:.3}, blocks within 5 % {:.2}, corrected LRMS {:.3} (noise floor {:.3})",
            self.mean_ratio, self.blocks_within, self.corrected_lrms, self.noise_floor
        )
    }
}

/// A 70° camera at `p` turned by `yaw` about +Y, then tilted by `pitch`.
fn camera(p: Vec3, yaw: f32, pitch: f32, w: u32, h: u32) -> PinholeCamera {
    let rotation = Quat::from_rotation_y(yaw) * Quat::from_rotation_x(pitch);
    PinholeCamera::new(p, rotation, 70f32.to_radians(), w, h).unwrap()
}

/// Two independent path-traced halves of `spp` samples per pixel in all (seeds 11 and 12).
fn reference_halves(
    placed: &plenoptic_trace::PlacedScene<'_>,
    camera: &PinholeCamera,
    spp: u32,
) -> (Image<Vec3>, Image<Vec3>) {
    let half = |seed| {
        PathTracer::new(PathTracerSettings {
            samples_per_pixel: spp / 2,
            max_depth: 32,
            rr_start_depth: 5,
            seed,
            environment_sampling: true,
        })
        .render(placed, camera)
        .radiance()
    };
    (half(11), half(12))
}

fn measure(test: &Image<Vec3>, a: &Image<Vec3>, b: &Image<Vec3>) -> Figures {
    let c = corrected_relative_lrms(test, a, b);
    let (t, a_l, b_l) = (lum(test), lum(a), lum(b));
    let r: Vec<f64> = a_l.iter().zip(&b_l).map(|(x, y)| 0.5 * (x + y)).collect();
    let (w, h) = (test.width as usize, test.height as usize);
    let (mut blocks, mut within) = (0usize, 0usize);
    for by in 0..h / 8 {
        for bx in 0..w / 8 {
            let (mut st, mut sr, mut sa, mut sb) = (0.0, 0.0, 0.0, 0.0);
            for y in by * 8..by * 8 + 8 {
                for x in bx * 8..bx * 8 + 8 {
                    st += t[y * w + x];
                    sr += r[y * w + x];
                    sa += a_l[y * w + x];
                    sb += b_l[y * w + x];
                }
            }
            blocks += 1;
            if sr > 0.0 && (st / sr - 1.0).abs() <= 0.05 {
                within += 1;
            } else {
                // How far the reference's own halves disagree there: a block whose halves
                // differ by several per cent is beyond what this reference can judge.
                println!(
                    "   block ({bx}, {by}): bake / reference {:.3}, half A / half B {:.3}, \
                     reference mean {:.4}",
                    st / sr,
                    sa / sb,
                    sr / 64.0
                );
            }
        }
    }
    Figures {
        mean_ratio: c.mean_ratio,
        blocks_within: within as f64 / blocks.max(1) as f64,
        corrected_lrms: c.corrected,
        noise_floor: c.noise_floor,
    }
}

/// The bake's ambient field for `quality` at `t`.
fn bake_field(accel: &SceneAccel<'_>, quality: &Quality, t: f32) -> AmbientField {
    AmbientField::build(&accel.at_time(t), &ambient::settings(quality, 7)).unwrap()
}

/// Renders the bake's view of `camera` at the field's time (the multi-stage renderer over
/// the bake's ambient field, as for a range image) and a two-half path-traced reference.
/// The reference gets `reference_spp` samples per pixel in all, the bake's frame `bake_spp`
/// (1024 or more, so that what is measured is its lighting, not its pixel noise: the
/// corrected error subtracts only the reference's noise). Images go to
/// `target/tmp/bake_accuracy/`.
fn base_view_frame(
    name: &str,
    accel: &SceneAccel<'_>,
    field: &AmbientField,
    camera: &PinholeCamera,
    (reference_spp, bake_spp): (u32, u32),
) -> Figures {
    let placed = accel.at_time(field.time());
    let start = std::time::Instant::now();
    let ms = MultiStageRenderer::new(
        MultiStageSettings {
            samples_per_pixel: bake_spp,
            shadow_samples: 2,
            glossy_samples: 2,
            max_specular_depth: 4,
            seed: 3,
            // The bake's final gather, with 4× its rays per sample at 256-px faces: the
            // expectation is the bake's, and the frame's own noise (which the corrected error
            // does not subtract; the bake smooths it out of its texels) a quarter.
            final_gather: 4 * final_gather_rays(256),
        },
        field,
    )
    .render(&placed, camera)
    .radiance();
    let ms_time = start.elapsed().as_secs_f64();
    let (a, b) = reference_halves(&placed, camera, reference_spp);
    // Where the error is: the pixels that contribute most to it.
    {
        let (t, al, bl) = (lum(&ms), lum(&a), lum(&b));
        let mut e: Vec<(f64, usize)> = (0..t.len())
            .map(|i| {
                (
                    (t[i] - 0.5 * (al[i] + bl[i])).powi(2) - (al[i] - bl[i]).powi(2) / 4.0,
                    i,
                )
            })
            .collect();
        e.sort_by(|x, y| y.0.total_cmp(&x.0));
        let total: f64 = e.iter().map(|x| x.0).sum();
        for &(v, i) in e.iter().take(3) {
            println!(
                "   worst ({}, {}): bake {:.3} ref {:.3}/{:.3}, share {:.2}",
                i % camera.width as usize,
                i / camera.width as usize,
                t[i],
                al[i],
                bl[i],
                v / total
            );
        }
    }
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("bake_accuracy");
    std::fs::create_dir_all(&dir).unwrap();
    let file = name.replace([' ', ','], "_").replace("__", "_");
    let exposure = 0.5 / a.mean_luminance() as f32;
    ms.save_png(dir.join(format!("{file}_bake.png")), exposure)
        .unwrap();
    a.save_png(dir.join(format!("{file}_reference.png")), exposure)
        .unwrap();
    println!(
        "  multi-stage {ms_time:.2} s, reference {:.2} s",
        start.elapsed().as_secs_f64() - ms_time
    );
    measure(&ms, &a, &b)
}

/// Two rooms side by side, 8 × 4 m and 2.5 m high, built as exporters build them: boxes for
/// floor, ceiling and walls that run into each other (the floor runs under the walls, the
/// walls cross at the corners). Room 1 (x < 0) gets the sun through an open south window
/// and has a mirror on its north wall; room 2 is lit only by light coming through the
/// doorway in the wall between them.
fn two_rooms() -> Scene {
    use plenoptic_scene::Trs;
    use plenoptic_scene::builder::{LightDesc, MaterialDesc, NodeDesc, SceneBuilder};
    let mut b = SceneBuilder::new();
    let wall = b.add_material(MaterialDesc::diffuse(Vec3::new(0.8, 0.78, 0.74)).named("plaster"));
    let floor = b.add_material(MaterialDesc::diffuse(Vec3::new(0.55, 0.4, 0.28)).named("wood"));
    let mirror = b.add_material(MaterialDesc::metal(Vec3::splat(0.95), 0.0).named("mirror"));
    let mut slab = |name: &str, min: Vec3, max: Vec3, m| {
        let mesh = b.add_box(name, max - min, m);
        b.add_node(NodeDesc::new(name).mesh(mesh).transform(Trs {
            translation: (min + max) * 0.5,
            ..Trs::default()
        }));
    };
    let v = Vec3::new;
    slab("Floor", v(-4.1, -0.1, -2.1), v(4.1, 0.0, 2.1), floor);
    slab("Ceiling", v(-4.1, 2.5, -2.1), v(4.1, 2.6, 2.1), wall);
    slab("Wall_West", v(-4.1, -0.1, -2.1), v(-4.0, 2.6, 2.1), wall);
    slab("Wall_East", v(4.0, -0.1, -2.1), v(4.1, 2.6, 2.1), wall);
    slab("Wall_North", v(-4.1, -0.1, 2.0), v(4.1, 2.6, 2.1), wall);
    // South wall with a window in room 1 (x ∈ [−2.8, −1.2], y ∈ [0.8, 2.0]).
    slab(
        "Wall_South_1",
        v(-4.1, -0.1, -2.1),
        v(-2.8, 2.6, -2.0),
        wall,
    );
    slab("Wall_South_2", v(-1.2, -0.1, -2.1), v(4.1, 2.6, -2.0), wall);
    slab(
        "Wall_South_Sill",
        v(-2.8, -0.1, -2.1),
        v(-1.2, 0.8, -2.0),
        wall,
    );
    slab(
        "Wall_South_Head",
        v(-2.8, 2.0, -2.1),
        v(-1.2, 2.6, -2.0),
        wall,
    );
    // The wall between the rooms, a doorway (z ∈ [−0.5, 0.5], 2.1 m high) in the middle.
    slab(
        "Wall_Middle_1",
        v(-0.05, -0.1, -2.1),
        v(0.05, 2.6, -0.5),
        wall,
    );
    slab(
        "Wall_Middle_2",
        v(-0.05, -0.1, 0.5),
        v(0.05, 2.6, 2.1),
        wall,
    );
    slab(
        "Wall_Middle_Head",
        v(-0.05, 2.1, -0.5),
        v(0.05, 2.6, 0.5),
        wall,
    );
    slab("Mirror", v(-3.0, 0.6, 1.97), v(-1.0, 2.0, 2.0), mirror);
    let sun = Vec3::new(0.25, -0.55, 1.0).normalize();
    b.add_node(
        NodeDesc::new("Sun")
            .translation(Vec3::new(0.0, 20.0, 0.0))
            .rotation(Quat::from_rotation_arc(Vec3::NEG_Z, sun))
            .light(LightDesc::directional(Vec3::new(1.0, 0.95, 0.85), 6.0).named("Sun")),
    );
    let bytes = b.to_glb_bytes().unwrap();
    plenoptic_scene::load_slice(&bytes, "two_rooms.glb", None).unwrap()
}

/// The CI's base views of the two rooms: (name, position, yaw, pitch).
const VIEWS: [(&str, Vec3, f32, f32); 4] = [
    ("sunlit floor", Vec3::new(-3.0, 1.6, -1.0), 0.6, -0.6),
    ("mirror", Vec3::new(-1.0, 1.6, -1.2), 2.7, -0.1),
    (
        "indirect room, doorway",
        Vec3::new(3.0, 1.6, 0.5),
        1.3,
        -0.25,
    ),
    (
        "indirect room, corner",
        Vec3::new(1.5, 1.6, -1.0),
        -2.4,
        -0.3,
    ),
];

/// Four base views of the two rooms (the draft bake's ambient field): the sunlit floor, the
/// mirror, and two views of the room lit only indirectly. Mean luminance within 3 %, 8 × 8
/// block means within 5 % for 90 % of blocks, corrected relative LRMS ≤ 0.10.
#[test]
fn base_views_agree_with_the_path_tracer() {
    let scene = two_rooms();
    let accel = SceneAccel::new(&scene).unwrap();
    let start = std::time::Instant::now();
    let field = bake_field(&accel, &Quality::draft(), 0.0);
    println!(
        "field: {} points, {} inside solids, {} bounces, {:.2} s",
        field.layout().point_count(),
        field.invalid_points(),
        field.bounces(),
        start.elapsed().as_secs_f64()
    );
    let (w, h) = (32, 24);
    let views = VIEWS;
    let mut failures = Vec::new();
    for (name, p, yaw, pitch) in views {
        let f = base_view_frame(
            name,
            &accel,
            &field,
            &camera(p, yaw, pitch, w, h),
            (4096, 1024),
        );
        println!("{name}: {f}");
        if (f.mean_ratio - 1.0).abs() > 0.03 || f.blocks_within < 0.9 || f.corrected_lrms > 0.1 {
            failures.push((name, f));
        }
    }
    assert!(failures.is_empty(), "{failures:?}");
}

/// A camera's view of a range image: each pixel the mean of `k × k` jittered rays' nearest
/// texels (the reference integrates the pixel's footprint too).
fn view_of_cube(cube: &plenoptic_pack::RangeImage, camera: &PinholeCamera, k: u32) -> Image<Vec3> {
    use plenoptic_trace::Camera;
    Image::render(camera.width, camera.height, |x, y| {
        let mut sum = Vec3::ZERO;
        for sy in 0..k {
            for sx in 0..k {
                let o = glam::Vec2::new((sx as f32 + 0.5) / k as f32, (sy as f32 + 0.5) / k as f32);
                let ray = camera.ray(x, y, o).unwrap();
                sum += *cube.radiance.lookup(ray.direction).unwrap();
            }
        }
        sum / (k * k) as f32
    })
}

/// The range images the draft bake stores at the four base views of
/// [`base_views_agree_with_the_path_tracer`] (face size, samples per pixel and specular depth
/// of `Quality::draft()`), seen through the same cameras and through 3× sharper ones, against
/// the two-half reference: the denoiser off, on (default settings and two variants, on the
/// same rendered faces), and off at 8× the samples (what less noise alone would give).
/// Prints the figures of docs/bake-accuracy.md; checks only that no variant biases the mean.
#[test]
#[ignore = "minutes in release: cargo test --release -p plenoptic_bake --test bake_accuracy -- --ignored --nocapture denoising"]
fn range_images_with_and_without_denoising() {
    let d = DenoiseSettings::default();
    let variants = [
        ("on (default)", d),
        ("on, 3 passes", DenoiseSettings { passes: 3, ..d }),
        (
            "on, σℓ = 1",
            DenoiseSettings {
                sigma_luminance: 1.0,
                ..d
            },
        ),
    ];
    denoise_sweep(&[0, 1, 2, 3], &variants);
}

/// Off, each of `variants`, and off at 8× the samples, at the views numbered `which`.
fn denoise_sweep(which: &[usize], variants: &[(&str, DenoiseSettings)]) {
    let scene = two_rooms();
    let accel = SceneAccel::new(&scene).unwrap();
    let quality = Quality::draft();
    let field = bake_field(&accel, &quality, 0.0);
    let placed = accel.at_time(0.0);
    let views = VIEWS;
    let renderer = |spp| {
        MultiStageRenderer::new(
            MultiStageSettings {
                samples_per_pixel: spp,
                shadow_samples: 2,
                glossy_samples: 2,
                max_specular_depth: quality.max_specular_depth,
                seed: 5,
                final_gather: 0,
            },
            &field,
        )
    };
    let n = quality.range_image_size;
    let spp = quality.samples_per_pixel;
    println!(
        "range images {n} px, {spp} spp; default denoiser {:?}",
        DenoiseSettings::default()
    );
    let mut biased = Vec::new();
    for &(name, p, yaw, pitch) in which.iter().map(|&i| &views[i]) {
        let cube = plenoptic_trace::CubeCamera::new(p, n).unwrap();
        let faces = renderer(spp).render_cube(&placed, &cube);
        let mut images = vec![(
            format!("off, {spp} spp"),
            plenoptic_bake::render::to_range_image(n, &faces),
        )];
        for &(label, settings) in variants {
            let start = std::time::Instant::now();
            let mut lighting = LightingCube::from_faces(n, &faces);
            denoise(&mut lighting, &settings);
            let label = format!("{label} ({:.1} s)", start.elapsed().as_secs_f64());
            images.push((label, lighting.to_range_image()));
        }
        let faces = renderer(8 * spp).render_cube(&placed, &cube);
        images.push((
            format!("off, {} spp", 8 * spp),
            plenoptic_bake::render::to_range_image(n, &faces),
        ));
        for (w, h, ref_spp) in [(32, 24, 4096), (96, 72, 1024)] {
            let cam = camera(p, yaw, pitch, w, h);
            let (a, b) = reference_halves(&placed, &cam, ref_spp);
            println!("{name}, camera {w} × {h}, reference {ref_spp} spp:");
            for (label, image) in &images {
                let f = measure(&view_of_cube(image, &cam, 6), &a, &b);
                println!("  {label}: {f}");
                if (f.mean_ratio - 1.0).abs() > 0.03 {
                    biased.push((name, w, label.clone(), f));
                }
            }
        }
    }
    assert!(biased.is_empty(), "{biased:?}");
}

fn tour_scene() -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples/architectural_tour/assets/tour.glb");
    plenoptic_scene::load(&path).unwrap()
}

/// The tour's base views measured, each at one of its time keys: (name, position, time,
/// yaw, pitch).
const TOUR_VIEWS: [(&str, Vec3, f32, f32, f32); 5] = [
    // Base view 12, which the lattice puts between the slabs of the revolving sculpture at
    // (0, 1.6, 0), where the plan moves it (plan::clearance).
    (
        "atrium centre, t = 0",
        Vec3::new(-0.191, 1.6, -0.462),
        0.0,
        0.0,
        -0.35,
    ),
    ("room B, t = 3.5", Vec3::new(5.5, 1.6, 2.5), 3.5, 1.2, -0.4),
    (
        "room A, t = 10.5",
        Vec3::new(-5.5, 1.6, -2.5),
        10.5,
        -2.4,
        -0.3,
    ),
    (
        "atrium south, t = 7",
        Vec3::new(0.0, 1.6, 2.5),
        7.0,
        3.0,
        -0.45,
    ),
    // Base view 12's neighbour on the lattice towards the north, looking back across the
    // atrium.
    (
        "atrium north, t = 0",
        Vec3::new(0.0, 1.6, -2.5),
        0.0,
        std::f32::consts::PI,
        -0.35,
    ),
];

/// The tour at five base views of its draft bake (the 5 × 5 lattice over its view space), each
/// at a time key, against the targets of docs/bake-accuracy.md. Slow (minutes in release).
#[test]
#[ignore = "minutes in release: cargo test --release -p plenoptic_bake --test bake_accuracy -- --ignored --nocapture"]
fn tour_base_views() {
    let scene = tour_scene();
    let accel = SceneAccel::new(&scene).unwrap();
    let quality = Quality::draft();
    let (w, h) = (80, 48);
    let views = TOUR_VIEWS;
    let mut failures = Vec::new();
    for (i, (name, p, t, yaw, pitch)) in views.into_iter().enumerate() {
        // The atrium's centre looks at dim surfaces: at 2 × 1024 the reference's own noise
        // (floor 0.164) put a tenth of its blocks' halves 3–6 % apart, too close to the 5 %
        // judged. Four times the samples there, on both sides.
        let spp = if i == 0 { 4096 } else { 1024 };
        let start = std::time::Instant::now();
        let field = bake_field(&accel, &quality, t);
        println!(
            "{name}: field {} points, {} inside solids, {} bounces, {:.1} s",
            field.layout().point_count(),
            field.invalid_points(),
            field.bounces(),
            start.elapsed().as_secs_f64()
        );
        let f = base_view_frame(
            name,
            &accel,
            &field,
            &camera(p, yaw, pitch, w, h),
            (spp, spp),
        );
        println!("{name}: {f}");
        // The targets, at every view.
        if (f.mean_ratio - 1.0).abs() > 0.03 || f.blocks_within < 0.9 || f.corrected_lrms > 0.1 {
            failures.push((name, f));
        }
    }
    assert!(failures.is_empty(), "{failures:?}");
}

/// The tour as its recipe bakes it (the sun study and the sky applied), at base view 13
/// (0, 1.6, 2.5) looking north across the atrium at the time key t = 10.5: the view that
/// shows glass seen from behind letting the field through (docs/bake-accuracy.md, cause 5).
/// Prints the figures of docs/bake-accuracy.md. Slow (minutes in release).
#[test]
#[ignore = "minutes in release: cargo test --release -p plenoptic_bake --test bake_accuracy -- --ignored --nocapture atrium"]
fn tour_atrium_under_its_daylight() {
    let recipe = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples/architectural_tour/assets/tour.toml");
    let (_, scene) = plenoptic_bake::input::load_recipe(&recipe).unwrap();
    let accel = SceneAccel::new(&scene).unwrap();
    let field = bake_field(&accel, &Quality::draft(), 10.5);
    let name = "atrium north under daylight, t = 10.5";
    let cam = camera(Vec3::new(0.0, 1.6, 2.5), 0.0, 0.0, 64, 40);
    // 8 × 8 blocks of 64 pixels, judged to 5 %: at 2 × 1024 reference samples and 1024 for
    // the bake, the two frames' own noise (the halves disagreed by up to 2.6 % on a block)
    // put 85 % of the blocks within; at these counts 93 %, the same three blocks outside.
    let f = base_view_frame(name, &accel, &field, &cam, (8192, 4096));
    println!("{name}: {f}");
}

/// The tour's range images as the draft bake stores them (256-px faces, 4 samples per
/// texel), seen through the cameras of [`tour_base_views`]: the field read directly at
/// each texel (what cause 6 of docs/bake-accuracy.md is about) against the final gather
/// of the bake, without and with its ambient smoothing (`LightingCube::smooth_ambient`,
/// 2–4 passes). Prints the figures of docs/bake-accuracy.md.
#[test]
#[ignore = "minutes in release: cargo test --release -p plenoptic_bake --test bake_accuracy -- --ignored --nocapture tour_range_images"]
fn tour_range_images_with_and_without_the_final_gather() {
    let scene = tour_scene();
    let accel = SceneAccel::new(&scene).unwrap();
    let quality = Quality::draft();
    // Room B, room A and the atrium's south.
    let views = &TOUR_VIEWS[1..4];
    let n = quality.range_image_size;
    for &(name, p, t, yaw, pitch) in views {
        let field = bake_field(&accel, &quality, t);
        let placed = accel.at_time(t);
        let cam = camera(p, yaw, pitch, 80, 48);
        let (a, b) = reference_halves(&placed, &cam, 1024);
        for final_gather in [0, final_gather_rays(n)] {
            let renderer = MultiStageRenderer::new(
                MultiStageSettings {
                    samples_per_pixel: quality.samples_per_pixel,
                    shadow_samples: 2,
                    glossy_samples: 2,
                    max_specular_depth: quality.max_specular_depth,
                    seed: 5,
                    final_gather,
                },
                &field,
            );
            let start = std::time::Instant::now();
            let cube = plenoptic_trace::CubeCamera::new(p, n).unwrap();
            let faces = renderer.render_cube(&placed, &cube);
            let secs = start.elapsed().as_secs_f64();
            let passes: &[u32] = if final_gather == 0 {
                &[0]
            } else {
                &[0, 2, 3, 4]
            };
            let mut unsmoothed = None;
            for &k in passes {
                let mut lighting = LightingCube::from_faces(n, &faces);
                if k > 0 {
                    lighting.smooth_ambient(k);
                }
                let f = measure(&view_of_cube(&lighting.to_range_image(), &cam, 6), &a, &b);
                println!(
                    "{name}: final gather {final_gather}, smoothing {k} passes: {f} \
                     (faces rendered in {secs:.1} s)"
                );
                // The smoothing is linear in the lighting, so it barely moves the frame's mean
                // (by up to 1.3 %, room A at 4 passes: texels reweighted by the camera and
                // multiplied by their own albedo). The denoiser with its luminance weight
                // moved it by 5–7 %.
                let m0 = *unsmoothed.get_or_insert(f.mean_ratio);
                assert!(
                    (f.mean_ratio / m0 - 1.0).abs() < 0.02,
                    "{name}: smoothing moved the mean {m0} → {}",
                    f.mean_ratio
                );
            }
        }
    }
}
