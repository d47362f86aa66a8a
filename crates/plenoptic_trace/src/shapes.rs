//! Small scene construction helpers for tests, examples and benchmarks: meshes (quads, boxes,
//! spheres), materials and a builder that assembles a [`Scene`] directly, plus the furnished
//! room used to compare the renderers.
//!
//! (Scenes from files come from `plenoptic_scene`'s importer; this is only for programmatic
//! test scenes.)

use glam::{Quat, Vec2, Vec3, Vec4};
use plenoptic_scene::{
    Interpolation, Key, Light, LightKind, Material, Mesh, Node, Object, ObjectId, Scene, Track,
    Trs, TrsTrack,
};
use std::f32::consts::PI;

/// A quad of `size` in the XZ plane, centred, facing +Y.
pub fn quad(size: Vec2) -> Mesh {
    let (hx, hz) = (size.x * 0.5, size.y * 0.5);
    Mesh {
        positions: vec![
            Vec3::new(-hx, 0.0, -hz),
            Vec3::new(-hx, 0.0, hz),
            Vec3::new(hx, 0.0, hz),
            Vec3::new(hx, 0.0, -hz),
        ],
        normals: vec![Vec3::Y; 4],
        uvs: vec![Vec2::ZERO, Vec2::Y, Vec2::ONE, Vec2::X],
        tangents: Vec::new(),
        colors: Vec::new(),
        triangles: vec![[0, 1, 2], [0, 2, 3]],
    }
}

/// An axis-aligned box of `size`, centred, with outward faces (24 vertices, flat normals):
/// the scene builder's box, so test scenes and glTF-built scenes share one mesh.
pub use plenoptic_scene::builder::shapes::cuboid;

/// A UV sphere of `radius` with `segments` around and `rings` from pole to pole, outward:
/// the scene builder's sphere, so test scenes and glTF-built scenes share one mesh.
pub use plenoptic_scene::builder::shapes::uv_sphere_with_rings as uv_sphere;

/// The mesh turned inside out: winding and normals reversed.
pub fn inverted(mut mesh: Mesh) -> Mesh {
    for t in &mut mesh.triangles {
        t.swap(1, 2);
    }
    for n in &mut mesh.normals {
        *n = -*n;
    }
    mesh
}

/// A pure Lambertian material of albedo `color` (metallic 0, roughness 1, IOR 1 so that the
/// dielectric Fresnel layer vanishes: exactly albedo/π).
pub fn diffuse(color: Vec3) -> Material {
    Material {
        name: "diffuse".into(),
        base_color: color.extend(1.0),
        metallic: 0.0,
        roughness: 1.0,
        ior: 1.0,
        ..Material::default()
    }
}

/// A dielectric with a GGX coat of `roughness` (IOR 1.5) over a Lambertian base.
pub fn plastic(color: Vec3, roughness: f32) -> Material {
    Material {
        name: "plastic".into(),
        base_color: color.extend(1.0),
        metallic: 0.0,
        roughness,
        ..Material::default()
    }
}

/// A metal of reflectance `color` and `roughness` (0 = mirror).
pub fn metal(color: Vec3, roughness: f32) -> Material {
    Material {
        name: "metal".into(),
        base_color: color.extend(1.0),
        metallic: 1.0,
        roughness,
        ..Material::default()
    }
}

/// A clear dielectric (transmission 1) of index `ior` and `roughness`.
pub fn glass(ior: f32, roughness: f32) -> Material {
    Material {
        name: "glass".into(),
        base_color: Vec4::ONE,
        metallic: 0.0,
        roughness,
        transmission: 1.0,
        ior,
        ..Material::default()
    }
}

/// A black Lambertian emitter of radiance `radiance` (front faces).
pub fn emitter(radiance: Vec3) -> Material {
    Material {
        name: "emitter".into(),
        emissive: radiance,
        ..diffuse(Vec3::ZERO)
    }
}

/// Assembles a [`Scene`] directly: one root node per object or light.
#[derive(Debug, Clone, Default)]
pub struct SceneBuilder {
    scene: Scene,
}

impl SceneBuilder {
    /// Adds a material; returns its index.
    pub fn material(&mut self, material: Material) -> usize {
        self.scene.materials.push(material);
        self.scene.materials.len() - 1
    }

