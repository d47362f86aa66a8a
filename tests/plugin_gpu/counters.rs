//! The cost counters (`bevy_plenoptic::reconstruct::counters`): with
//! `PlenopticSettings::cost_counters` on, the geometry-assisted shaders count their work per
//! pixel into the camera's counter buffer, which is read back into its `CostReport`. The
//! counts must be exact where they can be checked (every reconstruction of a point tries each
//! of the camera's lookups once, and loads its texel), and counting must not change the frame.

use crate::harness::{compare, compare_on};
use crate::many_cameras::{
    Eye, assert_each_matches, cpu_frame, cpu_frame_with, plugin_cameras_with, settled_frames,
};
use crate::pack::{Materials, PackSpec, room, write_pack};
use bevy::camera::Hdr;
use bevy::core_pipeline::tonemapping::Tonemapping;
use bevy::prelude::*;
use bevy_plenoptic::prelude::*;
use bevy_plenoptic::reconstruct::counters::CostReport;
use bevy_plenoptic::reconstruct::geometry::view::ViewBuffer;

/// The room with its moving slider, three views of keys at 0, 1 and 2 s, objects with
/// `materials`, written as `room.pack` in a new temporary folder.
fn room_pack(materials: Materials) -> (tempfile::TempDir, std::path::PathBuf) {
    room_pack_of(materials, 8)
}

/// [`room_pack`] with cube faces of `face` texels.
fn room_pack_of(materials: Materials, face: u32) -> (tempfile::TempDir, std::path::PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("room.pack");
    write_pack(
        &room(true),
        &PackSpec {
            materials,
            ..PackSpec::segment(3, vec![0.0, 1.0, 2.0], face)
        },
        &path,
    );
    (dir, path)
}

/// The first cost report `camera` reads back.
fn first_report(app: &mut App, camera: Entity) -> CostReport {
    for _ in 0..200 {
        app.update();
        if let Some(r) = app.world().get::<CostReport>(camera)
            && r.fragments > 0
        {
            return r.clone();
        }
    }
    panic!("no cost report was read back");
}

/// The room's camera below, geometry-assisted.
fn eye() -> Eye {
    Eye {
        at: Vec3::new(0.3, 1.3, 1.0),
        target: Vec3::new(0.0, 0.8, -2.5),
        t: 0.6,
        mode: ReconMode::GeometryAssisted,
    }
}

/// The settled frames of `eye()` over the room pack in `dir` with counters on (and the
/// screen-space fill on or off, the camera's settings changed by `tweak`), its first cost
/// report and the view's lookup count.
fn counted(
    dir: &std::path::Path,
    screen_fill: bool,
    tweak: impl Fn(&mut ReconSettings),
) -> (Vec<Vec<Vec3>>, CostReport, f64) {
    counted_with(dir, (screen_fill, false), tweak)
}

/// [`counted`], with the lookup kernel on or off (`fills.1`) where the screen fill is on
/// (`fills.0`).
fn counted_with(
    dir: &std::path::Path,
    (screen_fill, lookup_kernel): (bool, bool),
    tweak: impl Fn(&mut ReconSettings),
) -> (Vec<Vec<Vec3>>, CostReport, f64) {
    let (mut app, cameras, targets) = plugin_cameras_with(dir, &[eye()], |s| {
        s.cost_counters = true;
        s.screen_fill = screen_fill;
        s.lookup_kernel = lookup_kernel;
    });
    tweak(
        &mut app
            .world_mut()
            .get_mut::<PlenopticCamera>(cameras[0])
            .unwrap()
            .settings,
    );
    let frames = settled_frames(&mut app, &targets);
    let report = first_report(&mut app, cameras[0]);
    let lookups = app
        .world()
        .get::<ViewBuffer>(cameras[0])
        .unwrap()
        .params()
        .lookup_count as f64;
    eprintln!("screen fill {screen_fill}: {lookups} lookups in the view; {report:?}");
    (frames, report, lookups)
}

