use glam::{Quat, Vec3};
use plenoptic_pack::{Interpolation, ObjectTracks, ProxyMesh, Track};

use super::*;
use crate::ObjectMotion;
use crate::proxy::PackProxy;
use crate::shadow::ShadowScene;

/// Quads (two triangles each) as one mesh.
fn quads(id: u32, quads: &[[Vec3; 4]]) -> ProxyMesh {
    let mut positions = Vec::new();
    let mut indices = Vec::new();
    for q in quads {
        let b = positions.len() as u32;
        positions.extend_from_slice(q);
        indices.extend_from_slice(&[b, b + 1, b + 2, b, b + 2, b + 3]);
    }
    ProxyMesh {
        object_id: id,
        positions,
        indices,
        normals: None,
    }
}

/// An axis-aligned box's six faces.
fn box_faces(lo: Vec3, hi: Vec3) -> Vec<[Vec3; 4]> {
    let c = |x: bool, y: bool, z: bool| {
        Vec3::new(
            if x { hi.x } else { lo.x },
            if y { hi.y } else { lo.y },
            if z { hi.z } else { lo.z },
        )
    };
    let (f, t) = (false, true);
    vec![
        [c(f, f, f), c(f, t, f), c(f, t, t), c(f, f, t)],
        [c(t, f, f), c(t, t, f), c(t, t, t), c(t, f, t)],
        [c(f, f, f), c(t, f, f), c(t, f, t), c(f, f, t)],
        [c(f, t, f), c(t, t, f), c(t, t, t), c(f, t, t)],
        [c(f, f, f), c(t, f, f), c(t, t, f), c(f, t, f)],
        [c(f, f, t), c(t, f, t), c(t, t, t), c(f, t, t)],
    ]
}

/// A 4 × 3 × 4 room with a 1 × 1 window in its +x wall, a pillar, and a cube that slides
/// 2 m along z over the first second.
fn scene() -> ProxyGeometry {
    let (x0, x1, y1, z0, z1) = (-2.0, 2.0, 3.0, -2.0, 2.0);
    let v = Vec3::new;
    let mut room = box_faces(v(x0, 0.0, z0), v(x1, y1, z1));
    // The +x wall around a window at y 1..2, z −0.5..0.5.
    room[1] = [
        v(x1, 0.0, z0),
        v(x1, 1.0, z0),
        v(x1, 1.0, z1),
        v(x1, 0.0, z1),
    ];
    room.push([v(x1, 2.0, z0), v(x1, y1, z0), v(x1, y1, z1), v(x1, 2.0, z1)]);
    room.push([
        v(x1, 1.0, z0),
        v(x1, 2.0, z0),
        v(x1, 2.0, -0.5),
        v(x1, 1.0, -0.5),
    ]);
    room.push([
        v(x1, 1.0, 0.5),
        v(x1, 2.0, 0.5),
        v(x1, 2.0, z1),
        v(x1, 1.0, z1),
    ]);
    let pillar = box_faces(v(-1.0, 0.0, -1.0), v(-0.6, 3.0, -0.6));
    let cube = box_faces(Vec3::splat(-0.25), Vec3::splat(0.25));
    let motion = ObjectMotion::new(&ObjectTracks {
        object_id: 3,
        translation: Some(Track {
            interpolation: Interpolation::Linear,
            times: vec![0.0, 1.0],
            values: vec![v(1.0, 1.5, 0.0), v(1.0, 1.5, 2.0)],
        }),
        rotation: Some(Track {
            interpolation: Interpolation::Linear,
            times: vec![0.0, 1.0],
            values: vec![Quat::IDENTITY, Quat::from_rotation_y(0.7)],
        }),
        scale: None,
    });
    let proxy = |id: u32, mesh: ProxyMesh, track: Option<ObjectMotion>| PackProxy {
        id,
        name: format!("object{id}"),
        node_path: format!("object{id}"),
        mesh,
        track,
    };
    ProxyGeometry::from_proxies(&[
        proxy(1, quads(1, &room), None),
        proxy(2, quads(2, &pillar), None),
        proxy(3, quads(3, &cube), Some(motion)),
    ])
    .unwrap()
}

/// Deterministic points in the unit cube (a 3-D additive recurrence).
fn r3(k: u32) -> Vec3 {
    let g = 1.220_744_1_f64;
    let a = [1.0 / g, 1.0 / (g * g), 1.0 / (g * g * g)];
    let f = |i: usize| ((0.5 + a[i] * f64::from(k)).fract()) as f32;
    Vec3::new(f(0), f(1), f(2))
}

