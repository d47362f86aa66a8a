//! The bake plan: decomposition of space and time (thesis ch. 6).

mod common;

use common::*;
use plenoptic_bake::input::load_recipe;
use plenoptic_bake::plan::{self, Plan};
use plenoptic_trace::SceneAccel;

fn plan_of(view: &str, scene: &plenoptic_scene::builder::SceneBuilder, quality: &str) -> Plan {
    let dir = tempfile::tempdir().unwrap();
    let path = write_recipe(dir.path(), scene, view, quality);
    let (recipe, scene) = load_recipe(&path).unwrap();
    let accel = SceneAccel::new(&scene).unwrap();
    plan::decompose(&recipe, &scene, &accel).0
}

#[test]
fn q_zero_gives_the_corners_and_the_endpoints_only() {
    let rooms = two_rooms();
    let p = plan_of(ROOM_A_SEGMENT, &rooms, "q = 0.0\nmax_space_depth = 3");
    assert_eq!(p.base_views.len(), 2);
    assert!(p.animated);
    for v in &p.base_views {
        assert_eq!(v.time_keys, vec![0.0, 1.0]);
    }
    let p = plan_of(ROOM_A_RECT, &rooms, "q = 0.0\nmax_space_depth = 3");
    assert_eq!(p.base_views.len(), 4);
    assert_eq!(p.light_keys, vec![0.0, 1.0]);
}

#[test]
fn base_views_and_time_keys_never_fall_as_q_rises() {
    let rooms = two_rooms();
    let mut last = (0usize, 0usize);
    let mut counts = Vec::new();
    for q in [0.0, 0.5, 0.8, 0.95, 1.0] {
        let p = plan_of(
            ROOM_A_RECT,
            &rooms,
            &format!("q = {q}\nmax_space_depth = 2\nmax_time_depth = 3"),
        );
        let now = (p.base_views.len(), p.time_key_count());
        assert!(
            now.0 >= last.0 && now.1 >= last.1,
            "q = {q}: {now:?} after {last:?}"
        );
        for v in &p.base_views {
            assert!(v.time_keys.windows(2).all(|w| w[0] < w[1]));
            assert_eq!(v.time_keys.first(), Some(&0.0));
            assert_eq!(v.time_keys.last(), Some(&1.0));
        }
        counts.push(now);
        last = now;
    }
    assert!(last.0 > 4 && last.1 > 8, "q = 1 subdivides: {counts:?}");
}

#[test]
fn a_static_scene_gets_one_time_key_per_base_view() {
    let p = plan_of(
        STATIC_SEGMENT,
        &static_room(),
        "q = 0.99\nmax_space_depth = 2",
    );
    assert!(!p.animated);
    assert!(p.base_views.len() >= 2);
    for v in &p.base_views {
        assert_eq!(v.time_keys, vec![0.0]);
        assert_eq!(v.volume_samples, 0);
    }
}

#[test]
fn a_moving_object_adds_keys_only_where_it_is_seen() {
    // Base view 0 is in room A with the moving box, base view 1 in the closed room B.
    let p = plan_of(ROOMS_SEGMENT, &two_rooms(), "q = 0.95\nmax_space_depth = 0");
    assert_eq!(p.base_views.len(), 2);
    assert_eq!(
        p.light_keys,
        vec![0.0, 1.0],
        "the lamp in B never sees the box"
    );
    let (a, b) = (&p.base_views[0], &p.base_views[1]);
    assert!(a.position.x < 0.0 && b.position.x > 0.0);
    assert!(a.time_keys.len() > 2, "room A: {:?}", a.time_keys);
    assert_eq!(b.time_keys, vec![0.0, 1.0]);
    // The temporal-volume budget follows the change seen.
    assert!(a.volume_samples > b.volume_samples && b.volume_samples > 0);
}

#[test]
fn plans_round_trip_through_json() {
    let p = plan_of(ROOM_A_SEGMENT, &two_rooms(), "q = 0.9");
    let back = Plan::from_json(&p.to_json(), std::path::Path::new("plan.json")).unwrap();
    assert_eq!(back, p);
    let cost = p.cost(1e6);
    assert_eq!(cost.range_images as usize, p.time_key_count());
    assert!(cost.estimated_bytes > 0 && cost.estimated_seconds > 0.0);
}

