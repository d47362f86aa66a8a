//! The sun study's building, generated in code as a CAD/BIM tool would export it: a
//! 10 × 3 × 7 m hall of 0.25 m slabs, two 2.4 × 1.6 m windows in the south (+z) wall and a
//! 2 × 2 m skylight, all glazed with `alphaMode: BLEND` panes of alpha 0.12, an oak floor,
//! plaster walls, and no lights of its own: the recipe brings the sun and the sky.

use glam::{Vec3, Vec4};
use plenoptic_scene::builder::shapes::cuboid;
use plenoptic_scene::builder::{MaterialDesc, SceneBuilder};
use plenoptic_scene::{AlphaMode, Trs};

/// A 10 × 3 × 7 m building of 0.25 m slabs, as a CAD export has it: windows as openings with
/// BLEND glass panes of alpha 0.12 in the south (+z) wall, a skylight in the roof, no lights.
pub fn building() -> SceneBuilder {
    let mut b = SceneBuilder::new();
    let plaster = b.add_material(MaterialDesc::diffuse(Vec3::splat(0.75)).named("plaster"));
    let floor = b.add_material(MaterialDesc::diffuse(Vec3::new(0.45, 0.35, 0.25)).named("oak"));
    let glass = b.add_material(
        MaterialDesc::diffuse(Vec3::splat(0.9))
            .base_color_alpha(Vec4::new(0.9, 0.95, 0.95, 0.12))
            .alpha_mode(AlphaMode::Blend)
            .double_sided(true)
            .named("Glazing"),
    );
    let t = 0.25;
    let slab = |b: &mut SceneBuilder, name: &str, size: Vec3, at: Vec3, m| {
        b.add_object(
            name,
            cuboid(size),
            m,
            Trs {
                translation: at,
                ..Trs::default()
            },
        );
    };
    let (w, h, d) = (10.0f32, 3.0f32, 7.0f32);
    slab(
        &mut b,
        "Floor",
        Vec3::new(w, t, d),
        Vec3::new(0.0, -t / 2.0, 0.0),
        floor,
    );
    // The roof in two parts around a 2 × 2 m skylight at x ∈ [2, 4], z ∈ [−1, 1].
    slab(
        &mut b,
        "RoofW",
        Vec3::new(7.0, t, d),
        Vec3::new(-1.5, h + t / 2.0, 0.0),
        plaster,
    );
    slab(
        &mut b,
        "RoofE",
        Vec3::new(1.0, t, d),
        Vec3::new(4.5, h + t / 2.0, 0.0),
        plaster,
    );
    slab(
        &mut b,
        "RoofN",
        Vec3::new(2.0, t, 2.5),
        Vec3::new(3.0, h + t / 2.0, -2.25),
        plaster,
    );
    slab(
        &mut b,
        "RoofS",
        Vec3::new(2.0, t, 2.5),
        Vec3::new(3.0, h + t / 2.0, 2.25),
        plaster,
    );
    slab(
        &mut b,
        "Skylight",
        Vec3::new(2.0, 0.01, 2.0),
        Vec3::new(3.0, h + t / 2.0, 0.0),
        glass,
    );
    slab(
        &mut b,
        "North",
        Vec3::new(w, h, t),
        Vec3::new(0.0, h / 2.0, -d / 2.0 + t / 2.0),
        plaster,
    );
    slab(
        &mut b,
        "West",
        Vec3::new(t, h, d - 2.0 * t),
        Vec3::new(-w / 2.0 + t / 2.0, h / 2.0, 0.0),
        plaster,
    );
    slab(
        &mut b,
        "East",
        Vec3::new(t, h, d - 2.0 * t),
        Vec3::new(w / 2.0 - t / 2.0, h / 2.0, 0.0),
        plaster,
    );
    // South wall: piers between two 2.4 × 1.6 m windows (x ∈ [−3.6, −1.2] and [1.2, 3.6]).
    let z = d / 2.0 - t / 2.0;
    for (name, x0, x1) in [
        ("PierW", -5.0, -3.6),
        ("PierM", -1.2, 1.2),
        ("PierE", 3.6, 5.0),
    ] {
        slab(
            &mut b,
            name,
            Vec3::new(x1 - x0, h, t),
            Vec3::new(0.5 * (x0 + x1), h / 2.0, z),
            plaster,
        );
    }
    for (i, x) in [-2.4f32, 2.4].into_iter().enumerate() {
        slab(
            &mut b,
            &format!("Sill{i}"),
            Vec3::new(2.4, 0.8, t),
            Vec3::new(x, 0.4, z),
            plaster,
        );
        slab(
            &mut b,
            &format!("Head{i}"),
            Vec3::new(2.4, 0.6, t),
            Vec3::new(x, 2.7, z),
            plaster,
        );
        slab(
            &mut b,
            &format!("Pane{i}"),
            Vec3::new(2.4, 1.6, 0.01),
            Vec3::new(x, 1.6, z),
            glass,
        );
    }
    b
}