/// The flat layout's traversal answers as the CPU's BVHs do, with the moving cube at two
/// times, on rays from inside the room in every direction; and so does the layout with the
/// pillar as glazing in a BVH of its own.
#[test]
fn the_flat_traversal_agrees_with_the_cpus_bvhs() {
    let geometry = scene();
    let shadows = ShadowScene::new(&geometry);
    let glazed = FlatRays::with_see_through(&geometry, [(2, 0.5)]);
    assert_eq!(glazed.moving(), &[3, 2]);
    agrees_with(&geometry, &shadows, &glazed);
    let flat = FlatRays::new(&geometry);
    assert_eq!(flat.moving(), &[3]);
    agrees_with(&geometry, &shadows, &flat);
}

/// [`the_flat_traversal_agrees_with_the_cpus_bvhs`] for one layout.
fn agrees_with(geometry: &ProxyGeometry, shadows: &ShadowScene, flat: &FlatRays) {
    let (mut agree, mut total, mut blocked) = (0, 0, 0);
    for t in [0.0, 0.6] {
        let placed = shadows.at(geometry, t);
        let placements = flat.placements(|id| geometry.transform(id, t));
        for k in 0..4000 {
            let o = r3(k) * Vec3::new(3.8, 2.8, 3.8) + Vec3::new(-1.9, 0.1, -1.9);
            let d = (r3(k + 7919) * 2.0 - 1.0).normalize_or(Vec3::X);
            let tmax = if k % 2 == 0 { 100.0 } else { 1.0 };
            let cpu = placed.occluded(o, d, tmax);
            let gpu = flat.occluded(&placements, o, d, tmax);
            agree += u32::from(cpu == gpu);
            blocked += u32::from(cpu);
            total += 1;
        }
    }
    // Only rays through a shared edge may be told apart by the two tests' rounding.
    assert!(agree + 2 >= total, "{agree} of {total} agree");
    // Both kinds of answer occur (half the rays are short).
    assert!(
        blocked > total / 4 && blocked < total,
        "{blocked} of {total} blocked"
    );
}

/// Hand-picked rays: out through the window, into a wall, and against the moving cube
/// before and after it slid away.
#[test]
fn windows_let_rays_out_and_the_moving_cube_follows_its_track() {
    let geometry = scene();
    let flat = FlatRays::new(&geometry);
    let at = |t: f32| flat.placements(|id| geometry.transform(id, t));
    let o = Vec3::new(0.0, 1.5, 0.0);
    // Through the window (the cube is at z = 2 at t = 1, out of the way).
    assert!(!flat.occluded(&at(1.0), o, Vec3::X, 100.0));
    // At t = 0 the cube sits in front of the window.
    assert!(flat.occluded(&at(0.0), o, Vec3::X, 100.0));
    // ... but not within 0.5 m.
    assert!(!flat.occluded(&at(0.0), o, Vec3::X, 0.5));
    // Below the window: the wall.
    assert!(flat.occluded(&at(1.0), Vec3::new(0.0, 0.5, 0.0), Vec3::X, 100.0));
    // Behind the pillar.
    let to_pillar = (Vec3::new(-0.8, 1.5, -0.7) - o).normalize();
    assert!(flat.occluded(&at(1.0), o, to_pillar, 1.0));
    assert!(!flat.occluded(&at(1.0), o, to_pillar, 0.8));
}

/// A pack without proxies casts nothing, and a placement buffer is never empty.
#[test]
fn no_geometry_occludes_nothing() {
    let none = FlatRays::none();
    assert!(!none.occluded(&[], Vec3::ZERO, Vec3::X, 1e9));
    assert_eq!(none.placements(|_| Affine3A::IDENTITY).len(), 1);
    let flat = FlatRays::new(&scene());
    // Header: the flag, and the moving table after it.
    assert_eq!(flat.words()[0].w.to_bits(), 1);
    assert_eq!(flat.words()[1].z.to_bits(), 3);
}