/// The room, geometry-assisted with counters on: the report counts every covered pixel,
/// `lookups` is the camera's lookup count per reconstruction (the pixel's own and each point
/// the fragment hole fill reconstructs again), each lookup loads at least its texel, a
/// group's largest pixel is at least the mean, and the frame still equals the CPU's. With the
/// screen-space fill no fragment reconstructs a neighbour; without it the holes' fragments do,
/// and the frame is the same.
#[test]
fn counters_count_each_lookup_and_leave_the_frame_unchanged() {
    let (dir, path) = room_pack(Materials::None);
    let cpu = cpu_frame(&path, eye());
    let (screen, fragment) = (
        counted(dir.path(), true, |_| {}),
        counted(dir.path(), false, |_| {}),
    );
    // The fragment fill reconstructs its ring's points where the CPU and the screen fill
    // average the ring pixels' results: in the holes the lookups' face test leaves at a
    // crease, that differs by a few per cent (measured: 99.3 % of pixels within 5 %, mean
    // 0.0016; the screen fill 99.97 % and 0.0007).
    for ((frames, report, lookups), within5) in [(&screen, 0.995), (&fragment, 0.99)] {
        let (w, h) = (crate::common::WIDTH as u64, crate::common::HEIGHT as u64);
        assert!(
            report.fragments >= w * h * 9 / 10,
            "{} fragments counted of {} pixels",
            report.fragments,
            w * h
        );
        let reconstructions = 1.0 + report.mean_of("fill_lookups").unwrap();
        let per = report.mean_of("lookups").unwrap() / reconstructions;
        assert!(*lookups >= 2.0);
        assert!(
            (per - lookups).abs() < 1e-6 * lookups,
            "{per} lookups per reconstruction, the view has {lookups}"
        );
        // A lookup loads its texel, in the fragment or in the lookup kernel.
        let loads_16 = report.mean_of("loads_16").unwrap() + report.kernel_loads;
        assert!(loads_16 >= report.mean_of("lookups").unwrap());
        assert!(report.group_max_loads >= report.loads && report.group_max_work >= report.work);
        assert!(report.diffuse_fragments > 0 && report.diffuse_loads + report.kernel_loads > 0.0);
        assert_each_matches(frames, std::slice::from_ref(&cpu), 0.003, within5);
    }
    // The same holes, entered by both; reconstructed again only by the fragment fill.
    let (s, f) = (&screen.1, &fragment.1);
    assert!(s.mean_of("fill").unwrap() > 0.1, "{s:?}");
    assert!((s.mean_of("fill").unwrap() - f.mean_of("fill").unwrap()).abs() < 1e-9);
    assert_eq!(s.mean_of("fill_lookups"), Some(0.0));
    assert!(f.mean_of("fill_lookups").unwrap() > 1.0, "{f:?}");
    eprintln!(
        "fetches per pixel: screen fill {:.1} + kernel {:.1}, fragment fill {:.1} ({:.2}×)",
        s.loads,
        s.kernel_loads,
        f.loads,
        f.loads / (s.loads + s.kernel_loads)
    );
    assert!(s.kernel_loads > 0.0 && f.kernel_loads == 0.0);
    assert!(s.loads + s.kernel_loads < f.loads);
}

