//! A closed room lit through a glazed window: the pane 1 cm thick, `alphaMode: BLEND`,
//! alpha 0.12, as CAD exporters write glass, and the sun shining through it onto the floor
//! (`tests/sunlit_interior.rs`, `tests/light_groups.rs`).

use glam::{Quat, Vec3, Vec4};
use plenoptic_scene::AlphaMode;
use plenoptic_scene::builder::{LightDesc, MaterialDesc, NodeDesc, SceneBuilder};

/// Inner half-size of the room, and its walls' thickness.
pub const HALF: f32 = 2.0;
pub const WALL: f32 = 0.2;
/// The window in the +x wall: y and z extents.
pub const WINDOW_Y: (f32, f32) = (-0.6, 0.9);
pub const WINDOW_Z: (f32, f32) = (-1.3, 1.3);

/// Where the sunlight travels: in through the window, down onto the floor.
pub fn sun_direction() -> Vec3 {
    Vec3::new(-1.0, -1.1, 0.25).normalize()
}

/// A box of `size` centred at `c`.
fn slab(b: &mut SceneBuilder, name: &str, c: Vec3, size: Vec3, mat: MaterialDesc) {
    let mat = b.add_material(mat);
    let mesh = b.add_box(name, size, mat);
    b.add_node(NodeDesc::new(name).mesh(mesh).translation(c));
}

/// The room: floor, ceiling, three plain walls, the +x wall around the window, the pane in
/// the window, a table on the floor, and the sun.
pub fn scene() -> SceneBuilder {
    scene_with_sun(4.0)
}

/// [`scene`] with a sun of illuminance `sun`.
pub fn scene_with_sun(sun: f32) -> SceneBuilder {
    let mut b = SceneBuilder::new();
    let plaster = MaterialDesc::diffuse(Vec3::splat(0.7));
    let floor = MaterialDesc::diffuse(Vec3::new(0.55, 0.45, 0.35));
    let outer = 2.0 * HALF + 2.0 * WALL;
    let d = HALF + 0.5 * WALL;
    slab(
        &mut b,
        "floor",
        Vec3::new(0.0, -d, 0.0),
        Vec3::new(outer, WALL, outer),
        floor,
    );
    slab(
        &mut b,
        "ceiling",
        Vec3::new(0.0, d, 0.0),
        Vec3::new(outer, WALL, outer),
        plaster.clone(),
    );
    slab(
        &mut b,
        "wall_w",
        Vec3::new(-d, 0.0, 0.0),
        Vec3::new(WALL, outer, outer),
        plaster.clone(),
    );
    slab(
        &mut b,
        "wall_s",
        Vec3::new(0.0, 0.0, -d),
        Vec3::new(outer, outer, WALL),
        plaster.clone(),
    );
    slab(
        &mut b,
        "wall_n",
        Vec3::new(0.0, 0.0, d),
        Vec3::new(outer, outer, WALL),
        plaster.clone(),
    );
    // The +x wall as four pieces around the window.
    let (y0, y1) = WINDOW_Y;
    let (z0, z1) = WINDOW_Z;
    let pieces = [
        ("wall_e_below", (-HALF, y0), (-HALF, HALF)),
        ("wall_e_above", (y1, HALF), (-HALF, HALF)),
        ("wall_e_left", (y0, y1), (-HALF, z0)),
        ("wall_e_right", (y0, y1), (z1, HALF)),
    ];
    for (name, (ya, yb), (za, zb)) in pieces {
        let c = Vec3::new(d, 0.5 * (ya + yb), 0.5 * (za + zb));
        slab(
            &mut b,
            name,
            c,
            Vec3::new(WALL, yb - ya, zb - za),
            plaster.clone(),
        );
    }
    let glazing = MaterialDesc::diffuse(Vec3::splat(0.9))
        .base_color_alpha(Vec4::new(0.9, 0.95, 0.95, 0.12))
        .alpha_mode(AlphaMode::Blend)
        .double_sided(true)
        .named("glazing");
    let pane = Vec3::new(d, 0.5 * (y0 + y1), 0.5 * (z0 + z1));
    slab(
        &mut b,
        "pane",
        pane,
        Vec3::new(0.01, y1 - y0, z1 - z0),
        glazing,
    );
    let wood = MaterialDesc::diffuse(Vec3::new(0.5, 0.3, 0.15));
    slab(
        &mut b,
        "table",
        Vec3::new(-0.9, -1.3, 1.0),
        Vec3::new(0.8, 0.08, 0.8),
        wood,
    );
    b.add_node(
        NodeDesc::new("sun")
            .light(LightDesc::directional(Vec3::ONE, sun))
            .rotation(Quat::from_rotation_arc(Vec3::NEG_Z, sun_direction())),
    );
    b
}

/// Whether the sun reaches floor point `p` through the window opening (the pane aside).
pub fn sunlit(p: Vec3) -> bool {
    let towards = -sun_direction();
    // Where the ray towards the sun crosses the wall's inner face.
    let s = (HALF - p.x) / towards.x;
    let q = p + towards * s;
    let (y0, y1) = WINDOW_Y;
    let (z0, z1) = WINDOW_Z;
    p.y < -HALF + 1e-2 && (y0..y1).contains(&q.y) && (z0..z1).contains(&q.z)
}

/// A camera in the room's south-west corner looking down at the sun patch.
pub fn camera(width: u32, height: u32) -> plenoptic_recon::Camera {
    plenoptic_recon::Camera::look_at(
        Vec3::new(-1.6, 0.4, -1.5),
        Vec3::new(0.4, -1.6, 0.4),
        Vec3::Y,
        75f32.to_radians(),
        width,
        height,
    )
    .unwrap()
}
