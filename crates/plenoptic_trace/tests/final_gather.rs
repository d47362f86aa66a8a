//! The final gather of the multi-stage renderer (`AmbientField::irradiance_gathered`)
//! against a closed form: the floor under a black table top in a uniform sky. The ambient
//! field's grid is coarser than the table, so its interpolation carries the open floor's
//! light under it; a final gather traced from the floor itself sees the table.

mod common;

use common::mean_and_se;
use glam::{Vec2, Vec3};
use plenoptic_scene::Environment;
use plenoptic_scene::builder::shapes::{cuboid, plane};
use plenoptic_trace::shapes::{SceneBuilder, diffuse};
use plenoptic_trace::{
    AmbientField, AmbientSettings, MultiStageRenderer, MultiStageSettings, PinholeCamera,
    SceneAccel,
};
use std::f64::consts::PI;

const ALBEDO: f32 = 0.5;

/// View factor from a point to a parallel rectangle whose corner is straight above it at
/// height `c`, with sides `a` and `b` (Howell's catalogue of configuration factors, B-3).
fn corner_view_factor(a: f64, b: f64, c: f64) -> f64 {
    let (x, y) = (a / c, b / c);
    let (sx, sy) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
    (x / sx * (y / sx).atan() + y / sy * (x / sy).atan()) / (2.0 * PI)
}

#[test]
fn a_final_gather_sees_the_table_the_field_interpolates_across() {
    let l = Vec3::splat(1.0);
    let mut b = SceneBuilder::default();
    let floor = b.material(diffuse(Vec3::splat(ALBEDO)));
    let black = b.material(diffuse(Vec3::ZERO));
    b.object("Floor", plane(Vec2::splat(6.0), 1), floor, Vec3::ZERO);
    // A 1 × 1 m black top whose underside is 0.3 m above the floor.
    b.object(
        "Table",
        cuboid(Vec3::new(1.0, 0.05, 1.0)),
        black,
        Vec3::new(0.0, 0.325, 0.0),
    );
    let mut scene = b.build();
    scene.environment = Environment::Uniform(l);
    let accel = SceneAccel::new(&scene).unwrap();
    let placed = accel.at_time(0.0);
    let field = AmbientField::build(
        &placed,
        &AmbientSettings {
            rays_per_point: 1024,
            ..AmbientSettings::low()
        },
    )
    .unwrap();
    // The floor under the table's centre, seen from 0.2 m above it.
    let camera =
        PinholeCamera::look_at(Vec3::new(0.0, 0.2, 0.0), Vec3::ZERO, Vec3::Z, 0.05, 8, 8).unwrap();
    let render = |final_gather| {
        let settings = MultiStageSettings {
            samples_per_pixel: 256,
            shadow_samples: 1,
            glossy_samples: 1,
            max_specular_depth: 1,
            seed: 5,
            final_gather,
        };
        let img = MultiStageRenderer::new(settings, &field).render(&placed, &camera);
        mean_and_se(&img.radiance())
    };
    // Black table, and a floor cannot see itself: the floor's irradiance is the sky's πL
    // times the part of the hemisphere the table does not cover. Radiance ρ/π of that.
    let covered = 4.0 * corner_view_factor(0.5, 0.5, 0.3);
    let want = f64::from(ALBEDO) * (1.0 - covered);
    let (gathered, se) = render(1);
    let (interpolated, _) = render(0);
    println!(
        "under the table: final gather {:.4} (se {se:.4}), field {:.4}, exact {want:.4} \
         (table covers {covered:.3} of the sky)",
        gathered, interpolated
    );
    assert!(
        (gathered - want).abs() < 0.03 * want + 3.0 * se,
        "final gather {gathered} against {want}"
    );
    // The field's points are half a metre apart: under the table they are interpolated with
    // those of the open floor around it.
    assert!(
        interpolated > 1.3 * want,
        "the field alone ({interpolated}) should be far too bright here ({want})"
    );
}
