//! Animation evaluation through the file format, against values computed by hand (the
//! arithmetic is in the comments), for every interpolation mode, before the first and after
//! the last key, and for a child under an animated parent.

#![allow(
    clippy::excessive_precision,
    reason = "hand-computed constants, written to 8 digits"
)]
use std::f32::consts::FRAC_1_SQRT_2;

use glam::{Quat, Vec3};
use plenoptic_scene::builder::{MaterialDesc, NodeDesc, SceneBuilder, shapes};
use plenoptic_scene::{Interpolation, Scene, Track};

fn near(a: Vec3, b: Vec3) {
    assert!(a.abs_diff_eq(b, 1e-5), "{a} != {b}");
}

fn near_q(a: Quat, b: Quat) {
    // q and −q are the same rotation.
    assert!(
        a.abs_diff_eq(b, 1e-5) || a.abs_diff_eq(-b, 1e-5),
        "{a} != {b}"
    );
}

/// One animated node "N" (with a box) imported through GLB; returns the scene and its index.
fn one_node(
    animate: impl FnOnce(&mut SceneBuilder, plenoptic_scene::builder::NodeHandle),
) -> (Scene, usize) {
    let mut b = SceneBuilder::new();
    let m = b.add_material(MaterialDesc::default());
    let mesh = b.add_mesh("box", shapes::cuboid(Vec3::ONE), m);
    let node = b.add_node(NodeDesc::new("N").mesh(mesh));
    animate(&mut b, node);
    let scene = b.build_scene().unwrap();
    let n = scene.node_by_name("N").unwrap();
    (scene, n)
}

#[test]
fn step_translation() {
    let (scene, n) = one_node(|b, node| {
        b.animate_translation(
            node,
            Track::step([
                (0.0, Vec3::ZERO),
                (1.0, Vec3::new(1.0, 2.0, 3.0)),
                (2.0, Vec3::splat(4.0)),
            ]),
        );
    });
    let track = scene.nodes[n].track.as_ref().unwrap();
    assert_eq!(
        track.translation.as_ref().unwrap().interpolation,
        Interpolation::Step
    );
    let at = |t| scene.local_trs(n, t).translation;
    near(at(-1.0), Vec3::ZERO); // before the first key: the first value
    near(at(0.5), Vec3::ZERO);
    near(at(1.0), Vec3::new(1.0, 2.0, 3.0)); // at a key: that key
    near(at(1.999), Vec3::new(1.0, 2.0, 3.0));
    near(at(2.0), Vec3::splat(4.0));
    near(at(10.0), Vec3::splat(4.0)); // after the last key: the last value
}

#[test]
fn linear_translation() {
    let (scene, n) = one_node(|b, node| {
        b.animate_translation(
            node,
            Track::linear([(1.0, Vec3::ZERO), (3.0, Vec3::new(2.0, 4.0, -6.0))]),
        );
    });
    let at = |t| scene.local_trs(n, t).translation;
    // t = 1.5: s = 0.5 / 2 = 0.25 → 0.25 · (2, 4, −6) = (0.5, 1, −1.5).
    near(at(1.5), Vec3::new(0.5, 1.0, -1.5));
    // t = 2.5: s = 0.75 → (1.5, 3, −4.5).
    near(at(2.5), Vec3::new(1.5, 3.0, -4.5));
    near(at(0.0), Vec3::ZERO);
    near(at(5.0), Vec3::new(2.0, 4.0, -6.0));
    assert_eq!(scene.animation_range(), (1.0, 3.0));
}

#[test]
fn slerp_rotation() {
    // From identity to 120° about z.
    let (scene, n) = one_node(|b, node| {
        b.animate_rotation(
            node,
            Track::linear([
                (0.0, Quat::IDENTITY),
                (4.0, Quat::from_xyzw(0.0, 0.0, 0.8660254, 0.5)),
            ]),
        );
    });
    let at = |t| scene.local_trs(n, t).rotation;
    // t = 1: s = 0.25 → slerp gives 30° about z: (0, 0, sin 15°, cos 15°).
    // (Normalised lerp would give 27.8°: (0, 0, 0.2165, 0.875)/0.9014.)
    near_q(at(1.0), Quat::from_xyzw(0.0, 0.0, 0.25881905, 0.96592583));
    // t = 2: 60° → (0, 0, 0.5, 0.8660254).
    near_q(at(2.0), Quat::from_xyzw(0.0, 0.0, 0.5, 0.8660254));
    near_q(at(-3.0), Quat::IDENTITY);
    near_q(at(9.0), Quat::from_xyzw(0.0, 0.0, 0.8660254, 0.5));
    // 30° about z takes x to (cos 30°, sin 30°, 0).
    let m = scene.node_transform(n, 1.0);
    near(m.transform_vector3(Vec3::X), Vec3::new(0.8660254, 0.5, 0.0));
}

