//! BVHs, hits, cameras and id-images.

use glam::{Quat, Vec2, Vec3};
use plenoptic_scene::{NO_OBJECT, Scene};
use plenoptic_trace::{
    CUBE_FACES, Camera, CubeCamera, CubeFace, FisheyeCamera, PinholeCamera, Ray, SceneAccel,
    TraceError, shapes,
};

/// Six boxes, one on each axis at distance 3, object id = face index.
fn six_boxes() -> Scene {
    let mut b = shapes::SceneBuilder::default();
    let m = b.material(shapes::diffuse(Vec3::splat(0.5)));
    let dirs = [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
    for (i, d) in dirs.iter().enumerate() {
        b.object(
            &format!("box{i}"),
            shapes::cuboid(Vec3::splat(1.0)),
            m,
            *d * 3.0,
        );
    }
    b.build()
}

#[test]
fn empty_scene_is_an_error() {
    let scene = Scene::default();
    assert!(matches!(
        SceneAccel::new(&scene),
        Err(TraceError::EmptyScene)
    ));
}

#[test]
fn invalid_cameras_are_errors() {
    assert!(PinholeCamera::new(Vec3::ZERO, Quat::IDENTITY, 0.0, 4, 4).is_err());
    assert!(PinholeCamera::new(Vec3::ZERO, Quat::IDENTITY, 1.0, 0, 4).is_err());
    assert!(CubeCamera::new(Vec3::NAN, 8).is_err());
    assert!(FisheyeCamera::new(Vec3::ZERO, Quat::IDENTITY, 7.0, 8).is_err());
}

#[test]
fn closest_hit_reports_the_surface() {
    let mut b = shapes::SceneBuilder::default();
    let m = b.material(shapes::diffuse(Vec3::ONE));
    b.object("floor", shapes::quad(Vec2::splat(4.0)), m, Vec3::ZERO);
    b.object(
        "box",
        shapes::cuboid(Vec3::ONE),
        m,
        Vec3::new(0.0, 2.0, 0.0),
    );
    let scene = b.build();
    let accel = SceneAccel::new(&scene).unwrap();
    let placed = accel.at_time(0.0);
    // Down through the box: its top face at y = 2.5 first.
    let hit = placed
        .intersect(&Ray::new(Vec3::new(0.1, 5.0, 0.2), -Vec3::Y))
        .unwrap();
    assert_eq!(hit.object, 1);
    assert!((hit.distance - 2.5).abs() < 1e-5);
    assert!(hit.geometric_normal.abs_diff_eq(Vec3::Y, 1e-5));
    assert!(hit.front_face);
    assert!(hit.position.abs_diff_eq(Vec3::new(0.1, 2.5, 0.2), 1e-5));
    // Beside the box: the floor, whose uv runs over [0, 1]² across its 4 m.
    let hit = placed
        .intersect(&Ray::new(Vec3::new(1.0, 5.0, 1.0), -Vec3::Y))
        .unwrap();
    assert_eq!(hit.object, 0);
    assert!((hit.distance - 5.0).abs() < 1e-5);
    assert!(
        hit.uv.abs_diff_eq(Vec2::new(0.75, 0.75), 1e-5),
        "{}",
        hit.uv
    );
    // From below: back face.
    let hit = placed
        .intersect(&Ray::new(Vec3::new(1.0, -1.0, 1.0), Vec3::Y))
        .unwrap();
    assert!(!hit.front_face);
    // Shadow rays respect tmax.
    let mut r = Ray::new(Vec3::new(0.0, 5.0, 0.0), -Vec3::Y);
    r.tmax = 2.4;
    assert!(!placed.occluded(&r));
    r.tmax = 2.6;
    assert!(placed.occluded(&r));
    assert!(
        placed
            .intersect(&Ray::new(Vec3::new(0.0, 5.0, 0.0), Vec3::Y))
            .is_none()
    );
}

#[test]
fn pinhole_id_image_and_animation() {
    let mut scene = shapes::furnished_room();
    let slider = scene
        .objects
        .iter()
        .position(|o| o.name == shapes::ROOM_ANIMATED_OBJECT)
        .unwrap() as u32;
    assert!(scene.object_is_animated(slider));
    let accel = SceneAccel::new(&scene).unwrap();
    // Look straight down at the slider's start and end positions.
    let look = |p: Vec3| {
        PinholeCamera::look_at(p + Vec3::new(0.0, 2.0, 0.0), p, Vec3::Z, 0.1, 3, 3).unwrap()
    };
    let start = Vec3::new(-1.2, 0.0, 1.0);
    let end = Vec3::new(0.8, 0.0, 0.6);
    let p0 = accel.at_time(0.0);
    let p2 = accel.at_time(2.0);
    assert_eq!(*p0.id_image(&look(start)).get(1, 1), slider);
    assert_ne!(*p2.id_image(&look(start)).get(1, 1), slider);
    assert_eq!(*p2.id_image(&look(end)).get(1, 1), slider);
    // A camera outside the room looking away sees nothing.
    let away = PinholeCamera::look_at(
        Vec3::new(0.0, 1.0, 10.0),
        Vec3::new(0.0, 1.0, 20.0),
        Vec3::Y,
        1.0,
        4,
        4,
    )
    .unwrap();
    assert!(p0.id_image(&away).pixels.iter().all(|&id| id == NO_OBJECT));
    scene.objects.clear();
}

/// Vulkan's cube map face selection (spec table "Cube map face selection"), written out
/// independently: direction → (face, s, t) with s, t ∈ [0, 1].
fn vulkan_select(d: Vec3) -> (usize, f32, f32) {
    let a = d.abs();
    let (face, sc, tc, ma) = if a.x >= a.y && a.x >= a.z {
        if d.x > 0.0 {
            (0, -d.z, -d.y, a.x)
        } else {
            (1, d.z, -d.y, a.x)
        }
    } else if a.y >= a.z {
        if d.y > 0.0 {
            (2, d.x, d.z, a.y)
        } else {
            (3, d.x, -d.z, a.y)
        }
    } else if d.z > 0.0 {
        (4, d.x, -d.y, a.z)
    } else {
        (5, -d.x, -d.y, a.z)
    };
    (face, 0.5 * (sc / ma + 1.0), 0.5 * (tc / ma + 1.0))
}

#[test]
fn cube_faces_follow_vulkan() {
    let cube = CubeCamera::new(Vec3::ZERO, 8).unwrap();
    for face in CUBE_FACES {
        let cam = cube.face(face);
        for (x, y) in [(0, 0), (7, 0), (0, 7), (3, 5), (7, 7)] {
            let r = cam.ray(x, y, Vec2::splat(0.5)).unwrap();
            let (f, s, t) = vulkan_select(r.direction);
            assert_eq!(f, face.index(), "{face:?} pixel ({x}, {y})");
            assert!((s * 8.0 - (x as f32 + 0.5)).abs() < 1e-4, "{face:?} s");
            assert!((t * 8.0 - (y as f32 + 0.5)).abs() < 1e-4, "{face:?} t");
        }
    }
    assert_eq!(
        CubeFace::PosX.direction(-1.0, -1.0),
        Vec3::new(1.0, 1.0, 1.0)
    );
}

#[test]
fn cube_id_images_see_the_box_on_each_axis() {
    let scene = six_boxes();
    let accel = SceneAccel::new(&scene).unwrap();
    let placed = accel.at_time(0.0);
    let cube = CubeCamera::new(Vec3::ZERO, 9).unwrap();
    for face in CUBE_FACES {
        let ids = placed.id_image(&cube.face(face));
        assert_eq!(*ids.get(4, 4), face.index() as u32, "{face:?}");
        // The corners look 54.7° off the axis, past the 1 m box at 3 m.
        assert_eq!(*ids.get(0, 0), NO_OBJECT);
    }
}

#[test]
fn fisheye_covers_the_sphere() {
    let scene = six_boxes();
    let accel = SceneAccel::new(&scene).unwrap();
    let placed = accel.at_time(0.0);
    let cam = FisheyeCamera::new(Vec3::ZERO, Quat::IDENTITY, std::f32::consts::TAU, 33).unwrap();
    let ids = placed.id_image(&cam);
    assert_eq!(*ids.get(16, 16), 5, "centre looks along −Z");
    // Half-way to the rim: 90° off the axis, i.e. +X on the right and +Y at the top.
    assert_eq!(*ids.get(24, 16), 0);
    assert_eq!(*ids.get(8, 16), 1);
    assert_eq!(*ids.get(16, 8), 2);
    assert_eq!(*ids.get(16, 24), 3);
    assert_eq!(*ids.get(0, 0), NO_OBJECT, "outside the circle");
    // Near the rim: behind, +Z.
    assert_eq!(*ids.get(32, 16), 4);
}
