//! Normal maps under a mirroring placement. A node with a negative scale (as exporters write
//! mirrored copies) must show its normal map mirrored: the shading normal at a point is the
//! mirror image of the unmirrored copy's at the mirrored point. The bitangent, the cross
//! product of the placed normal and tangent, comes out negated under a mirror and has to be
//! flipped back (glTF's MikkTSpace tangents; Bevy's `mesh_tangent_local_to_world` flips it
//! the same way, so the plugin's GPU path and the CPU's agree with the tracer).

use glam::{Vec2, Vec3};
use plenoptic_scene::builder::{MaterialDesc, NodeDesc, SceneBuilder};
use plenoptic_trace::{Ray, SceneAccel};

/// A 2 × 2 normal map whose every texel leans 30° towards +v (the bitangent).
fn leaning_map() -> Vec<u8> {
    let (sin, cos) = 30f32.to_radians().sin_cos();
    let byte = |v: f32| ((v * 0.5 + 0.5) * 255.0).round() as u8;
    [byte(0.0), byte(sin), byte(cos), 255].repeat(4)
}

/// The shading normal where a ray straight down meets the floor at `(x, z)`, with the floor
/// scaled by `scale`.
fn shading_normal(scale: Vec3, x: f32, z: f32) -> Vec3 {
    let mut b = SceneBuilder::new();
    let map = b.add_texture_rgba8(2, 2, leaning_map());
    let m = b.add_material(MaterialDesc::diffuse(Vec3::splat(0.5)).normal_texture(map));
    let plane = b.add_plane("floor", Vec2::splat(4.0), 1, m);
    b.add_node(NodeDesc::new("floor").mesh(plane).scale(scale));
    let scene = b.build_scene().unwrap();
    let accel = SceneAccel::new(&scene).unwrap();
    let hit = accel
        .at_time(0.0)
        .intersect(&Ray::new(Vec3::new(x, 3.0, z), -Vec3::Y))
        .expect("the ray meets the floor");
    hit.shading_normal
}

#[test]
fn a_mirrored_node_shows_its_normal_map_mirrored() {
    let plain = shading_normal(Vec3::ONE, 0.3, 0.7);
    // The map leans the normal away from the geometric one, along the floor.
    assert!(plain.y < 0.95 && plain.y > 0.8, "{plain}");
    assert!(Vec2::new(plain.x, plain.z).length() > 0.4, "{plain}");
    for axis in [Vec3::X, Vec3::Z] {
        let mirror = Vec3::ONE - 2.0 * axis;
        let mirrored = shading_normal(mirror, 0.3 * mirror.x, 0.7 * mirror.z);
        let expected = plain * mirror;
        assert!(
            (mirrored - expected).length() < 1e-3,
            "mirrored along {axis}: {mirrored}, expected {expected} (unmirrored {plain})"
        );
    }
}