#[test]
fn cubic_spline_with_tangents() {
    // Keys at t = 0 and t = 2 (td = 2): v0 = (0, 1, 0), out-tangent b0 = (1, 2, 0);
    // v1 = (1, 1, 0), in-tangent a1 = (3, −1, 0). The first in- and last out-tangents must
    // not matter: they are set to 100.
    let junk = Vec3::splat(100.0);
    let (scene, n) = one_node(|b, node| {
        b.animate_translation(
            node,
            Track::cubic_spline([
                (
                    0.0,
                    junk,
                    Vec3::new(0.0, 1.0, 0.0),
                    Vec3::new(1.0, 2.0, 0.0),
                ),
                (
                    2.0,
                    Vec3::new(3.0, -1.0, 0.0),
                    Vec3::new(1.0, 1.0, 0.0),
                    junk,
                ),
            ]),
        );
    });
    let at = |t| scene.local_trs(n, t).translation;
    // t = 1, s = 0.5: h00 = 0.5, h10 = 0.125, h01 = 0.5, h11 = −0.125.
    // x = 0.5·0 + 2·0.125·1 + 0.5·1 + 2·(−0.125)·3 = 0.25 + 0.5 − 0.75 = 0
    // y = 0.5·1 + 2·0.125·2 + 0.5·1 + 2·(−0.125)·(−1) = 0.5 + 0.5 + 0.5 + 0.25 = 1.75
    near(at(1.0), Vec3::new(0.0, 1.75, 0.0));
    // t = 0.5, s = 0.25: h00 = 0.84375, h10 = 0.140625, h01 = 0.15625, h11 = −0.046875.
    // x = 2·0.140625·1 + 0.15625·1 + 2·(−0.046875)·3 = 0.28125 + 0.15625 − 0.28125 = 0.15625
    // y = 0.84375 + 2·0.140625·2 + 0.15625 + 2·(−0.046875)·(−1)
    //   = 0.84375 + 0.5625 + 0.15625 + 0.09375 = 1.65625
    near(at(0.5), Vec3::new(0.15625, 1.65625, 0.0));
    near(at(-1.0), Vec3::new(0.0, 1.0, 0.0));
    near(at(3.0), Vec3::new(1.0, 1.0, 0.0));
}

#[test]
fn cubic_spline_rotation_is_normalised() {
    // Zero tangents, identity → 90° about z. At s = 0.5 the Hermite weights are 0.5 and 0.5:
    // (0, 0, 0.35355339, 0.85355339), of length 0.92387953 → (0, 0, 0.38268343, 0.92387953),
    // i.e. 45° about z.
    let zero = Quat::from_xyzw(0.0, 0.0, 0.0, 0.0);
    let (scene, n) = one_node(|b, node| {
        b.animate_rotation(
            node,
            Track::cubic_spline([
                (0.0, zero, Quat::IDENTITY, zero),
                (
                    1.0,
                    zero,
                    Quat::from_xyzw(0.0, 0.0, FRAC_1_SQRT_2, FRAC_1_SQRT_2),
                    zero,
                ),
            ]),
        );
    });
    near_q(
        scene.local_trs(n, 0.5).rotation,
        Quat::from_xyzw(0.0, 0.0, 0.38268343, 0.92387953),
    );
}

#[test]
fn child_under_animated_parent() {
    let mut b = SceneBuilder::new();
    let m = b.add_material(MaterialDesc::default());
    let mesh = b.add_mesh("box", shapes::cuboid(Vec3::ONE), m);
    let parent = b.add_node(NodeDesc::new("Parent"));
    b.add_node(
        NodeDesc::new("Child")
            .parent(parent)
            .mesh(mesh)
            .translation(Vec3::X)
            .scale(Vec3::splat(2.0)),
    );
    b.animate_translation(
        parent,
        Track::linear([(0.0, Vec3::ZERO), (2.0, Vec3::new(4.0, 0.0, 0.0))]),
    )
    .animate_rotation(
        parent,
        Track::step([
            (0.0, Quat::IDENTITY),
            (1.0, Quat::from_xyzw(0.0, 0.0, FRAC_1_SQRT_2, FRAC_1_SQRT_2)),
        ]),
    );
    let scene = b.build_scene().unwrap();
    let child = scene.node_by_name("Child").unwrap();
    let object = scene.object_by_name("Child").unwrap();
    assert!(scene.object_is_animated(object));
    assert!(scene.nodes[child].track.is_none());

    // t = 0.5: parent at (1, 0, 0), unrotated → child origin (2, 0, 0), x axis (2, 0, 0).
    let m = scene.node_transform(child, 0.5);
    near(m.translation.into(), Vec3::new(2.0, 0.0, 0.0));
    near(m.transform_vector3(Vec3::X), Vec3::new(2.0, 0.0, 0.0));
    // t = 1.5: parent at (3, 0, 0), 90° about z (x → y) → origin (3, 1, 0), x axis (0, 2, 0).
    let m = scene.node_transform(child, 1.5);
    near(m.translation.into(), Vec3::new(3.0, 1.0, 0.0));
    near(m.transform_vector3(Vec3::X), Vec3::new(0.0, 2.0, 0.0));
    // After the end both tracks hold: (4, 0, 0) + (0, 1, 0).
    near(
        scene.object_transform(object, 7.0).translation.into(),
        Vec3::new(4.0, 1.0, 0.0),
    );
    assert_eq!(scene.animation_range(), (0.0, 2.0));
}
