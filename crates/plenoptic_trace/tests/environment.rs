//! The environment light in both tracers, against known answers:
//!
//! - a uniform sky of radiance L over an open Lambertian plane gives irradiance πL, so the
//!   plane's radiance is ρL;
//! - a horizontal plane under the Hosek–Wilkie sky gets the irradiance the model integrates
//!   to (a fine quadrature of `plenoptic_sky`'s radiance over the hemisphere);
//! - a BLEND pane of alpha 0.25 over the plane transmits 75 % of the sky and of the sun;
//! - the sun's disc softens shadow edges over the width its angular size predicts;
//! - a room lit by the sky through one window: the multi-stage renderer against the path
//!   tracer.

mod common;

use common::{mean_and_se, out_dir};
use glam::{Vec2, Vec3, Vec4};
use plenoptic_scene::builder::shapes::{cuboid, plane};
use plenoptic_scene::{AlphaMode, Environment, Light, LightKind, Material, Node, Scene, Sun, Trs};
use plenoptic_sky::{SkyParams, SunTrack};
use plenoptic_trace::image::luminance;
use plenoptic_trace::metrics::relative_lrms;
use plenoptic_trace::shapes::{SceneBuilder, diffuse, sky_lit_room, sky_room_camera};
use plenoptic_trace::{
    AmbientField, AmbientSettings, Image, MultiStageRenderer, MultiStageSettings, PathTracer,
    PathTracerSettings, PinholeCamera, RadianceSample, SceneAccel,
};
use std::f32::consts::PI;

const ALBEDO: f32 = 0.5;

fn pt(spp: u32, seed: u64) -> PathTracer {
    PathTracer::new(PathTracerSettings {
        samples_per_pixel: spp,
        max_depth: 32,
        rr_start_depth: 3,
        seed,
        environment_sampling: true,
    })
}

fn ms(spp: u32, shadow: u32) -> MultiStageSettings {
    MultiStageSettings {
        samples_per_pixel: spp,
        shadow_samples: shadow,
        glossy_samples: 1,
        max_specular_depth: 4,
        seed: 11,
        final_gather: 0,
    }
}

/// A 40 m Lambertian floor at y = 0 and nothing else.
fn open_floor() -> SceneBuilder {
    let mut b = SceneBuilder::default();
    let m = b.material(diffuse(Vec3::splat(ALBEDO)));
    b.object("Floor", plane(Vec2::splat(40.0), 1), m, Vec3::ZERO);
    b
}

fn down_camera(size: u32) -> PinholeCamera {
    PinholeCamera::look_at(
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::ZERO,
        Vec3::Z,
        1.2,
        size,
        size,
    )
    .unwrap()
}