    /// Adds an object with its own mesh, placed by `trs`.
    pub fn object_trs(&mut self, name: &str, mesh: Mesh, material: usize, trs: Trs) -> ObjectId {
        self.scene.meshes.push(mesh);
        let node = self.node(name, trs);
        self.scene.objects.push(Object {
            name: name.into(),
            node_path: format!("/{name}"),
            node,
            mesh: self.scene.meshes.len() - 1,
            material,
        });
        (self.scene.objects.len() - 1) as ObjectId
    }

    /// Adds an object translated to `position`.
    pub fn object(&mut self, name: &str, mesh: Mesh, material: usize, position: Vec3) -> ObjectId {
        self.object_trs(
            name,
            mesh,
            material,
            Trs {
                translation: position,
                ..Trs::default()
            },
        )
    }

    /// Animates object `id` linearly through `keys` of (time, translation).
    pub fn animate_translation(&mut self, id: ObjectId, keys: &[(f32, Vec3)]) {
        let node = self.scene.objects[id as usize].node;
        self.scene.nodes[node].track = Some(TrsTrack {
            translation: Some(Track {
                interpolation: Interpolation::Linear,
                keys: keys
                    .iter()
                    .map(|&(time, value)| Key {
                        time,
                        value,
                        in_tangent: Vec3::ZERO,
                        out_tangent: Vec3::ZERO,
                    })
                    .collect(),
            }),
            rotation: None,
            scale: None,
        });
    }

    /// Adds a point light of `intensity` (glTF candela) and `color` at `position`.
    pub fn point_light(&mut self, position: Vec3, color: Vec3, intensity: f32) -> usize {
        let node = self.node(
            "light",
            Trs {
                translation: position,
                ..Trs::default()
            },
        );
        self.scene.lights.push(Light {
            name: format!("light{}", self.scene.lights.len()),
            kind: LightKind::Point,
            color,
            intensity,
            range: None,
            angular_radius: 0.0,
            node,
        });
        self.scene.lights.len() - 1
    }

    fn node(&mut self, name: &str, rest: Trs) -> usize {
        self.scene.nodes.push(Node {
            name: name.into(),
            parent: None,
            rest,
            track: None,
        });
        self.scene.nodes.len() - 1
    }

    /// The scene.
    pub fn build(self) -> Scene {
        self.scene
    }
}

/// Rotation taking +Y to `normal`.
fn facing(normal: Vec3) -> Quat {
    let n = normal.normalize();
    if n.dot(Vec3::Y) < -0.999 {
        return Quat::from_rotation_x(PI);
    }
    Quat::from_rotation_arc(Vec3::Y, n)
}

/// Index of the animated object in [`furnished_room`].
pub const ROOM_ANIMATED_OBJECT: &str = "sliding_box";

/// A furnished room, 4 m × 2.6 m × 5 m (x ∈ [−2, 2], y ∈ [0, 2.6], z ∈ [−2.5, 2.5]): red and
/// green side walls, white floor, back wall and ceiling, a 1 m² ceiling light panel, a table
/// (top and four legs), two boxes, a plastic, a rough metal and a mirror sphere, and a box
/// that slides along x from t = 0 to t = 2 s. About 3k triangles. A good camera:
/// [`room_camera`].
pub fn furnished_room() -> Scene {
    let mut b = SceneBuilder::default();
    let m = RoomMaterials::add(&mut b);
    room_shell(&mut b, &m);
    room_furniture(&mut b, &m);
    let slider = b.object(
        ROOM_ANIMATED_OBJECT,
        cuboid(Vec3::splat(0.35)),
        m.red,
        Vec3::new(-0.5, 0.175, 1.0),
    );
    b.animate_translation(
        slider,
        &[
            (0.0, Vec3::new(-1.2, 0.175, 1.0)),
            (2.0, Vec3::new(0.8, 0.175, 0.6)),
        ],
    );
    b.point_light(Vec3::new(1.2, 2.0, 1.5), Vec3::new(1.0, 0.9, 0.8), 1.5);
    b.build()
}