/// The lookup kernel (`bevy_plenoptic::reconstruct::geometry::lookup_kernel`): with it the
/// opaque fragments make no lookup (they load nothing on this pack without materials) and
/// the kernel makes every pixel's, once; the frame is the one the fragments' own lookups
/// give, and the CPU's.
#[test]
fn the_lookup_kernel_makes_every_pixels_lookups_for_the_same_frame() {
    let (dir, path) = room_pack(Materials::Factors);
    let dense = |s: &mut ReconSettings| s.sparse_lighting = false;
    let (kernel, in_kernel, lookups) = counted_with(dir.path(), (true, true), dense);
    let (fragments, in_fragments, _) = counted_with(dir.path(), (true, false), |_| {});
    let m = |r: &CostReport, n: &str| r.mean_of(n).unwrap();
    eprintln!(
        "fetches per pixel: lookup kernel {:.1} + {:.1} in the kernels, fragments {:.1} + {:.1}",
        in_kernel.loads, in_kernel.kernel_loads, in_fragments.loads, in_fragments.kernel_loads
    );
    // Every pixel's lookups, made once either way.
    assert!((m(&in_kernel, "lookups") - m(&in_fragments, "lookups")).abs() < 1e-6 * lookups);
    assert!(in_kernel.loads < 0.5 * in_fragments.loads, "{in_kernel:?}");
    assert!(
        in_kernel.kernel_loads > in_fragments.kernel_loads,
        "{in_kernel:?}"
    );
    let (mean, f5, _) = compare(&kernel[0], &fragments[0]);
    assert!(
        mean < 1e-3 && f5 > 0.999,
        "kernel against fragments: {mean} {f5}"
    );
    assert_each_matches(&kernel, &[cpu_frame(&path, eye())], 0.003, 0.995);
}

/// The sparse lighting in the lookup kernel (`ReconSettings::sparse_lighting`, on by
/// default, `plenoptic_recon`'s `geometry::sparse` rule): materials' lighting is looked up at
/// the anchors (even row and column) and interpolated between them where they agree, so the
/// kernel makes fewer lookups; the frame is within a hair of the kernel's dense frame and
/// equals the CPU's sparse frame about as closely as the dense one equals the CPU's dense
/// frame. 32-texel faces: at 8 most anchors' footprints cross an outline or a seam in some
/// key, and interpolate nothing.
#[test]
fn the_lookup_kernel_interpolates_sparse_lighting_as_the_cpu_does() {
    let (dir, path) = room_pack_of(Materials::Factors, 32);
    let (sparse, in_sparse, _) = counted_with(dir.path(), (true, true), |_| {});
    let dense_settings = |s: &mut ReconSettings| s.sparse_lighting = false;
    let (dense, in_dense, _) = counted_with(dir.path(), (true, true), dense_settings);
    let m = |r: &CostReport, n: &str| r.mean_of(n).unwrap();
    let ratio = m(&in_sparse, "lookups") / m(&in_dense, "lookups");
    eprintln!(
        "sparse lighting: {:.2} lookups per pixel against {:.2} ({ratio:.2}×); fetches {:.1} against {:.1}",
        m(&in_sparse, "lookups"),
        m(&in_dense, "lookups"),
        in_sparse.loads + in_sparse.kernel_loads,
        in_dense.loads + in_dense.kernel_loads,
    );
    assert!(ratio < 0.8, "{in_sparse:?}");
    // Measured: 18.1 fetches against 20.6 (an anchor's cell and entry, two loads, against a
    // blended pair's load and 5 or 6 gathers).
    let fetches = |r: &CostReport| r.loads + r.kernel_loads;
    assert!(
        fetches(&in_sparse) < 0.95 * fetches(&in_dense),
        "{in_sparse:?}"
    );
    let (mean, f5, _) = compare(&sparse[0], &dense[0]);
    eprintln!("sparse against dense: mean {mean:.5}, within 5 % {f5:.4}");
    assert!(
        mean < 2e-3 && f5 > 0.995,
        "sparse against dense: {mean} {f5}"
    );
    let cpu_sparse = cpu_frame(&path, eye());
    let cpu_dense = cpu_frame_with(&path, eye(), dense_settings);
    let (to_sparse, _, _) = compare(&sparse[0], &cpu_sparse);
    let (dense_to_dense, _, _) = compare(&dense[0], &cpu_dense);
    eprintln!("against the CPU: sparse {to_sparse:.5}, dense {dense_to_dense:.5}");
    assert!(to_sparse <= dense_to_dense * 1.25 + 2e-4);
    assert_each_matches(&sparse, &[cpu_sparse], 0.003, 0.995);
}

