//! glTF alpha in the tracers, with known answers: a BLEND pane of alpha a between a sun and a
//! diffuse floor transmits 1 − a of the sun; a MASK cut-out casts the cut-out's shadow. The
//! scenes are written as glTF by `plenoptic_scene`'s builder and imported, so the importer's
//! `alphaMode`, `COLOR_0` and texture handling are on the path.
//!
//! Both scenes have a black (absorbing) occluder over a single floor plane and no other light
//! than the sun, so the floor's radiance is exactly ρ/π · E · (transmitted fraction): there is
//! no indirect light for either renderer to get wrong, and the only noise is the coverage
//! decision of each shadow ray (binomial, σ stated per test).

mod common;

use common::mean_and_se;
use glam::{Quat, Vec2, Vec3, Vec4};
use plenoptic_scene::builder::shapes::plane;
use plenoptic_scene::builder::{LightDesc, MaterialDesc, NodeDesc, SceneBuilder};
use plenoptic_scene::{AlphaMode, Scene, Trs};
use plenoptic_trace::material::SurfaceProps;
use plenoptic_trace::{
    AmbientField, AmbientSettings, Camera, Image, MultiStageRenderer, MultiStageSettings,
    PathTracer, PathTracerSettings, PinholeCamera, RadianceSample, Ray, SceneAccel,
    image::luminance,
};
use std::f32::consts::{FRAC_PI_2, PI};

const ALBEDO: f32 = 0.5;
const SUN: f32 = 3.0;

fn pt(spp: u32) -> PathTracer {
    PathTracer::new(PathTracerSettings {
        samples_per_pixel: spp,
        max_depth: 16,
        rr_start_depth: 3,
        seed: 5,
        environment_sampling: true,
    })
}

fn ms(spp: u32) -> MultiStageSettings {
    MultiStageSettings {
        samples_per_pixel: spp,
        shadow_samples: 1,
        glossy_samples: 1,
        max_specular_depth: 4,
        seed: 9,
        final_gather: 0,
    }
}

/// A 20 m Lambertian floor (IOR 1: exactly ρ/π) at y = 0 and a sun shining straight down.
fn floor_and_sun() -> SceneBuilder {
    let mut b = SceneBuilder::new();
    let floor = b.add_material(
        MaterialDesc::diffuse(Vec3::splat(ALBEDO))
            .transmission(0.0, 1.0)
            .named("floor"),
    );
    b.add_object("Floor", plane(Vec2::splat(20.0), 1), floor, Trs::default());
    b.add_node(
        NodeDesc::new("Sun")
            .rotation(Quat::from_rotation_x(-FRAC_PI_2))
            .light(LightDesc::directional(Vec3::ONE, SUN)),
    );
    b
}

/// A perfect absorber: black, IOR 1 (no Fresnel reflection).
fn black() -> MaterialDesc {
    MaterialDesc::diffuse(Vec3::ZERO).transmission(0.0, 1.0)
}

fn at_height(y: f32) -> Trs {
    Trs {
        translation: Vec3::new(0.0, y, 0.0),
        ..Trs::default()
    }
}

/// Unshadowed floor radiance.
fn lit() -> f32 {
    ALBEDO / PI * SUN
}

/// A camera between floor and occluder looking straight down.
fn down_camera(height: f32, size: u32) -> PinholeCamera {
    PinholeCamera::look_at(
        Vec3::new(0.0, height, 0.0),
        Vec3::ZERO,
        Vec3::Z,
        1.6,
        size,
        size,
    )
    .unwrap()
}