/// The materials of [`furnished_room`], as indices into its builder.
struct RoomMaterials {
    white: usize,
    red: usize,
    green: usize,
    wood: usize,
    blue: usize,
    gold: usize,
    mirror: usize,
    light: usize,
}

impl RoomMaterials {
    /// Adds the room's materials to `b`.
    fn add(b: &mut SceneBuilder) -> Self {
        Self {
            white: b.material(plastic(Vec3::splat(0.75), 0.9)),
            red: b.material(plastic(Vec3::new(0.7, 0.12, 0.1), 0.9)),
            green: b.material(plastic(Vec3::new(0.15, 0.6, 0.15), 0.9)),
            wood: b.material(plastic(Vec3::new(0.45, 0.28, 0.15), 0.6)),
            blue: b.material(plastic(Vec3::new(0.2, 0.3, 0.7), 0.4)),
            gold: b.material(metal(Vec3::new(0.95, 0.75, 0.4), 0.3)),
            mirror: b.material(metal(Vec3::splat(0.9), 0.0)),
            light: b.material(emitter(Vec3::new(12.0, 11.0, 9.5))),
        }
    }
}

/// The room's floor, ceiling, four walls and ceiling light panel: quads centred at a point,
/// facing into the room. A quad's extent is (x, z) before it is turned to face its normal.
fn room_shell(b: &mut SceneBuilder, m: &RoomMaterials) {
    let panels = [
        ("floor", [4.0, 5.0], [0.0, 0.0, 0.0], Vec3::Y, m.white),
        ("ceiling", [4.0, 5.0], [0.0, 2.6, 0.0], -Vec3::Y, m.white),
        ("back_wall", [4.0, 2.6], [0.0, 1.3, -2.5], Vec3::Z, m.white),
        ("front_wall", [4.0, 2.6], [0.0, 1.3, 2.5], -Vec3::Z, m.white),
        ("left_wall", [2.6, 5.0], [-2.0, 1.3, 0.0], Vec3::X, m.red),
        ("right_wall", [2.6, 5.0], [2.0, 1.3, 0.0], -Vec3::X, m.green),
        (
            "light_panel",
            [1.0, 1.0],
            [0.0, 2.59, -0.5],
            -Vec3::Y,
            m.light,
        ),
    ];
    for (name, size, translation, normal, material) in panels {
        let trs = Trs {
            translation: Vec3::from(translation),
            rotation: facing(normal),
            scale: Vec3::ONE,
        };
        b.object_trs(name, quad(Vec2::from(size)), material, trs);
    }
}

/// The room's table (top and four legs), its two boxes and three spheres.
fn room_furniture(b: &mut SceneBuilder, m: &RoomMaterials) {
    b.object(
        "table_top",
        cuboid(Vec3::new(1.6, 0.06, 0.9)),
        m.wood,
        Vec3::new(0.3, 0.75, -1.0),
    );
    for (dx, dz) in [(-0.72, -0.38), (0.72, -0.38), (-0.72, 0.38), (0.72, 0.38)] {
        b.object(
            "table_leg",
            cuboid(Vec3::new(0.06, 0.72, 0.06)),
            m.wood,
            Vec3::new(0.3 + dx, 0.36, -1.0 + dz),
        );
    }
    b.object_trs(
        "tall_box",
        cuboid(Vec3::new(0.5, 1.2, 0.5)),
        m.white,
        Trs {
            translation: Vec3::new(-1.3, 0.6, -1.6),
            rotation: Quat::from_rotation_y(0.35),
            scale: Vec3::ONE,
        },
    );
    b.object(
        "blue_box",
        cuboid(Vec3::new(0.4, 0.4, 0.4)),
        m.blue,
        Vec3::new(0.6, 0.98, -1.1),
    );
    let spheres = [
        ("plastic_sphere", 0.3, m.blue, Vec3::new(-0.8, 0.3, 0.2)),
        ("gold_sphere", 0.2, m.gold, Vec3::new(-0.1, 0.98, -0.9)),
        ("mirror_sphere", 0.35, m.mirror, Vec3::new(1.3, 0.35, 0.3)),
    ];
    for (name, radius, material, position) in spheres {
        b.object(name, uv_sphere(radius, 32, 16), material, position);
    }
}