/// With a negative depth tolerance no lookup is accepted: every pixel is a hole and no ring holds
/// an answered pixel. Without the lookup kernel the hole list fills to its room (a quarter of
/// the pixels) and the fill kernel takes its holes' later fallbacks from the keys (the
/// object's nearby texels, else the heaviest key's texel); the holes past the room fill
/// themselves in their fragments. With the lookup kernel the list has a record per pixel and
/// every hole is filled by the kernels. Both frames still equal the CPU's.
#[test]
fn every_pixel_a_hole_fills_as_on_the_cpu() {
    let (dir, path) = room_pack(Materials::None);
    let cpu = cpu_frame_with(&path, eye(), |s| s.depth_tolerance = -1.0);
    for lookup_kernel in [false, true] {
        let (frames, report, _) = counted_with(dir.path(), (true, lookup_kernel), |s| {
            s.depth_tolerance = -1.0
        });
        let m = |n: &str| report.mean_of(n).unwrap();
        // Every fragment a hole, each taking the nearby texels: without the lookup kernel a
        // quarter in the fill kernel, the rest after reconstructing its ring in the fragment.
        assert!(m("fill") > 0.99 && m("neighbour") > 0.99, "{report:?}");
        assert!(report.kernel_loads > 0.0, "{report:?}");
        if lookup_kernel {
            assert_eq!(m("fill_lookups"), 0.0, "{report:?}");
        } else {
            assert!(m("fill_lookups") > 1.0, "{report:?}");
        }
        assert_each_matches(&frames, std::slice::from_ref(&cpu), 0.003, 0.995);
    }
}

/// A pack with materials: each view's two time keys are blended once per frame where they
/// agree (`bevy_plenoptic::reconstruct::geometry::blend`), and a lookup of the still walls
/// reads its pair once, so the frame loads fewer key texels than it tries lookups; the slider,
/// which moves between the keys, takes them apart. The frame still equals the CPU's.
#[test]
fn blended_pairs_load_still_objects_once_for_both_keys() {
    let (dir, path) = room_pack(Materials::Factors);
    let (frames, report, _) = counted(dir.path(), true, |_| {});
    let m = |n: &str| report.mean_of(n).unwrap();
    // One nearest-texel load per pair where it decides (two lookups), one per lookup where
    // the keys are taken apart.
    assert!(m("loads_16") < 0.75 * m("lookups"), "{report:?}");
    assert_each_matches(&frames, &[cpu_frame(&path, eye())], 0.003, 0.995);
}

/// The settled frame of `eye()` over the room pack in `dir` with Bevy's 4× MSAA on the
/// camera, counters on and the screen-space fill on or off, and its first cost report; with
/// `tonemapping`, on an 8-bit target tonemapped so (the camera's `Hdr` taken off).
fn msaa_frame(
    dir: &std::path::Path,
    screen_fill: bool,
    tonemapping: Option<Tonemapping>,
) -> (Vec<Vec3>, CostReport) {
    let (mut app, cameras, targets) = plugin_cameras_with(dir, &[eye()], |s| {
        s.cost_counters = true;
        s.screen_fill = screen_fill;
    });
    let mut camera = app.world_mut().entity_mut(cameras[0]);
    camera.insert(Msaa::Sample4);
    if let Some(t) = tonemapping {
        camera.remove::<Hdr>().insert(t);
    }
    let mut frames = settled_frames(&mut app, &targets);
    let report = first_report(&mut app, cameras[0]);
    (frames.swap_remove(0), report)
}

