//! The ambient field does not leak light through a wall thinner than its cells: a floor that
//! runs under a wall, lit on one side only, stays dark on the other.

use glam::{Quat, Vec3};
use plenoptic_trace::{
    AmbientField, AmbientSettings, Camera, MultiStageRenderer, MultiStageSettings, PinholeCamera,
    Ray, SceneAccel, image::luminance, shapes,
};

/// A 4 × 2 m floor slab (top at y = 0) with a 0.1 m wall across it at x = 0 that runs into
/// the slab, 1.1 m high, and a point light at (1, 0.5, 0). No ceiling: nothing can carry the
/// light over the wall, so the floor at x < 0 receives none at all.
fn scene() -> plenoptic_scene::Scene {
    let mut b = shapes::SceneBuilder::default();
    let m = b.material(shapes::diffuse(Vec3::splat(0.8)));
    b.object(
        "Floor",
        shapes::cuboid(Vec3::new(4.0, 0.1, 2.0)),
        m,
        Vec3::new(0.0, -0.05, 0.0),
    );
    b.object(
        "Wall",
        shapes::cuboid(Vec3::new(0.1, 1.2, 2.0)),
        m,
        Vec3::new(0.0, 0.5, 0.0),
    );
    b.point_light(Vec3::new(1.0, 0.5, 0.0), Vec3::ONE, 10.0);
    b.build()
}

#[test]
fn no_light_leaks_under_a_wall() {
    let scene = scene();
    let accel = SceneAccel::new(&scene).unwrap();
    let placed = accel.at_time(0.0);
    // Cells of about 0.6 m: one sub-triangle of the floor spans the 0.1 m wall.
    let field = AmbientField::build(
        &placed,
        &AmbientSettings {
            quality: 0.05,
            ..AmbientSettings::low()
        },
    )
    .unwrap();
    assert!(field.guarded_points() > 0, "the wall blocks grid edges");
    assert!(
        field.invalid_points() > 0,
        "floor points under the wall are inside it"
    );

    // Floor points on the dark side, 2–30 cm from the wall: plain interpolation would pull
    // in the lit side's irradiance; the lookup that tests visibility does not.
    let (mut plain, mut seen, mut lit) = (0.0f32, 0.0f32, 0.0f32);
    for k in 0..15 {
        let d = 0.02 * (k + 1) as f32;
        for (x, acc) in [(-0.05 - d, 0), (0.05 + d, 1)] {
            let ray = Ray::new(Vec3::new(x, 1.0, 0.3), Vec3::NEG_Y);
            let hit = placed.intersect(&ray).expect("the floor");
            assert!(hit.position.y.abs() < 1e-3, "{hit:?}");
            let e_seen = luminance(field.irradiance_seen(&placed, &hit, Vec3::Y));
            if acc == 0 {
                plain += luminance(field.irradiance_at(hit.object, hit.triangle, hit.barycentrics));
                seen += e_seen;
            } else {
                lit += e_seen;
            }
        }
    }
    println!("dark side: plain {plain:.4}, visibility-tested {seen:.4}; lit side {lit:.4}");
    assert!(lit > 0.0);
    assert!(plain > 0.05 * lit, "the test must have a leak to stop");
    assert!(
        seen < 0.01 * lit,
        "light leaked under the wall: {seen} vs {lit}"
    );

    // And in rendered pixels: the dark side of the floor stays black.
    let render = |x: f32| {
        let cam = PinholeCamera::new(
            Vec3::new(x, 0.6, 0.0),
            Quat::from_rotation_x(-std::f32::consts::FRAC_PI_2),
            0.4,
            16,
            16,
        )
        .unwrap();
        assert_eq!(cam.resolution(), (16, 16));
        let settings = MultiStageSettings {
            samples_per_pixel: 4,
            ..MultiStageSettings::default()
        };
        MultiStageRenderer::new(settings, &field)
            .render(&placed, &cam)
            .radiance()
            .mean_luminance()
    };
    let (dark, bright) = (render(-0.2), render(0.2));
    println!("rendered: dark side {dark:.5}, lit side {bright:.5}");
    assert!(dark < 0.01 * bright, "{dark} vs {bright}");
}