fn both(
    scene: &Scene,
    camera: &PinholeCamera,
    spp: u32,
) -> [(&'static str, Image<RadianceSample>); 2] {
    let accel = SceneAccel::new(scene).unwrap();
    let placed = accel.at_time(0.0);
    // Many gather rays: the open plane has few field points, and the field's noise is what
    // these tests would otherwise measure.
    let settings = AmbientSettings {
        rays_per_point: 2048,
        ..AmbientSettings::low()
    };
    let field = AmbientField::build(&placed, &settings).unwrap();
    [
        ("PT", pt(spp, 3).render(&placed, camera)),
        (
            "MS",
            MultiStageRenderer::new(ms(spp, 4), &field).render(&placed, camera),
        ),
    ]
}

#[test]
fn a_uniform_sky_gives_pi_l_over_a_plane() {
    let l = Vec3::new(0.8, 1.0, 1.3);
    let mut scene = open_floor().build();
    scene.environment = Environment::Uniform(l);
    let want = f64::from(ALBEDO * luminance(l));
    for (name, img) in both(&scene, &down_camera(32), 16) {
        let (mean, se) = mean_and_se(&img.radiance());
        println!(
            "uniform sky {name}: {:.5} (want {want:.5}, se {se:.5})",
            mean / want
        );
        assert!((mean / want - 1.0).abs() < 0.01, "{name}: {mean} vs {want}");
    }
}

/// The model's irradiance on a horizontal plane (midpoint rule, 600 × 2400 cells).
fn sky_irradiance(scene: &Scene) -> f64 {
    f64::from(luminance(
        scene.environment_at(0.0).horizontal_irradiance(600),
    ))
}

/// A sun light (no intensity: only its direction drives the sky) at `elevation_deg`.
fn add_sky(scene: &mut Scene, towards_sun: Vec3, sun_lux: f32, disc: f32) {
    scene.nodes.push(Node {
        name: "Sun".into(),
        parent: None,
        rest: Trs::default(),
        track: None,
    });
    scene.lights.push(Light {
        name: "Sun".into(),
        kind: LightKind::Directional,
        color: Vec3::ONE,
        intensity: sun_lux,
        range: None,
        angular_radius: disc,
        node: scene.nodes.len() - 1,
    });
    scene.sun = Some(Sun {
        light: scene.lights.len() - 1,
        track: Some(SunTrack::fixed(towards_sun, Vec3::splat(sun_lux))),
    });
    scene.environment = Environment::Sky(SkyParams {
        scale: 1.0,
        ..SkyParams::default()
    });
}

#[test]
fn a_plane_under_the_sky_gets_the_irradiance_the_model_integrates_to() {
    let mut scene = open_floor().build();
    let sun = Vec3::new(0.4, 0.5, -0.6).normalize();
    add_sky(&mut scene, sun, 0.0, 0.0);
    let e = sky_irradiance(&scene);
    let want = f64::from(ALBEDO) / f64::from(PI) * e;
    for (name, img) in both(&scene, &down_camera(32), 16) {
        let (mean, se) = mean_and_se(&img.radiance());
        println!(
            "Hosek–Wilkie sky {name}: {:.5} of the integral (se {:.5})",
            mean / want,
            se / want
        );
        assert!((mean / want - 1.0).abs() < 0.01, "{name}: {mean} vs {want}");
    }
}

#[test]
fn a_pane_of_alpha_a_quarter_transmits_three_quarters_of_sun_and_sky() {
    let camera = down_camera(32);
    let sun_dir = Vec3::new(0.2, 0.9, 0.1).normalize();
    let mut open = open_floor().build();
    add_sky(&mut open, sun_dir, 3.0, 0.0);
    let mut b = open_floor();
    let pane = b.material(Material {
        base_color: Vec4::new(0.0, 0.0, 0.0, 0.25),
        alpha_mode: AlphaMode::Blend,
        double_sided: true,
        ..diffuse(Vec3::ZERO)
    });
    // 400 m wide at 1.5 m: it hides all but 1e-5 of the cosine-weighted sky.
    b.object(
        "Pane",
        plane(Vec2::splat(400.0), 1),
        pane,
        Vec3::new(0.0, 1.5, 0.0),
    );
    let mut covered = b.build();
    add_sky(&mut covered, sun_dir, 3.0, 0.0);
    for ((name, a), (_, b)) in both(&open, &camera, 32)
        .into_iter()
        .zip(both(&covered, &camera, 32))
    {
        let (m0, _) = mean_and_se(&a.radiance());
        let (m1, se) = mean_and_se(&b.radiance());
        let ratio = m1 / m0;
        println!(
            "BLEND 0.25 under sun and sky {name}: {ratio:.4} (se {:.4})",
            se / m0
        );
        assert!((ratio - 0.75).abs() < 0.015, "{name}: {ratio}");
    }
}

#[test]
fn the_suns_disc_gives_a_penumbra_of_its_angular_size() {
    // A 2 m high wall edge along z at x = 0 casts a shadow on the floor; the sun stands 45°
    // up in the −x half plane. The penumbra on the floor is h/sin²(45°)·2r wide across x.
    let towards = Vec3::new(-1.0, 1.0, 0.0).normalize();
    let r = 0.02; // a sun four times wider than the real one, for a measurable penumbra
    let mut b = open_floor();
    let black = b.material(diffuse(Vec3::ZERO));
    b.object(
        "Wall",
        cuboid(Vec3::new(0.05, 2.0, 40.0)),
        black,
        Vec3::new(0.0, 1.0, 0.0),
    );
    let mut hard = b.clone().build();
    add_sky(&mut hard, towards, 3.0, 0.0);
    hard.environment = Environment::None;
    let mut soft = b.build();
    add_sky(&mut soft, towards, 3.0, r);
    soft.environment = Environment::None;
    // Columns of pixels across the shadow edge, which lies at x = 2 (h / tan 45°).
    let camera = PinholeCamera::look_at(
        Vec3::new(2.0, 1.0, 0.0),
        Vec3::new(2.0, 0.0, 0.0),
        Vec3::Z,
        0.5,
        64,
        64,
    )
    .unwrap();
    let lit = ALBEDO / PI * 3.0 * towards.y;
    let partial = |scene: &Scene| {
        let accel = SceneAccel::new(scene).unwrap();
        let img = pt(16, 1).render(&accel.at_time(0.0), &camera).radiance();
        img.pixels
            .iter()
            .filter(|p| {
                let f = luminance(**p) / lit;
                f > 0.1 && f < 0.9
            })
            .count()
            / 64
    };
    // Partially lit columns (a pixel column runs along the edge).
    let (h, s) = (partial(&hard), partial(&soft));
    // 64 pixels over 2·tan(0.25)·1 m = 0.51 m: 8 mm each. The edge's rays travel 2√2 m from
    // the wall's top, where the disc spans 2r: 2·0.02·2.83 = 0.113 m across the rays, 0.16 m
    // on the floor at 45° (20 pixels); the 10–90 % part of a disc's occlusion is about 0.7 of
    // it, 14 pixels.
    println!("penumbra pixels: hard {h}, soft {s}");
    assert!(h <= 2, "a delta sun has a hard edge: {h}");
    assert!((10..=18).contains(&s), "soft edge over {s} pixels");
}

#[test]
fn a_sky_lit_room_multi_stage_against_the_path_tracer() {
    let scene = sky_lit_room();
    let accel = SceneAccel::new(&scene).unwrap();
    let placed = accel.at_time(0.0);
    let camera = sky_room_camera(48, 36).unwrap();
    let a = pt(256, 21).render(&placed, &camera).radiance();
    let b = pt(256, 22).render(&placed, &camera).radiance();
    let reference = Image {
        width: a.width,
        height: a.height,
        pixels: a
            .pixels
            .iter()
            .zip(&b.pixels)
            .map(|(x, y)| (*x + *y) * 0.5)
            .collect(),
    };
    let field = AmbientField::build(&placed, &AmbientSettings::medium()).unwrap();
    let msr = MultiStageRenderer::new(ms(8, 8), &field)
        .render(&placed, &camera)
        .radiance();
    let mean = |i: &Image<Vec3>| i.mean_luminance();
    let ratio = mean(&msr) / mean(&reference);
    let lrms = relative_lrms(&msr, &reference);
    // Variance-corrected: the reference's per-pixel variance, |A − B|²/4, is taken out of the
    // squared error (docs/architecture.md, "Measuring against a noisy reference").
    let (mut err, mut var) = (0.0f64, 0.0f64);
    for ((x, a), b) in msr.pixels.iter().zip(&a.pixels).zip(&b.pixels) {
        let (x, a, b) = (
            luminance(*x) as f64,
            luminance(*a) as f64,
            luminance(*b) as f64,
        );
        err += (x - 0.5 * (a + b)).powi(2);
        var += 0.25 * (a - b).powi(2);
    }
    let n = msr.pixels.len() as f64;
    let corrected = ((err - var).max(0.0) / n).sqrt() / mean(&reference);
    let noise = (var / n).sqrt() / mean(&reference);
    println!(
        "sky-lit room: MS/PT mean {ratio:.4}, relative LRMS {lrms:.4}, corrected {corrected:.4} (reference noise {noise:.4}), field bounces {}",
        field.bounces()
    );
    let dir = out_dir();
    let exposure = 0.5 / mean(&reference) as f32;
    reference
        .save_png(dir.join("sky_room_pt.png"), exposure)
        .unwrap();
    msr.save_png(dir.join("sky_room_ms.png"), exposure).unwrap();
    assert!(mean(&reference) > 0.0);
    assert!((ratio - 1.0).abs() < 0.05, "mean ratio {ratio}");
    assert!(corrected < 0.2, "corrected relative LRMS {corrected}");
}