/// With Bevy's 4× MSAA the screen fill fills the holes as the fragment fill does: its
/// composite draws each hole's samples (the fragment's coverage) at the hole surface's depth,
/// so a sample of the pixel that an occluder covers keeps the occluder, and no fragment
/// reconstructs a neighbour. The frame equals the fragment fill's at the same MSAA, and the
/// CPU's but at silhouettes, where MSAA blends two objects.
#[test]
fn the_screen_fill_takes_msaa_cameras_too() {
    let (dir, path) = room_pack(Materials::None);
    let (screen, report) = msaa_frame(dir.path(), true, None);
    let m = |n: &str| report.mean_of(n).unwrap();
    assert!(m("fill") > 0.1 && m("fill_lookups") == 0.0, "{report:?}");
    assert!(report.kernel_loads > 0.0, "{report:?}");
    let (fragment, _) = msaa_frame(dir.path(), false, None);
    let (mean, f5, f20) = compare(&screen, &fragment);
    eprintln!(
        "4× MSAA: screen fill against fragment fill mean {mean:.4}, within 5 % {f5:.4}, within 20 % {f20:.4}"
    );
    // Measured on lavapipe: mean 0.0055, 99.15 % within 5 %, 99.64 % within 20 %. The pixels
    // apart lie along a silhouette over a hole: a pixel there keeps one entry for its two
    // objects, so the kernel's search misses a neighbour the fragment fill reconstructs.
    assert!(mean < 0.012 && f5 > 0.98 && f20 > 0.99, "{mean} {f5} {f20}");
    let (mean, f5, f20) = compare(&screen, &cpu_frame(&path, eye()));
    eprintln!(
        "4× MSAA: screen fill against CPU mean {mean:.4}, within 5 % {f5:.4}, within 20 % {f20:.4}"
    );
    // Measured on lavapipe: mean 0.0201, 96.7 % within 5 %, 97.6 % within 20 % (the fragment
    // fill: 0.0230, 95.8 %, 97.2 %). The mean is left out: MSAA's blends of a bright and a dark
    // object at silhouettes dominate it, and it varies between lavapipe's builds.
    assert!(f5 > 0.93 && f20 > 0.95, "{mean} {f5} {f20}");
}

/// On a camera without an HDR target (Bevy's default, here with 4× MSAA and Reinhard
/// tonemapping) the screen fill's composite tonemaps the filled holes as the proxies'
/// fragments tonemap theirs: the frame equals the fragment fill's on the same camera.
#[test]
fn the_screen_fill_tonemaps_on_an_8_bit_target() {
    let (dir, _) = room_pack(Materials::None);
    let ldr = Some(Tonemapping::Reinhard);
    let (screen, report) = msaa_frame(dir.path(), true, ldr);
    let m = |n: &str| report.mean_of(n).unwrap();
    assert!(m("fill") > 0.1 && m("fill_lookups") == 0.0, "{report:?}");
    let (fragment, report) = msaa_frame(dir.path(), false, ldr);
    assert!(report.mean_of("fill_lookups").unwrap() > 0.0, "{report:?}");
    let (mean, f5, f20) = compare(&screen, &fragment);
    eprintln!(
        "8-bit, Reinhard, 4× MSAA: screen fill against fragment fill mean {mean:.4}, within 5 % {f5:.4}, within 20 % {f20:.4}"
    );
    assert!(mean < 0.012 && f5 > 0.98 && f20 > 0.99, "{mean} {f5} {f20}");
}

/// The GPU's antialiasing is Bevy's MSAA (docs/architecture.md, "Reconstruction"), measured:
/// with 4× MSAA the frame is nearer the CPU's frame supersampled 4 × 4 (a box filter over each
/// pixel, as the path tracer's pixels are) than with one sample per pixel. MSAA smooths the
/// silhouettes; lighting inside a pixel is still looked up once, at its centre.
#[test]
fn msaa_brings_the_frame_nearer_the_supersampled_cpu_frame() {
    let (dir, path) = room_pack(Materials::None);
    let (single, _, _) = counted(dir.path(), true, |_| {});
    let (msaa, _) = msaa_frame(dir.path(), true, None);
    let cpu = cpu_frame_with(&path, eye(), |s| s.supersampling = 4);
    let (off, off5, _) = compare_on(&single[0], &cpu);
    let (on, on5, _) = compare_on(&msaa, &cpu);
    eprintln!(
        "against the CPU's 4 × 4 supersampled frame: one sample mean {off:.4} ({off5:.4} within 5 %), 4× MSAA mean {on:.4} ({on5:.4} within 5 %)"
    );
    // Measured on lavapipe: one sample mean 0.0316 (87.8 % within 5 %), 4× MSAA 0.0221
    // (89.8 %).
    assert!(on < 0.8 * off && on5 > off5, "{off} {on} {off5} {on5}");
}
