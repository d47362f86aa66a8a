//! Per-view state: a camera's lookups, time and settings live in its view buffer
//! (`bevy_plenoptic::reconstruct::geometry::view`), which every material it draws binds. When the
//! camera's time moves (the lookups' weights, keys and the slider's motion change), only the
//! view buffer is rewritten; the proxy materials are written again only when something they
//! bind was replaced, and the frame still equals the CPU's at the new time.

use std::collections::HashSet;

use crate::harness::compare;
use crate::many_cameras::{Eye, assert_each_matches, cpu_frame, plugin_cameras, settled_frames};
use crate::pack::{PackSpec, room, write_pack};
use bevy::prelude::*;
use bevy_plenoptic::prelude::*;
use bevy_plenoptic::reconstruct::geometry::PlenopticMaterial;
use bevy_plenoptic::reconstruct::geometry::view::ViewBuffer;

/// What happened to the camera's materials and view buffer, frame by frame.
#[derive(Resource, Default)]
struct Seen {
    /// `AssetEvent::Modified` of proxy materials.
    modified: usize,
    /// Distinct `ViewBuffer::bindings` values.
    bindings: HashSet<u64>,
    /// Distinct view buffer contents (by their debug text).
    contents: HashSet<String>,
}

fn watch(
    mut events: MessageReader<AssetEvent<PlenopticMaterial>>,
    views: Query<&ViewBuffer>,
    mut seen: ResMut<Seen>,
) {
    seen.modified += events
        .read()
        .filter(|e| matches!(e, AssetEvent::Modified { .. }))
        .count();
    for v in &views {
        seen.bindings.insert(v.bindings);
        let text = format!("{:?}", v.params());
        seen.contents.insert(text);
    }
}

/// A geometry-assisted camera settles at t = 1, then its time moves to t = 1.6 in steps:
/// every step changes its view buffer, no step rewrites a material unless the camera's
/// bindings changed (a repacked volume buffer), and the settled frame equals the CPU's at
/// t = 1.6 and differs from the frame at t = 1 (the slider moved).
#[test]
fn moving_time_rewrites_the_view_buffer_not_the_materials() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("room.pack");
    write_pack(
        &room(true),
        &PackSpec {
            time: (0.0, 3.0),
            ..PackSpec::segment(3, vec![0.0, 1.0, 2.0, 3.0], 8)
        },
        &path,
    );
    let eye = |t: f32| Eye {
        at: Vec3::new(0.3, 1.3, 1.0),
        target: Vec3::new(0.0, 0.8, -2.5),
        t,
        mode: ReconMode::GeometryAssisted,
    };
    let (mut app, cameras, targets) = plugin_cameras(dir.path(), &[eye(1.0)]);
    let before = settled_frames(&mut app, &targets);
    let materials = app.world().resource::<Assets<PlenopticMaterial>>().len();
    assert!(materials > 0, "no proxy material");

    app.init_resource::<Seen>().add_systems(PostUpdate, watch);
    let steps = 6;
    for step in 1..=steps {
        let t = 1.0 + 0.6 * step as f32 / steps as f32;
        app.world_mut()
            .get_mut::<PlenopticCamera>(cameras[0])
            .unwrap()
            .time = t;
        for _ in 0..3 {
            app.update();
        }
    }
    let after = settled_frames(&mut app, &targets);
    let seen = app.world().resource::<Seen>();
    let rebinds = seen.bindings.len() - 1;
    eprintln!(
        "{} view-buffer contents, {} bindings, {} material writes of {materials} materials",
        seen.contents.len(),
        seen.bindings.len(),
        seen.modified
    );
    assert!(
        seen.contents.len() >= steps,
        "the view buffer did not follow the time: {} contents",
        seen.contents.len()
    );
    assert!(
        seen.modified <= rebinds * materials,
        "{} material writes for {rebinds} rebinds of {materials} materials",
        seen.modified
    );

    let cpu = cpu_frame(&path, eye(1.6));
    let (apart, same, _) = compare(&before[0], &after[0]);
    eprintln!("t = 1 against t = 1.6: mean {apart:.3}, within 5 % {same:.3}");
    assert!(apart > 0.01 && same < 0.99, "{apart} {same}");
    assert_each_matches(&after, &[cpu], 0.003, 0.995);
}