#[test]
fn trace_cube_faces_match_the_pack_texel_order() {
    use plenoptic_trace::{Camera, CubeCamera};
    let n = 4u32;
    let cube = CubeCamera::new(glam::Vec3::ZERO, n).unwrap();
    for (f, face) in cube.faces().iter().enumerate() {
        for y in 0..n {
            for x in 0..n {
                let ray = face.ray(x, y, glam::Vec2::splat(0.5)).unwrap();
                let i = f * (n * n) as usize + (y * n + x) as usize;
                let d = plenoptic_pack::cube::texel_direction(n, i).normalize();
                assert!(ray.direction.dot(d) > 0.9999, "face {f} ({x}, {y})");
            }
        }
    }
}

/// Base views clear of objects (`plan::clearance`): room A's rectangle has a pillar standing
/// on one corner and a box sliding through another halfway through the bake's range. Both
/// views move to a clear point nearby (not farther than 0.45 of the way to the next view);
/// the other two stay on their lattice points.
#[test]
fn base_views_move_out_of_objects_and_out_of_the_way_of_moving_ones() {
    use glam::Vec3;
    use plenoptic_bake::plan::clearance;
    use plenoptic_scene::Track;
    use plenoptic_scene::builder::{MaterialDesc, NodeDesc};

    // In lattice order (x, then z).
    let lattice = [
        Vec3::new(-6.0, 0.3, -1.0),
        Vec3::new(-6.0, 0.3, 1.0),
        Vec3::new(-4.0, 0.3, -1.0),
        Vec3::new(-4.0, 0.3, 1.0),
    ];
    let rooms = two_rooms();
    let quality = "q = 0.0\nmax_space_depth = 3";
    let before = plan_of(ROOM_A_RECT, &rooms, quality);
    assert_eq!(before.counters.views_moved, 0);
    let mut scene = two_rooms();
    let grey = scene.add_material(MaterialDesc::diffuse(Vec3::splat(0.5)));
    let pillar = scene.add_box("pillar", Vec3::new(0.4, 3.9, 0.4), grey);
    scene.add_node(NodeDesc::new("pillar").mesh(pillar).translation(lattice[0]));
    let slider = scene.add_box("slider", Vec3::splat(0.3), grey);
    let node = scene.add_node(
        NodeDesc::new("slider")
            .mesh(slider)
            .translation(Vec3::new(-4.0, 0.3, 0.2)),
    );
    scene.animate_translation(
        node,
        Track::linear([
            (0.0, Vec3::new(-4.0, 0.3, 0.2)),
            (1.0, Vec3::new(-4.0, 0.3, 1.8)),
        ]),
    );
    let after = plan_of(ROOM_A_RECT, &scene, quality);
    assert_eq!(after.base_views.len(), 4);
    assert_eq!(
        (after.counters.views_moved, after.counters.views_crowded),
        (2, 0)
    );
    // The same lattice points in the same order; only the positions moved.
    for (a, b) in before.base_views.iter().zip(&after.base_views) {
        assert_eq!(a.lattice, b.lattice);
    }
    let dir = tempfile::tempdir().unwrap();
    let path = write_recipe(dir.path(), &scene, ROOM_A_RECT, quality);
    let (_, loaded) = load_recipe(&path).unwrap();
    let accel = SceneAccel::new(&loaded).unwrap();
    let scenes: Vec<_> = clearance::times(0.0, 1.0, clearance::TIMES)
        .into_iter()
        .map(|t| accel.at_time(t))
        .collect();
    for (v, &l) in after.base_views.iter().zip(&lattice) {
        let moved = v.position.distance(l);
        let crowded_there = clearance::crowding(&scenes, l);
        if l == lattice[0] || l == lattice[3] {
            // In the pillar (every direction meets a back face), and in the slider's way.
            assert!(crowded_there > 0.5, "{l}: {crowded_there}");
            assert!(
                moved > 0.0 && moved <= 0.45 * 2.0 + 1e-4,
                "{l} -> {}",
                v.position
            );
            assert!(clearance::crowding(&scenes, v.position) <= clearance::CROWDED);
            assert_eq!(v.position.y, 0.3);
        } else {
            assert!(crowded_there <= clearance::CROWDED, "{l}: {crowded_there}");
            assert_eq!(v.position, l);
        }
    }
    // At the start and the end alone the slider is 0.8 m from its corner: clear.
    let ends: Vec<_> = [0.0, 1.0].map(|t| accel.at_time(t)).into_iter().collect();
    assert!(clearance::crowding(&ends, lattice[3]) <= clearance::CROWDED);
}
