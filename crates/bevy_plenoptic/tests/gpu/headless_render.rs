//! Proves the rendering path CI relies on: a Bevy app starts without a window on the
//! software Vulkan driver, renders a lit scene into an image, and the pixels read back
//! show what was drawn.

use crate::common::*;
use bevy::prelude::*;
use bevy_plenoptic::{PlenopticPlugin, PlenopticSettings};

#[test]
fn renders_a_frame_and_reads_it_back() {
    let mut app = headless_app();
    app.add_plugins(PlenopticPlugin);
    app.finish();
    app.cleanup();

    let world = app.world_mut();
    let image = target_image(&mut world.resource_mut::<Assets<Image>>());
    let mesh = world
        .resource_mut::<Assets<Mesh>>()
        .add(Cuboid::new(1.0, 1.0, 1.0));
    let material = world
        .resource_mut::<Assets<StandardMaterial>>()
        .add(StandardMaterial {
            base_color: Color::linear_rgb(0.0, 1.0, 0.0),
            unlit: true,
            ..default()
        });
    // A unit cube 3 m in front of the camera covers the middle of the frame; the red clear
    // colour fills the rest.
    world.spawn((Mesh3d(mesh), MeshMaterial3d(material), Transform::default()));
    world.spawn(camera_into(
        image.clone(),
        Transform::from_xyz(0.0, 0.0, 3.0).looking_at(Vec3::ZERO, Vec3::Y),
    ));

    // Wait until the cube's pipeline has compiled and the centre pixel is no longer the
    // clear colour; the assertions below then check what was drawn.
    let data = render_until(&mut app, image, 3000, |data| {
        data.len() == (WIDTH * HEIGHT * 4) as usize && {
            let centre = pixel(data, WIDTH / 2, HEIGHT / 2);
            centre[3] == 255 && centre[0] < 128
        }
    });
    assert_eq!(data.len(), (WIDTH * HEIGHT * 4) as usize);

    let centre = pixel(&data, WIDTH / 2, HEIGHT / 2);
    assert!(
        centre[1] > 240 && centre[0] < 15 && centre[2] < 15,
        "centre {centre:?}"
    );
    let corner = pixel(&data, 1, 1);
    assert!(
        corner[0] > 240 && corner[1] < 15 && corner[2] < 15,
        "corner {corner:?}"
    );

    // The cube's silhouette: a 1 m cube at 3 m with Bevy's default 45° vertical field of view
    // spans about 1 / (2·(3−0.5)·tan 22.5°) ≈ 48 % of the frame height.
    let green_rows = (0..HEIGHT)
        .filter(|&y| pixel(&data, WIDTH / 2, y)[1] > 128)
        .count() as f32;
    let fraction = green_rows / HEIGHT as f32;
    assert!(
        (0.40..0.56).contains(&fraction),
        "cube covers {fraction} of the height"
    );

    assert!(app.world().contains_resource::<PlenopticSettings>());
}
