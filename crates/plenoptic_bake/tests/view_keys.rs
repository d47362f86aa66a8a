//! A base view takes an ambient key time as a key of its own exactly where the light it sees
//! bends between its keys (`plenoptic_bake::plan::view_keys`).

mod common;

use std::sync::Arc;

use glam::Vec3;
use plenoptic_bake::plan::ambient;
use plenoptic_bake::plan::view_keys::{LERP_RMS, refine};
use plenoptic_scene::recipe::Quality;
use plenoptic_trace::multistage::FieldLayout;
use plenoptic_trace::{AmbientField, SceneAccel};

/// The view at (−1, 0, 0) in the lit room, whose light falls from the room's field at 0 s to
/// nothing at 1 s, and to `mid` of it at ½ s: its keys `keys` refined over the fields at 0, ½
/// and 1 s.
fn keys_after(mid: f32, keys: &[f32]) -> Vec<f32> {
    let scene = common::static_room().build_scene().unwrap();
    let mut settings = ambient::settings(&Quality::default(), 7);
    settings.rays_per_point = 16;
    let layout = Arc::new(FieldLayout::new(&scene, settings.quality).unwrap());
    let accel = SceneAccel::new(&scene).unwrap();
    let lit = AmbientField::compute(&accel.at_time(0.0), layout.clone(), &settings);
    let dark = AmbientField::zero(layout, 1.0);
    let fields = [
        AmbientField::lerp(&lit, &dark, 0.0).unwrap(),
        AmbientField::lerp(&lit, &dark, 1.0 - mid).unwrap(),
        dark,
    ];
    refine(
        &accel,
        Vec3::new(-1.0, 0.0, 0.0),
        keys,
        &[0.0, 0.5, 1.0],
        &fields,
    )
}

#[test]
fn a_view_takes_a_key_where_its_light_is_not_the_blend_of_its_keys() {
    // Half the light at ½ s: the blend of the keys at 0 and 1 s is exact there.
    assert_eq!(keys_after(0.5, &[0.0, 1.0]), vec![0.0, 1.0]);
    // A tenth at ½ s: the blend (a half) is 0.4 of the light off, far over LERP_RMS.
    assert_eq!(keys_after(0.1, &[0.0, 1.0]), vec![0.0, 0.5, 1.0]);
    // A key already there is kept, and nothing is added outside the view's keys.
    assert_eq!(keys_after(0.1, &[0.0, 0.5, 1.0]), vec![0.0, 0.5, 1.0]);
    assert_eq!(keys_after(0.1, &[0.0]), vec![0.0]);
}

#[test]
fn a_key_is_added_only_past_lerp_rms() {
    // At ½ s the light is `mid` of its start and the blend half of it: the relative
    // difference is 1 − 0.5 / mid, here 0.8 and 1.2 × LERP_RMS.
    let mid = |x: f32| 0.5 / (1.0 - x * LERP_RMS);
    assert_eq!(keys_after(mid(0.8), &[0.0, 1.0]), vec![0.0, 1.0]);
    assert_eq!(keys_after(mid(1.2), &[0.0, 1.0]), vec![0.0, 0.5, 1.0]);
}