/// A camera for [`furnished_room`] near the front wall looking at the table.
pub fn room_camera(width: u32, height: u32) -> crate::Result<crate::PinholeCamera> {
    crate::PinholeCamera::look_at(
        Vec3::new(0.0, 1.4, 2.3),
        Vec3::new(0.0, 0.9, -1.0),
        Vec3::Y,
        1.05,
        width,
        height,
    )
}

/// A 4 × 3 × 4 m room of 0.2 m slabs with one 1.6 × 1.2 m window in the +z wall, lit only by
/// a Hosek–Wilkie sky (model units, `scale` 1) whose sun stands 35° up behind the room: only
/// the sky's light enters. The environment tests and the `trace` benchmark use it.
pub fn sky_lit_room() -> Scene {
    let mut b = SceneBuilder::default();
    let wall = b.material(diffuse(Vec3::splat(0.7)));
    let floor = b.material(diffuse(Vec3::new(0.5, 0.4, 0.3)));
    let t = 0.2;
    let mut slab = |name: &str, size: Vec3, at: Vec3, m: usize| {
        b.object(name, cuboid(size), m, at);
    };
    slab(
        "Floor",
        Vec3::new(4.4, t, 4.4),
        Vec3::new(0.0, -t / 2.0, 0.0),
        floor,
    );
    slab(
        "Ceiling",
        Vec3::new(4.4, t, 4.4),
        Vec3::new(0.0, 3.0 + t / 2.0, 0.0),
        wall,
    );
    slab(
        "Back",
        Vec3::new(4.4, 3.0, t),
        Vec3::new(0.0, 1.5, -2.0 - t / 2.0),
        wall,
    );
    slab(
        "Left",
        Vec3::new(t, 3.0, 4.0),
        Vec3::new(-2.0 - t / 2.0, 1.5, 0.0),
        wall,
    );
    slab(
        "Right",
        Vec3::new(t, 3.0, 4.0),
        Vec3::new(2.0 + t / 2.0, 1.5, 0.0),
        wall,
    );
    // The window wall, around the opening x ∈ [−0.8, 0.8], y ∈ [1, 2.2].
    let z = 2.0 + t / 2.0;
    slab(
        "FrontL",
        Vec3::new(1.2 + t, 3.0, t),
        Vec3::new(-1.4 - t / 2.0, 1.5, z),
        wall,
    );
    slab(
        "FrontR",
        Vec3::new(1.2 + t, 3.0, t),
        Vec3::new(1.4 + t / 2.0, 1.5, z),
        wall,
    );
    slab("Sill", Vec3::new(1.6, 1.0, t), Vec3::new(0.0, 0.5, z), wall);
    slab(
        "Lintel",
        Vec3::new(1.6, 0.8, t),
        Vec3::new(0.0, 2.6, z),
        wall,
    );
    let sun = b.node(
        "Sun",
        Trs {
            rotation: Quat::IDENTITY,
            ..Trs::default()
        },
    );
    let mut scene = b.build();
    let towards = Vec3::new(0.3, 35f32.to_radians().sin(), -1.0).normalize();
    scene.lights.push(Light {
        name: "Sun".into(),
        kind: LightKind::Directional,
        color: Vec3::ONE,
        intensity: 0.0,
        range: None,
        angular_radius: 0.0,
        node: sun,
    });
    scene.sun = Some(plenoptic_scene::Sun {
        light: scene.lights.len() - 1,
        track: Some(plenoptic_sky::SunTrack::fixed(towards, Vec3::ZERO)),
    });
    scene.environment = plenoptic_scene::Environment::Sky(plenoptic_sky::SkyParams {
        scale: 1.0,
        ..plenoptic_sky::SkyParams::default()
    });
    scene
}

/// A camera in [`sky_lit_room`] from the window side towards the back corner: floor, walls
/// and the patch of sky light on the floor.
pub fn sky_room_camera(width: u32, height: u32) -> crate::Result<crate::PinholeCamera> {
    crate::PinholeCamera::look_at(
        Vec3::new(1.2, 1.6, 1.6),
        Vec3::new(-1.0, 0.6, -1.8),
        Vec3::Y,
        1.2,
        width,
        height,
    )
}