fn renders(
    scene: &Scene,
    camera: &PinholeCamera,
    spp: u32,
) -> [(&'static str, Image<RadianceSample>); 2] {
    let accel = SceneAccel::new(scene).unwrap();
    let placed = accel.at_time(0.0);
    let field = AmbientField::build(&placed, &AmbientSettings::low()).unwrap();
    [
        ("PT", pt(spp).render(&placed, camera)),
        (
            "MS",
            MultiStageRenderer::new(ms(spp), &field).render(&placed, camera),
        ),
    ]
}

/// A 20 m pane at y = 2 of BLEND alpha 0.25 (factor, or factor × COLOR_0 alpha × texture
/// alpha when `split`), black so that it reflects nothing.
fn pane_scene(split: bool) -> Scene {
    let mut b = floor_and_sun();
    let mut pane = plane(Vec2::splat(20.0), 1);
    let mut material = black().alpha_mode(AlphaMode::Blend).named("glass");
    if split {
        // 0.5 (factor) × 128/255 (texture) × 255/256 (COLOR_0) = 0.2500 everywhere.
        let tex = b.add_texture_rgba8(1, 1, vec![0, 0, 0, 128]);
        material = material
            .base_color_texture(tex)
            .base_color_alpha(Vec4::new(0.0, 0.0, 0.0, 0.5));
        pane.colors = vec![Vec4::new(1.0, 1.0, 1.0, 255.0 / 256.0); pane.positions.len()];
    } else {
        material = material.base_color_alpha(Vec4::new(0.0, 0.0, 0.0, 0.25));
    }
    let m = b.add_material(material);
    b.add_object("Pane", pane, m, at_height(2.0));
    b.build_scene().unwrap()
}

#[test]
fn blend_pane_transmits_three_quarters_of_the_sun() {
    let (size, spp) = (48u32, 16u32);
    let camera = down_camera(1.0, size);
    let open = floor_and_sun().build_scene().unwrap();
    let covered = pane_scene(false);
    let n = f64::from(size * size * spp);
    // Each shadow ray passes with probability 0.75 and the floor radiance is then exactly the
    // open floor's: the ratio is a binomial fraction, σ = √(0.75·0.25/n) ≈ 0.0023 here.
    let sigma = (0.75 * 0.25 / n).sqrt();
    for ((name, reference), (_, img)) in renders(&open, &camera, spp)
        .into_iter()
        .zip(renders(&covered, &camera, spp))
    {
        let (unshadowed, se0) = mean_and_se(&reference.radiance());
        assert!(
            (unshadowed - f64::from(lit())).abs() < 1e-4 * f64::from(lit()) && se0 < 1e-5,
            "{name}: open floor {unshadowed} ± {se0}, expected {}",
            lit()
        );
        let (mean, se) = mean_and_se(&img.radiance());
        let ratio = mean / unshadowed;
        println!(
            "BLEND 0.25 {name}: ratio {ratio:.4} (expected 0.75; σ {:.4} measured, {sigma:.4} binomial)",
            se / unshadowed
        );
        assert!((ratio - 0.75).abs() < 0.02 * 0.75, "{name}: ratio {ratio}");
        assert!(
            (ratio - 0.75).abs() < 4.0 * sigma,
            "{name}: ratio {ratio} beyond 4σ"
        );
    }
    // The coverage decision is a hash of the ray: the same render twice is the same image.
    let accel = SceneAccel::new(&covered).unwrap();
    let placed = accel.at_time(0.0);
    let a = pt(2).render(&placed, &camera).radiance();
    let b = pt(2).render(&placed, &camera).radiance();
    assert_eq!(a.pixels, b.pixels);
}

#[test]
fn blend_alpha_is_factor_times_texture_times_vertex_colour() {
    let (size, spp) = (32u32, 16u32);
    let camera = down_camera(1.0, size);
    let scene = pane_scene(true);
    let accel = SceneAccel::new(&scene).unwrap();
    let placed = accel.at_time(0.0);
    let img = pt(spp).render(&placed, &camera);
    let (mean, _) = mean_and_se(&img.radiance());
    // alpha = 0.5 · (128/255) · (255/256) ≈ 0.2500: transmission 0.7500.
    let alpha = 0.5 * (128.0 / 255.0) * (255.0 / 256.0);
    let n = f64::from(size * size * spp);
    let sigma = (alpha * (1.0 - alpha) / n).sqrt();
    let ratio = mean / f64::from(lit());
    println!(
        "BLEND factor × texture × COLOR_0: ratio {ratio:.4}, expected {:.4} ± {sigma:.4}",
        1.0 - alpha
    );
    assert!(
        (ratio - (1.0 - alpha)).abs() < 4.0 * sigma + 1e-4,
        "{ratio}"
    );
}

/// A 4 m MASK quad at y = 1 with an 8×8 checkerboard alpha texture (0.5 m texels), black.
fn mask_scene() -> Scene {
    let mut b = floor_and_sun();
    let rgba: Vec<u8> = (0..64)
        .flat_map(|k| {
            let (i, j) = (k % 8, k / 8);
            [0, 0, 0, if (i + j) % 2 == 0 { 255 } else { 0 }]
        })
        .collect();
    let tex = b.add_texture_rgba8(8, 8, rgba);
    let m = b.add_material(
        black()
            .base_color_texture(tex)
            .alpha_mode(AlphaMode::Mask { cutoff: 0.5 })
            .named("fence"),
    );
    b.add_object("Fence", plane(Vec2::splat(4.0), 1), m, at_height(1.0));
    b.build_scene().unwrap()
}

/// Whether the texel over floor point (x, z) is opaque, or `None` within `margin` texels of
/// a texel edge (bilinear filtering blends there).
fn opaque_texel(x: f32, z: f32, margin: f32) -> Option<bool> {
    // plane(): uv = ((x + 2)/4, (z + 2)/4); 8 texels across.
    let (u, v) = ((x + 2.0) / 4.0 * 8.0, (z + 2.0) / 4.0 * 8.0);
    let near_edge = |c: f32| {
        let f = c - c.floor();
        f < margin || f > 1.0 - margin
    };
    if near_edge(u) || near_edge(v) {
        return None;
    }
    Some((u.floor() as i32 + v.floor() as i32) % 2 == 0)
}

#[test]
fn mask_cutout_casts_the_cutouts_shadow() {
    let size = 48;
    let camera = down_camera(0.9, size);
    let scene = mask_scene();
    for (name, img) in renders(&scene, &camera, 4) {
        let (mut dark, mut bright) = (0, 0);
        for y in 0..size {
            for x in 0..size {
                let s = img.get(x, y);
                let ray = camera.ray(x, y, Vec2::splat(0.5)).unwrap();
                let p = ray.origin + ray.direction * s.distance;
                let l = luminance(s.radiance);
                match opaque_texel(p.x, p.z, 0.15) {
                    Some(true) => {
                        assert!(
                            l < 1e-6,
                            "{name}: pixel ({x}, {y}) under an opaque texel: {l}"
                        );
                        dark += 1;
                    }
                    Some(false) => {
                        assert!(
                            (l - lit()).abs() < 1e-3 * lit(),
                            "{name}: pixel ({x}, {y}) under a hole: {l} vs {}",
                            lit()
                        );
                        bright += 1;
                    }
                    None => {}
                }
            }
        }
        println!("MASK {name}: {dark} dark and {bright} lit pixels as the checkerboard says");
        assert!(dark > 300 && bright > 300, "{name}: {dark} / {bright}");
    }
}

#[test]
fn rays_and_id_images_see_through_the_cutout() {
    let scene = mask_scene();
    let accel = SceneAccel::new(&scene).unwrap();
    let placed = accel.at_time(0.0);
    let fence = scene.object_by_name("Fence").unwrap();
    let floor = scene.object_by_name("Floor").unwrap();
    // Texel (0, 0) spans x, z ∈ [−2, −1.5] and is opaque; texel (1, 0) is a hole.
    let down = |x: f32, z: f32| Ray::new(Vec3::new(x, 3.0, z), Vec3::NEG_Y);
    assert_eq!(placed.intersect(&down(-1.75, -1.75)).unwrap().object, fence);
    assert_eq!(placed.intersect(&down(-1.25, -1.75)).unwrap().object, floor);
    let up = |x: f32, z: f32| Ray {
        origin: Vec3::new(x, 0.01, z),
        direction: Vec3::Y,
        tmax: 5.0,
    };
    assert!(placed.occluded(&up(-1.75, -1.75)));
    assert!(!placed.occluded(&up(-1.25, -1.75)));
    let camera =
        PinholeCamera::look_at(Vec3::new(0.0, 3.0, 0.0), Vec3::ZERO, Vec3::Z, 1.0, 32, 32).unwrap();
    let ids = placed.id_image(&camera);
    let (f, g) = ids.pixels.iter().fold((0, 0), |(f, g), &id| {
        (f + usize::from(id == fence), g + usize::from(id == floor))
    });
    // Half the texels are holes: about half the pixels see the floor.
    assert!(f > 400 && g > 400, "fence {f}, floor {g}");
}

#[test]
fn vertex_colours_multiply_the_base_colour() {
    let mut b = SceneBuilder::new();
    let m = b.add_material(MaterialDesc::diffuse(Vec3::splat(0.5)));
    let mut floor = plane(Vec2::splat(2.0), 1);
    floor.colors = vec![Vec4::new(1.0, 0.5, 0.25, 1.0); floor.positions.len()];
    b.add_object("Floor", floor, m, Trs::default());
    let scene = b.build_scene().unwrap();
    let accel = SceneAccel::new(&scene).unwrap();
    let placed = accel.at_time(0.0);
    let hit = placed
        .intersect(&Ray::new(Vec3::new(0.2, 1.0, 0.3), Vec3::NEG_Y))
        .unwrap();
    let props = SurfaceProps::at(&scene, &hit);
    assert!(
        props
            .base_color
            .abs_diff_eq(Vec3::new(0.5, 0.25, 0.125), 1e-6),
        "{:?}",
        props.base_color
    );
}

/// Rays that meet the shared diagonal of a two-triangle square (the builder's plane) hit it:
/// the triangle test leaves no crack between neighbours. (Pixel (34, 13) of this camera fell
/// through before.)
#[test]
fn rays_along_a_shared_edge_hit() {
    let scene = floor_and_sun().build_scene().unwrap();
    let accel = SceneAccel::new(&scene).unwrap();
    let placed = accel.at_time(0.0);
    let camera = down_camera(0.9, 48);
    for y in 0..48 {
        for x in 0..48 {
            let ray = camera.ray(x, y, Vec2::splat(0.5)).unwrap();
            assert!(
                placed.intersect(&ray).is_some(),
                "pixel ({x}, {y}) falls through"
            );
        }
    }
}
