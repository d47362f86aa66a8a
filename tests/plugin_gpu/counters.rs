//! The cost counters (`bevy_plenoptic::reconstruct::counters`): with
//! `PlenopticSettings::cost_counters` on, the geometry-assisted shaders count their work per
//! pixel into the camera's counter buffer, which is read back into its `CostReport`. The
//! counts must be exact where they can be checked (every reconstruction of a point tries each
//! of the camera's lookups once, and loads its texel), and counting must not change the frame.

use crate::many_cameras::{
    Eye, assert_each_matches, cpu_frame, plugin_cameras_with, settled_frames,
};
use crate::pack::{PackSpec, room, write_pack};
use bevy::prelude::*;
use bevy_plenoptic::prelude::*;
use bevy_plenoptic::reconstruct::counters::CostReport;
use bevy_plenoptic::reconstruct::geometry::view::ViewBuffer;

/// The room, geometry-assisted with counters on: the report counts every covered pixel,
/// `lookups` is the camera's lookup count per reconstruction (the pixel's own and each point
/// the hole fill reconstructs again), each lookup loads at least its texel, a group's largest
/// pixel is at least the mean, and the frame still equals the CPU's.
#[test]
fn counters_count_each_lookup_and_leave_the_frame_unchanged() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("room.pack");
    write_pack(
        &room(true),
        &PackSpec::segment(3, vec![0.0, 1.0, 2.0], 8),
        &path,
    );
    let eye = || Eye {
        at: Vec3::new(0.3, 1.3, 1.0),
        target: Vec3::new(0.0, 0.8, -2.5),
        t: 0.6,
        mode: ReconMode::GeometryAssisted,
    };
    let (mut app, cameras, targets) =
        plugin_cameras_with(dir.path(), &[eye()], |s| s.cost_counters = true);
    let frames = settled_frames(&mut app, &targets);
    let mut report = None;
    for _ in 0..200 {
        app.update();
        report = app.world().get::<CostReport>(cameras[0]).cloned();
        if report.as_ref().is_some_and(|r| r.fragments > 0) {
            break;
        }
    }
    let report: CostReport = report.expect("no cost report was read back");
    let lookups = app
        .world()
        .get::<ViewBuffer>(cameras[0])
        .unwrap()
        .params()
        .lookup_count as f64;
    eprintln!("{lookups} lookups in the view; {report:?}");

    let (w, h) = (crate::common::WIDTH as u64, crate::common::HEIGHT as u64);
    assert!(
        report.fragments >= w * h * 9 / 10,
        "{} fragments counted of {} pixels",
        report.fragments,
        w * h
    );
    let reconstructions = 1.0 + report.mean_of("fill_lookups").unwrap();
    let per = report.mean_of("lookups").unwrap() / reconstructions;
    assert!(lookups >= 2.0);
    assert!(
        (per - lookups).abs() < 1e-6 * lookups,
        "{per} lookups per reconstruction, the view has {lookups}"
    );
    assert!(report.mean_of("loads_16").unwrap() >= report.mean_of("lookups").unwrap());
    assert!(report.group_max_loads >= report.loads && report.group_max_work >= report.work);
    assert!(report.diffuse_fragments > 0 && report.diffuse_loads > 0.0);

    let cpu = cpu_frame(&path, eye());
    assert_each_matches(&frames, &[cpu], 0.003, 0.995);
}
