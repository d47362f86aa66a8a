//! The scene's lights as the manifest lists them (docs/pack-format.md, "Manifest"), with the
//! place of each point and spot light that never moves (pack 4.1): the runtime evaluates
//! those lamps' highlights on glossy surfaces whose reflections it marches for the camera
//! (`plenoptic_recon::lamps`; docs/architecture.md). A lamp whose node or an ancestor is
//! animated is left unplaced, so the runtime keeps the highlights the bake stored.

use plenoptic_pack::{Light, LightKind, LightPlacement};
use plenoptic_scene::Scene;
use plenoptic_scene::recipe::Quality;

/// Whether a bake of `scene` at `quality` leaves its lamps' direct diffuse light to the
/// runtime (pack 5.0, `Manifest::lamps_at_runtime`): `quality.runtime_lamps`, the scene has a
/// point or spot light, and the runtime can evaluate every one
/// ([`plenoptic_pack::lamps_placed`]: none moves, no more than the runtime's maximum).
pub fn lamps_at_runtime(scene: &Scene, quality: &Quality) -> bool {
    let lights = manifest_lights(scene);
    let any = lights.iter().any(|l| l.placed.is_some());
    quality.runtime_lamps && any && plenoptic_pack::lamps_placed(&lights)
}

/// The manifest's lights of `scene`, in the scene's order.
pub fn manifest_lights(scene: &Scene) -> Vec<Light> {
    scene
        .lights
        .iter()
        .enumerate()
        .map(|(i, l)| Light {
            kind: match l.kind {
                plenoptic_scene::LightKind::Point => LightKind::Point,
                plenoptic_scene::LightKind::Spot {
                    inner_cone_angle,
                    outer_cone_angle,
                } => LightKind::Spot {
                    inner_cone: inner_cone_angle,
                    outer_cone: outer_cone_angle,
                },
                plenoptic_scene::LightKind::Directional => LightKind::Directional,
            },
            colour: l.color,
            intensity: l.intensity,
            follows_object: None,
            node_path: scene.nodes.get(l.node).map(|n| n.name.clone()),
            placed: placement(scene, i),
        })
        .collect()
}

/// Where scene light `i` shines from: point and spot lights whose node never moves; `None`
/// for the others.
fn placement(scene: &Scene, i: usize) -> Option<LightPlacement> {
    let l = &scene.lights[i];
    let punctual = matches!(
        l.kind,
        plenoptic_scene::LightKind::Point | plenoptic_scene::LightKind::Spot { .. }
    );
    if !punctual || scene.node_is_animated(l.node) {
        return None;
    }
    let placed = scene.placed_light(i, 0.0);
    Some(LightPlacement {
        position: placed.position,
        direction: placed.direction,
        range: l.range.filter(|r| r.is_finite() && *r > 0.0),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{Quat, Vec3};
    use plenoptic_scene::anim::Track;
    use plenoptic_scene::builder::{LightDesc, NodeDesc, SceneBuilder};

    #[test]
    fn lamps_that_never_move_are_placed_in_the_world() {
        let mut b = SceneBuilder::new();
        // A spot under a static parent, turned to shine along −Y.
        let rig = b.add_node(NodeDesc::new("rig").translation(Vec3::new(1.0, 2.0, 0.0)));
        b.add_node(
            NodeDesc::new("spot")
                .parent(rig)
                .translation(Vec3::new(0.0, 0.5, -1.0))
                .rotation(Quat::from_rotation_arc(Vec3::NEG_Z, Vec3::NEG_Y))
                .light(LightDesc::spot(Vec3::ONE, 5.0, 0.2, 0.4)),
        );
        // A lamp whose parent slides, and the sun.
        let cart = b.add_node(NodeDesc::new("cart"));
        b.animate_translation(cart, Track::linear([(0.0, Vec3::ZERO), (1.0, Vec3::X)]));
        b.add_node(
            NodeDesc::new("bulb")
                .parent(cart)
                .light(LightDesc::point(Vec3::ONE, 2.0)),
        );
        b.add_node(NodeDesc::new("sun").light(LightDesc::directional(Vec3::ONE, 3.0)));
        let scene = b.build_scene().unwrap();
        let lights = manifest_lights(&scene);
        let named = |name: &str| {
            lights
                .iter()
                .find(|l| l.node_path.as_deref() == Some(name))
                .unwrap()
        };
        let spot = named("spot").placed.expect("a static spot is placed");
        assert!((spot.position - Vec3::new(1.0, 2.5, -1.0)).length() < 1e-5);
        assert!((spot.direction - Vec3::NEG_Y).length() < 1e-5);
        assert_eq!(spot.range, None);
        assert!(matches!(named("spot").kind, LightKind::Spot { .. }));
        assert_eq!(named("bulb").placed, None, "its parent moves");
        assert_eq!(named("sun").placed, None, "the sun is no lamp");
    }
}