/// The CPU's nearest hit (the surface a mirror's ray meets, `crate::reflected`) names the
/// object and the triangle of its mesh, the moving cube's in its own space included.
#[test]
fn the_nearest_hit_names_its_object_and_triangle() {
    let geometry = scene();
    let shadows = ShadowScene::new(&geometry);
    // Off the cube's face diagonal, which obvhs's triangle test misses (see hits_triangle).
    let o = Vec3::new(0.0, 1.6, 0.1);
    // At t = 0 the cube (half-size 0.25 at x = 1) is in front of the window: its −x face
    // (quad 0: triangles 0 and 1) at 0.75 m.
    let hit = shadows
        .at(&geometry, 0.0)
        .nearest(o, Vec3::X, 100.0)
        .unwrap();
    assert_eq!((hit.object, hit.triangle / 2), (3, 0));
    assert!((hit.t - 0.75).abs() < 1e-4, "{hit:?}");
    // At t = 1 it has slid away: out through the window, nothing.
    assert_eq!(shadows.at(&geometry, 1.0).nearest(o, Vec3::X, 100.0), None);
    // Down to the floor (room quad 2) at 1.5 m, and towards the pillar (object 2), whose
    // +x face (quad 1) is nearer than the room's wall behind it.
    let floor = shadows
        .at(&geometry, 1.0)
        .nearest(o, Vec3::NEG_Y, 100.0)
        .unwrap();
    assert_eq!((floor.object, floor.triangle / 2), (1, 2));
    assert!((floor.t - 1.6).abs() < 1e-4);
    let to_pillar = (Vec3::new(-0.8, 1.6, -0.8) - o).normalize();
    let pillar = shadows
        .at(&geometry, 1.0)
        .nearest(o, to_pillar, 100.0)
        .unwrap();
    assert_eq!(pillar.object, 2);
    assert!(
        pillar.t < (Vec3::new(-0.8, 1.6, -0.8) - o).length(),
        "{pillar:?}"
    );
    // Beyond tmax: nothing.
    assert_eq!(
        shadows.at(&geometry, 1.0).nearest(o, Vec3::NEG_Y, 1.0),
        None
    );
}

/// See-through objects let `1 − c` through at each surface a shadow ray crosses, as the
/// tracer's rays pass BLEND coverage; an opaque surface anywhere along the ray stops it. The
/// GPU's flat layout gives the glazing's part alike.
#[test]
fn see_through_objects_pass_one_minus_coverage_per_surface() {
    let geometry = scene();
    let shadows = ShadowScene::new(&geometry).with_see_through([(2, 0.5), (3, 0.3)]);
    // Off the cube's face diagonals, where two triangles meet.
    let o = Vec3::new(0.0, 1.6, 0.1);
    let placed = shadows.at(&geometry, 0.0);
    // Out of the window through the moving cube's two faces.
    let through_cube = placed.transmittance(o, Vec3::X, 100.0);
    assert!((through_cube - 0.49).abs() < 1e-6, "{through_cube}");
    // Through the fixed pillar's two faces, then the wall behind it stops the ray.
    let to_pillar = (Vec3::new(-0.8, 1.7, -0.7) - o).normalize();
    let before_wall = placed.transmittance(o, to_pillar, 1.5);
    assert!((before_wall - 0.25).abs() < 1e-6, "{before_wall}");
    assert_eq!(placed.transmittance(o, to_pillar, 100.0), 0.0);
    // The cube slid away by t = 1: nothing in the window.
    let later = shadows.at(&geometry, 1.0);
    assert_eq!(later.transmittance(o, Vec3::X, 100.0), 1.0);
    // The GPU's layout: the glazing alone dims the ray (the wall behind the pillar is the
    // shadow map's), every surface still stops an occlusion test.
    let flat = FlatRays::with_see_through(&geometry, [(2, 0.5), (3, 0.3)]);
    let at = |t: f32| flat.placements(|id| geometry.transform(id, t));
    let gpu_cube = flat.see_through_pass(&at(0.0), o, Vec3::X, 100.0);
    assert!((gpu_cube - 0.49).abs() < 1e-6, "{gpu_cube}");
    let gpu_pillar = flat.see_through_pass(&at(0.0), o, to_pillar, 100.0);
    assert!((gpu_pillar - 0.25).abs() < 1e-6, "{gpu_pillar}");
    assert_eq!(flat.see_through_pass(&at(1.0), o, Vec3::X, 100.0), 1.0);
    assert!(flat.occluded(&at(0.0), o, Vec3::X, 100.0));
    assert!(flat.occluded(&at(0.0), o, to_pillar, 1.5));
    assert_eq!(
        FlatRays::new(&geometry).see_through_pass(&at(0.0), o, Vec3::X, 100.0),
        1.0
    );
    // Without see-through objects the answer is the occlusion test's.
    let opaque = ShadowScene::new(&geometry);
    let placed = opaque.at(&geometry, 0.0);
    assert_eq!(placed.transmittance(o, Vec3::X, 100.0), 0.0);
    assert_eq!(placed.transmittance(o, to_pillar, 0.8), 1.0);
}
