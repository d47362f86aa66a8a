//! The baked scene on screen: proxy geometry spawned from the pack and animated from its
//! tracks composites with ordinary Bevy meshes through the depth buffer; streaming stays
//! inside a budget smaller than the pack along a camera path through the whole view space.

mod common;

use bevy::prelude::*;
use bevy_plenoptic::prelude::*;
use bevy_plenoptic::proxy::ProxyOf;
use bevy_plenoptic::streaming::{StreamState, StreamingStats};
use common::pack::{PackSpec, room, write_pack};
use common::*;

fn room_pack(dir: &std::path::Path, views: usize) {
    write_pack(
        &room(true),
        &PackSpec::segment(views, vec![0.0, 1.0, 2.0], 8),
        &dir.join("room.pack"),
    );
}

/// Drawn (alpha 1) and not the red clear colour.
fn shows_scene(p: [u8; 4]) -> bool {
    p[3] == 255 && p[0] < 200
}

fn green_cube(app: &mut App, at: Vec3) {
    let world = app.world_mut();
    let mesh = world
        .resource_mut::<Assets<Mesh>>()
        .add(Cuboid::new(0.4, 0.4, 0.4));
    let material = world
        .resource_mut::<Assets<StandardMaterial>>()
        .add(StandardMaterial {
            base_color: Color::linear_rgb(0.0, 1.0, 0.0),
            unlit: true,
            ..default()
        });
    world.spawn((
        Mesh3d(mesh),
        MeshMaterial3d(material),
        Transform::from_translation(at),
    ));
}

/// Renders the room from (0, 1.3, 1) looking down −z with a green cube at `cube`; returns
/// the centre pixel once proxy geometry covers the frame.
fn centre_with_cube(cube: Vec3) -> [u8; 4] {
    let dir = tempfile::tempdir().unwrap();
    room_pack(dir.path(), 2);
    let mut app = headless_app_in(dir.path());
    let handle: Handle<RadiancePack> = app.world().resource::<AssetServer>().load("room.pack");
    let image = target_image(&mut app.world_mut().resource_mut::<Assets<Image>>());
    let eye = Vec3::new(0.0, 1.3, 1.0);
    app.world_mut().spawn((
        camera_into(
            image.clone(),
            Transform::from_translation(eye).looking_at(Vec3::new(0.0, 1.3, -2.5), Vec3::Y),
        ),
        PlenopticCamera {
            playback: Playback::Manual,
            ..PlenopticCamera::new(handle)
        },
    ));
    green_cube(&mut app, cube);
    // A witness cube left of centre, always in view: once it shows, the cubes' pipeline has
    // compiled, so a grey centre means "hidden", not "not drawn yet".
    green_cube(&mut app, Vec3::new(-0.3, 1.3, 0.0));
    // Ready when the closed room covers the corners (no red clear colour left) and the
    // witness is drawn.
    let data = render_until(&mut app, image, 3000, |d| {
        d.len() == (WIDTH * HEIGHT * 4) as usize
            && [(1, 1), (WIDTH - 2, HEIGHT - 2), (WIDTH / 2, HEIGHT / 2)]
                .iter()
                .all(|&(x, y)| shows_scene(pixel(d, x, y)))
            && pixel(d, 12, HEIGHT / 2)[1] > 240
    });
    let corner = pixel(&data, 1, 1);
    assert!(
        (100..156).contains(&corner[0]) && corner[0].abs_diff(corner[1]) <= 1,
        "proxy wall {corner:?}"
    );
    pixel(&data, WIDTH / 2, HEIGHT / 2)
}

#[test]
fn bevy_mesh_in_front_of_baked_geometry_is_visible() {
    let centre = centre_with_cube(Vec3::new(0.0, 1.3, -0.5));
    assert!(centre[1] > 240 && centre[0] < 15, "centre {centre:?}");
}

#[test]
fn bevy_mesh_behind_baked_geometry_is_hidden() {
    // Behind the back wall (z = −2.5): the wall's depth hides it.
    let centre = centre_with_cube(Vec3::new(0.0, 1.3, -3.2));
    assert!(
        centre[1] < 200 && centre[0].abs_diff(centre[1]) <= 1,
        "centre {centre:?}"
    );
}

#[test]
fn proxies_follow_the_tracks_and_budget_holds_along_a_path() {
    let dir = tempfile::tempdir().unwrap();
    room_pack(dir.path(), 5);
    let mut app = headless_app_in(dir.path());
    // One key (4 cubes of 8² × 6 texels, 4 bytes each) is 6 KiB; the pack holds 15 keys.
    let key_bytes = 4 * 6 * 64 * 4;
    let budget = 3 * key_bytes + key_bytes / 2;
    {
        let mut s = app.world_mut().resource_mut::<PlenopticSettings>();
        s.memory_budget_bytes = budget;
        s.max_views = 1;
    }
    let handle: Handle<RadiancePack> = app.world().resource::<AssetServer>().load("room.pack");
    let image = target_image(&mut app.world_mut().resource_mut::<Assets<Image>>());
    let camera = app
        .world_mut()
        .spawn((
            camera_into(image.clone(), Transform::from_xyz(-1.0, 1.3, 1.0)),
            PlenopticCamera {
                playback: Playback::Manual,
                ..PlenopticCamera::new(handle.clone())
            },
        ))
        .id();
    // Wait for the first frame of the room.
    render_until(&mut app, image.clone(), 3000, |d| {
        shows_scene(pixel(d, 1, 1))
    });
    let frames = 40;
    for i in 0..=frames {
        let s = i as f32 / frames as f32;
        {
            let mut e = app.world_mut().entity_mut(camera);
            e.get_mut::<Transform>().unwrap().translation = Vec3::new(-1.0 + 2.0 * s, 1.3, 1.0);
            e.get_mut::<PlenopticCamera>().unwrap().time = 2.0 * s;
        }
        // Render until this position's needed keys are resident (at most 30 frames); every
        // frame, complete or not, stays inside the budget.
        for _ in 0..30 {
            app.update();
            let stats = app.world().resource::<StreamingStats>();
            assert!(stats.resident_bytes <= budget, "frame {i}: {stats:?}");
            if app.world().get::<StreamState>(camera).unwrap().complete {
                break;
            }
            std::thread::sleep(std::time::Duration::from_millis(2));
        }
    }
    let stats = app.world().resource::<StreamingStats>().clone();
    assert!(stats.peak_resident_bytes <= budget, "{stats:?}");
    assert!(stats.decoded_keys >= 5, "{stats:?}");
    assert!(stats.evictions > 0, "{stats:?}");
    // Every frame still renders: a final frame reads back with the room on screen.
    let data = render_until(&mut app, image, 50, |d| shows_scene(pixel(d, 1, 1)));
    assert!(shows_scene(pixel(&data, 1, 1)));

    // The slider (object 9) sits where its track puts it at t = 2: x = 1.2.
    let mut q = app.world_mut().query::<(&ProxyOf, &Transform)>();
    let slider = q
        .iter(app.world())
        .find(|(p, _)| p.id == 9)
        .map(|(_, t)| *t)
        .expect("slider proxy");
    assert!(
        (slider.translation - Vec3::new(1.2, 0.25, -0.2)).length() < 1e-4,
        "{slider:?}"
    );
}
