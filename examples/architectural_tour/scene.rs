//! The architectural tour scene, generated in code with [`SceneBuilder`].
//!
//! Units are metres, +Y is up, the walkable floor is at y = 0 and the eye height of the tour
//! is [`EYE_HEIGHT`]. The building is 24 m × 12 m (x ∈ [−12, 12], z ∈ [−6, 6]) and has three
//! parts side by side along x:
//!
//! - **Room A** (x ∈ [−12, −4], 3.2 m high): a reading room. Two windows in the south wall,
//!   a large mirror on the north wall, a table with benches, a bookshelf, and a ceiling fan
//!   that turns.
//! - **Atrium** (x ∈ [−4, 4], 6.5 m high): a gallery under a skylight, with four columns,
//!   a flight of stairs against the north wall, benches, a tall south window, and a sculpture
//!   that revolves on its pedestal.
//! - **Room B** (x ∈ [4, 12], 3.2 m high): a gallery with two south windows and one east
//!   window glazed with a BLEND pane (as exporters write glass), a glass vitrine on a plinth, shelves, a table, a lamp, a cart that crosses the
//!   room and comes back along a cubic spline, and a sliding door between it and the atrium.
//!
//! Room A opens to the atrium through a wide doorway at x = −4; room B through a doorway at
//! x = 4 closed by the sliding door at the start, open from 2.5 s to 10 s.
//!
//! The sun is a directional light whose rotation is animated over the whole tour
//! ([`DURATION`] seconds): it climbs from the south-east and sets towards the south-west, so
//! the patches of sunlight from the windows and the skylight travel across the floors. The
//! bake recipe (`assets/tour.toml`) replaces that animation with a sun study (`[sun]`: a day
//! in Paris) and a Hosek–Wilkie sky that the windows show; the glb's own animation is what an
//! app that loads the glb without the recipe sees.
//!
//! Materials are textured in code ([`textures`]): oak planks in room A, tiles in the
//! atrium, stone slabs in room B and on the stairs, plaster on the walls, brick on the
//! atrium's north wall, fabric on the atrium's benches, brushed steel. Every mesh has UVs in
//! metres (box-mapped), and each texture's transform sets how many metres it repeats over.
//!
//! Object names follow `Part_Thing` (`RoomA_Mirror`, `Atrium_Column_2`, `RoomB_Cart`, …) so
//! tests and tools can find them. The scene is deterministic: the same code writes the same
//! bytes.

#[path = "textures.rs"]
mod textures;

use std::f32::consts::{FRAC_PI_2, PI, TAU};

use glam::{Quat, Vec2, Vec3, Vec4};
use plenoptic_scene::builder::{
    LightDesc, MaterialDesc, MaterialHandle, NodeDesc, NodeHandle, SceneBuilder, shapes,
};
use plenoptic_scene::{AlphaMode, Mesh, Track, Trs};

/// Length of the animation, seconds.
pub const DURATION: f32 = 14.0;
/// Eye height of the tour (the view space's y), metres.
pub const EYE_HEIGHT: f32 = 1.6;
/// Height of rooms A and B, metres.
pub const ROOM_HEIGHT: f32 = 3.2;
/// Height of the atrium, metres.
pub const ATRIUM_HEIGHT: f32 = 6.5;
/// Wall thickness, metres.
const WALL: f32 = 0.2;

/// Names of the objects that are animated (each moves between t = 0 and t = 5).
pub const ANIMATED_OBJECTS: [&str; 4] = [
    "RoomB_SlidingDoor",
    "Atrium_Sculpture",
    "RoomA_CeilingFan",
    "RoomB_Cart",
];

/// The name of the sun (a directional light whose node rotates).
pub const SUN: &str = "Sun";

/// Where the pieces of the generated scene are: positions the camera path looks at.
pub mod landmarks {
    use glam::Vec3;

    /// Centre of the sculpture in the atrium.
    pub const SCULPTURE: Vec3 = Vec3::new(0.0, 1.6, 0.0);
    /// Centre of the ceiling fan in room A.
    pub const FAN: Vec3 = Vec3::new(-8.0, 2.9, 0.5);
    /// Centre of the mirror in room A.
    pub const MIRROR: Vec3 = Vec3::new(-8.0, 1.5, -5.88);
    /// Centre of the glass vitrine in room B.
    pub const VITRINE: Vec3 = Vec3::new(9.5, 1.3, -3.0);
}

/// A mesh made of several pieces placed in the mesh's own space.
#[derive(Default)]
struct Compound {
    mesh: Mesh,
}

impl Compound {
    /// Appends `piece` transformed by `trs`.
    fn add(&mut self, piece: Mesh, trs: Trs) -> &mut Self {
        let m = trs.to_affine();
        let base = self.mesh.positions.len() as u32;
        self.mesh
            .positions
            .extend(piece.positions.iter().map(|&p| m.transform_point3(p)));
        self.mesh.normals.extend(
            piece
                .normals
                .iter()
                .map(|&n| m.transform_vector3(n).normalize_or(n)),
        );
        self.mesh.uvs.extend(piece.uvs.iter().copied());
        self.mesh.triangles.extend(
            piece
                .triangles
                .iter()
                .map(|t| [t[0] + base, t[1] + base, t[2] + base]),
        );
        self
    }

    /// Appends an axis-aligned box from `min` to `max`.
    fn cuboid(&mut self, min: Vec3, max: Vec3) -> &mut Self {
        self.add(shapes::cuboid(max - min), at((min + max) * 0.5))
    }

    fn into_mesh(self) -> Mesh {
        self.mesh
    }
}

/// Adds an object whose mesh gets UVs in metres ([`metric_uvs`]), so that the textured
/// materials' transforms give every surface the same texel density.
fn add_object(
    b: &mut SceneBuilder,
    name: impl Into<String>,
    mut mesh: Mesh,
    material: MaterialHandle,
    trs: Trs,
) -> NodeHandle {
    metric_uvs(&mut mesh);
    b.add_object(name, mesh, material, trs)
}

/// Box mapping in metres: each vertex's UV is its position projected along the dominant
/// axis of its normal (x-facing: (z, −y); y-facing: (x, z); z-facing: (x, −y)).
fn metric_uvs(mesh: &mut Mesh) {
    mesh.uvs = mesh
        .positions
        .iter()
        .zip(&mesh.normals)
        .map(|(p, n)| {
            let a = n.abs();
            if a.x >= a.y && a.x >= a.z {
                Vec2::new(p.z, -p.y)
            } else if a.y >= a.z {
                Vec2::new(p.x, p.z)
            } else {
                Vec2::new(p.x, -p.y)
            }
        })
        .collect();
    if mesh.uvs.len() != mesh.positions.len() {
        mesh.uvs.clear();
    }
}

/// A translation.
fn at(p: Vec3) -> Trs {
    Trs {
        translation: p,
        ..Trs::default()
    }
}

/// A closed prism of `sides` faces around +Y: radius `r`, from y = 0 to y = `h`.
fn cylinder(r: f32, h: f32, sides: u32) -> Mesh {
    let mut mesh = Mesh::default();
    let ring = |i: u32| {
        let a = TAU * i as f32 / sides as f32;
        Vec3::new(a.cos(), 0.0, -a.sin())
    };
    for i in 0..sides {
        let (d0, d1) = (ring(i), ring(i + 1));
        let n = (d0 + d1).normalize();
        let base = mesh.positions.len() as u32;
        for p in [d0 * r, d1 * r, d1 * r + Vec3::Y * h, d0 * r + Vec3::Y * h] {
            mesh.positions.push(p);
            mesh.normals.push(n);
            mesh.uvs.push(Vec2::ZERO);
        }
        mesh.triangles.push([base, base + 1, base + 2]);
        mesh.triangles.push([base, base + 2, base + 3]);
        // Caps.
        let base = mesh.positions.len() as u32;
        for (p, n) in [
            (Vec3::Y * h, Vec3::Y),
            (d0 * r + Vec3::Y * h, Vec3::Y),
            (d1 * r + Vec3::Y * h, Vec3::Y),
            (Vec3::ZERO, Vec3::NEG_Y),
            (d1 * r, Vec3::NEG_Y),
            (d0 * r, Vec3::NEG_Y),
        ] {
            mesh.positions.push(p);
            mesh.normals.push(n);
            mesh.uvs.push(Vec2::ZERO);
        }
        mesh.triangles.push([base, base + 1, base + 2]);
        mesh.triangles.push([base + 3, base + 4, base + 5]);
    }
    mesh
}

/// An opening in a wall: from `u0` to `u1` along the wall, from `v0` to `v1` in height.
#[derive(Clone, Copy)]
struct Opening {
    u0: f32,
    u1: f32,
    v0: f32,
    v1: f32,
}

const fn opening(u0: f32, u1: f32, v0: f32, v1: f32) -> Opening {
    Opening { u0, u1, v0, v1 }
}

/// A wall of height `h` from `a` to `b` (on the floor, axis-aligned) with `openings`
/// (sorted along the wall, u measured from `a`), as boxes.
fn wall(a: Vec2, b: Vec2, h: f32, openings: &[Opening]) -> Mesh {
    let along_x = (b.y - a.y).abs() < 1e-6;
    let len = (b - a).length();
    let dir = (b - a) / len;
    let mut c = Compound::default();
    let mut piece = |u0: f32, u1: f32, v0: f32, v1: f32| {
        if u1 - u0 < 1e-4 || v1 - v0 < 1e-4 {
            return;
        }
        let p0 = a + dir * u0;
        let p1 = a + dir * u1;
        let (min, max) = if along_x {
            (
                Vec3::new(p0.x.min(p1.x), v0, a.y - WALL * 0.5),
                Vec3::new(p0.x.max(p1.x), v1, a.y + WALL * 0.5),
            )
        } else {
            (
                Vec3::new(a.x - WALL * 0.5, v0, p0.y.min(p1.y)),
                Vec3::new(a.x + WALL * 0.5, v1, p0.y.max(p1.y)),
            )
        };
        c.cuboid(min, max);
    };
    let mut u = 0.0;
    for o in openings {
        piece(u, o.u0, 0.0, h);
        piece(o.u0, o.u1, 0.0, o.v0);
        piece(o.u0, o.u1, o.v1, h);
        u = o.u1;
    }
    piece(u, len, 0.0, h);
    c.into_mesh()
}

/// A quaternion that turns −Z (a light's direction) into `dir`.
fn aim(dir: Vec3) -> Quat {
    Quat::from_rotation_arc(Vec3::NEG_Z, dir.normalize())
}

/// The direction the sunlight travels at `t` seconds: azimuth from the south-east to the
/// south-west, elevation rising to 62° at noon (t = 7) and falling again.
pub fn sun_direction(t: f32) -> Vec3 {
    let u = (t / DURATION).clamp(0.0, 1.0);
    // Where the sun is, as seen from the building: south is +z.
    let azimuth = (-60.0 + 120.0 * u).to_radians(); // −60° (east of south) … +60° (west)
    let elevation = (30.0 + 32.0 * (PI * u).sin()).to_radians();
    let to_sun = Vec3::new(
        -azimuth.sin() * elevation.cos(),
        elevation.sin(),
        azimuth.cos() * elevation.cos(),
    );
    -to_sun
}

/// Builds the tour scene.
pub fn build() -> SceneBuilder {
    let mut b = SceneBuilder::new();

    // Materials: the textured ones get a texture made in code (textures.rs) whose mean is
    // their colour, repeating every `metres` of the meshes' metric UVs.
    let textured = |b: &mut SceneBuilder, desc: MaterialDesc, t: textures::Texture| {
        let tex = b.add_texture_rgba8(t.size, t.size, t.rgba8);
        b.add_material(desc.base_color_texture(tex).texture_transform(
            plenoptic_scene::UvTransform {
                offset: Vec2::ZERO,
                rotation: 0.0,
                scale: Vec2::splat(1.0 / t.metres),
            },
        ))
    };
    let white = Vec3::ONE;
    let plaster = textured(
        &mut b,
        MaterialDesc::diffuse(white).named("plaster"),
        textures::plaster(Vec3::new(0.82, 0.80, 0.76)),
    );
    let plaster_warm = textured(
        &mut b,
        MaterialDesc::diffuse(white).named("plaster_warm"),
        textures::plaster(Vec3::new(0.85, 0.72, 0.58)),
    );
    let plaster_blue = textured(
        &mut b,
        MaterialDesc::diffuse(white).named("plaster_blue"),
        textures::plaster(Vec3::new(0.55, 0.65, 0.78)),
    );
    let oak = textured(
        &mut b,
        MaterialDesc::diffuse(white).roughness(0.6).named("oak"),
        textures::oak_planks(Vec3::new(0.55, 0.36, 0.20)),
    );
    let walnut = b.add_material(MaterialDesc::diffuse(Vec3::new(0.30, 0.18, 0.10)).named("walnut"));
    let stone = textured(
        &mut b,
        MaterialDesc::diffuse(white).roughness(0.8).named("stone"),
        textures::stone_slabs(Vec3::new(0.70, 0.68, 0.64)),
    );
    let brick = textured(
        &mut b,
        MaterialDesc::diffuse(white).roughness(0.9).named("brick"),
        textures::brick(Vec3::new(0.62, 0.30, 0.20)),
    );
    let fabric = textured(
        &mut b,
        MaterialDesc::diffuse(white).named("fabric"),
        textures::fabric(Vec3::new(0.25, 0.32, 0.45)),
    );
    let terracotta =
        b.add_material(MaterialDesc::diffuse(Vec3::new(0.70, 0.35, 0.22)).named("terracotta"));
    let floor_tiles = textured(
        &mut b,
        MaterialDesc::diffuse(white).named("floor_tiles"),
        textures::floor_tiles(Vec3::new(0.45, 0.42, 0.40)),
    );
    let mirror = b.add_material(MaterialDesc::metal(Vec3::splat(0.95), 0.0).named("mirror"));
    let glass = b.add_material(
        MaterialDesc::glass(1.5)
            .transmission(1.0, 1.5)
            .named("glass"),
    );
    let glazing = b.add_material(
        MaterialDesc::diffuse(Vec3::splat(0.9))
            .base_color_alpha(Vec4::new(0.9, 0.95, 0.95, 0.12))
            .alpha_mode(AlphaMode::Blend)
            .double_sided(true)
            .named("glazing"),
    );
    let brass =
        b.add_material(MaterialDesc::metal(Vec3::new(0.90, 0.70, 0.35), 0.25).named("brass"));
    let red = b.add_material(MaterialDesc::diffuse(Vec3::new(0.75, 0.12, 0.10)).named("red_paint"));
    let steel = textured(
        &mut b,
        MaterialDesc::metal(white, 0.4).named("steel"),
        textures::brushed_steel(Vec3::splat(0.6)),
    );
    let lamp_shade = b.add_material(
        MaterialDesc::diffuse(Vec3::splat(0.9))
            .emissive(Vec3::new(1.0, 0.85, 0.6), 0.6)
            .named("lamp_shade"),
    );

    fn object(b: &mut SceneBuilder, name: &str, mesh: Mesh, mat: MaterialHandle) -> NodeHandle {
        add_object(b, name, mesh, mat, Trs::default())
    }

    // --- Floors and ceilings.
    let floor = |x0: f32, x1: f32| {
        let mut c = Compound::default();
        c.cuboid(Vec3::new(x0, -0.1, -6.0), Vec3::new(x1, 0.0, 6.0));
        c.into_mesh()
    };
    object(&mut b, "RoomA_Floor", floor(-12.0, -4.0), oak);
    object(&mut b, "Atrium_Floor", floor(-4.0, 4.0), floor_tiles);
    object(&mut b, "RoomB_Floor", floor(4.0, 12.0), stone);
    let slab = |x0: f32, x1: f32, y: f32| {
        let mut c = Compound::default();
        c.cuboid(Vec3::new(x0, y, -6.1), Vec3::new(x1, y + 0.2, 6.1));
        c.into_mesh()
    };
    object(
        &mut b,
        "RoomA_Ceiling",
        slab(-12.1, -4.0, ROOM_HEIGHT),
        plaster,
    );
    object(
        &mut b,
        "RoomB_Ceiling",
        slab(4.0, 12.1, ROOM_HEIGHT),
        plaster,
    );
    // Atrium roof with a 4 m × 4 m skylight opening, and its frame beams.
    {
        let y = ATRIUM_HEIGHT;
        let mut c = Compound::default();
        c.cuboid(Vec3::new(-4.1, y, -6.1), Vec3::new(4.1, y + 0.2, -2.0));
        c.cuboid(Vec3::new(-4.1, y, 2.0), Vec3::new(4.1, y + 0.2, 6.1));
        c.cuboid(Vec3::new(-4.1, y, -2.0), Vec3::new(-2.0, y + 0.2, 2.0));
        c.cuboid(Vec3::new(2.0, y, -2.0), Vec3::new(4.1, y + 0.2, 2.0));
        object(&mut b, "Atrium_Roof", c.into_mesh(), plaster);
        let mut f = Compound::default();
        for k in [-1.0, 0.0, 1.0] {
            f.cuboid(
                Vec3::new(k - 0.05, y, -2.0),
                Vec3::new(k + 0.05, y + 0.15, 2.0),
            );
        }
        f.cuboid(Vec3::new(-2.0, y, -0.05), Vec3::new(2.0, y + 0.15, 0.05));
        object(&mut b, "Atrium_Skylight_Frame", f.into_mesh(), steel);
    }

    // --- Walls. South is +z (sun side), north −z.
    let door_h = 2.4;
    // Room A.
    object(
        &mut b,
        "RoomA_Wall_South",
        wall(
            Vec2::new(-12.0, 6.0),
            Vec2::new(-4.0, 6.0),
            ROOM_HEIGHT,
            &[opening(1.5, 3.3, 0.9, 2.5), opening(4.7, 6.5, 0.9, 2.5)],
        ),
        plaster_warm,
    );
    object(
        &mut b,
        "RoomA_Wall_North",
        wall(
            Vec2::new(-12.0, -6.0),
            Vec2::new(-4.0, -6.0),
            ROOM_HEIGHT,
            &[],
        ),
        plaster_warm,
    );
    object(
        &mut b,
        "RoomA_Wall_West",
        wall(
            Vec2::new(-12.0, -6.0),
            Vec2::new(-12.0, 6.0),
            ROOM_HEIGHT,
            &[],
        ),
        plaster_warm,
    );
    // Atrium: tall window in the south wall, doorways to both rooms.
    object(
        &mut b,
        "Atrium_Wall_South",
        wall(
            Vec2::new(-4.0, 6.0),
            Vec2::new(4.0, 6.0),
            ATRIUM_HEIGHT,
            &[opening(2.5, 5.5, 1.0, 5.0)],
        ),
        plaster,
    );
    object(
        &mut b,
        "Atrium_Wall_North",
        wall(
            Vec2::new(-4.0, -6.0),
            Vec2::new(4.0, -6.0),
            ATRIUM_HEIGHT,
            &[],
        ),
        brick,
    );
    object(
        &mut b,
        "Atrium_Wall_West",
        wall(
            Vec2::new(-4.0, -6.0),
            Vec2::new(-4.0, 6.0),
            ATRIUM_HEIGHT,
            &[opening(4.6, 7.4, 0.0, door_h + 0.2)],
        ),
        plaster,
    );
    object(
        &mut b,
        "Atrium_Wall_East",
        wall(
            Vec2::new(4.0, -6.0),
            Vec2::new(4.0, 6.0),
            ATRIUM_HEIGHT,
            &[opening(5.0, 7.0, 0.0, door_h)],
        ),
        plaster,
    );
    // Room B.
    object(
        &mut b,
        "RoomB_Wall_South",
        wall(
            Vec2::new(4.0, 6.0),
            Vec2::new(12.0, 6.0),
            ROOM_HEIGHT,
            &[opening(1.5, 3.3, 0.9, 2.5), opening(4.7, 6.5, 0.9, 2.5)],
        ),
        plaster_blue,
    );
    object(
        &mut b,
        "RoomB_Wall_North",
        wall(
            Vec2::new(4.0, -6.0),
            Vec2::new(12.0, -6.0),
            ROOM_HEIGHT,
            &[],
        ),
        plaster_blue,
    );
    object(
        &mut b,
        "RoomB_Wall_East",
        wall(
            Vec2::new(12.0, -6.0),
            Vec2::new(12.0, 6.0),
            ROOM_HEIGHT,
            &[opening(4.5, 7.5, 1.0, 2.4)],
        ),
        plaster_blue,
    );
    // Window mullions and sills (the openings themselves are open to the sky).
    {
        let mut c = Compound::default();
        for x0 in [-10.5, -7.3, 5.5, 8.7] {
            c.cuboid(Vec3::new(x0, 0.85, 5.85), Vec3::new(x0 + 1.8, 0.9, 6.2));
            c.cuboid(
                Vec3::new(x0 + 0.87, 0.9, 5.95),
                Vec3::new(x0 + 0.93, 2.5, 6.05),
            );
        }
        object(&mut b, "Windows_Mullions", c.into_mesh(), walnut);
        let mut c = Compound::default();
        c.cuboid(Vec3::new(-1.5, 0.95, 5.85), Vec3::new(1.5, 1.0, 6.2));
        for x in [-0.55, 0.55] {
            c.cuboid(
                Vec3::new(x - 0.04, 1.0, 5.95),
                Vec3::new(x + 0.04, 5.0, 6.05),
            );
        }
        c.cuboid(Vec3::new(-1.5, 2.96, 5.95), Vec3::new(1.5, 3.04, 6.05));
        object(&mut b, "Atrium_Window_Mullions", c.into_mesh(), walnut);
        let mut c = Compound::default();
        c.cuboid(Vec3::new(11.85, 0.95, -1.5), Vec3::new(12.2, 1.0, 1.5));
        c.cuboid(Vec3::new(11.95, 1.0, -0.04), Vec3::new(12.05, 2.4, 0.04));
        object(&mut b, "RoomB_Window_East_Mullion", c.into_mesh(), walnut);
        // The east window is glazed as CAD exporters write glass: one pane, 1 cm thick, of
        // `alphaMode: BLEND` with alpha 0.12 (the see-through glazing of the daylight
        // issue). The other openings stay open to the sky.
        let mut c = Compound::default();
        c.cuboid(Vec3::new(11.995, 1.0, -1.5), Vec3::new(12.005, 2.4, 1.5));
        object(&mut b, "RoomB_Window_East_Pane", c.into_mesh(), glazing);
    }

    // --- Room A: mirror, table, benches, bookshelf, ceiling fan.
    add_object(
        &mut b,
        "RoomA_Mirror",
        shapes::cuboid(Vec3::new(3.0, 2.0, 0.03)),
        mirror,
        at(landmarks::MIRROR),
    );
    let frame = {
        let mut c = Compound::default();
        c.cuboid(Vec3::new(-1.6, -1.1, -0.04), Vec3::new(1.6, -1.0, 0.04));
        c.cuboid(Vec3::new(-1.6, 1.0, -0.04), Vec3::new(1.6, 1.1, 0.04));
        c.cuboid(Vec3::new(-1.6, -1.0, -0.04), Vec3::new(-1.5, 1.0, 0.04));
        c.cuboid(Vec3::new(1.5, -1.0, -0.04), Vec3::new(1.6, 1.0, 0.04));
        c.into_mesh()
    };
    add_object(
        &mut b,
        "RoomA_Mirror_Frame",
        frame,
        brass,
        at(landmarks::MIRROR),
    );
    add_object(
        &mut b,
        "RoomA_Table",
        table(2.2, 1.0, 0.75),
        oak,
        at(Vec3::new(-8.0, 0.0, 1.5)),
    );
    for (k, z) in [(0, 0.6), (1, 2.4)] {
        add_object(
            &mut b,
            format!("RoomA_Bench_{k}"),
            bench(2.0),
            walnut,
            at(Vec3::new(-8.0, 0.0, z)),
        );
    }
    add_object(
        &mut b,
        "RoomA_Bookshelf",
        shelf(3.0, 2.2, 0.35, 5),
        walnut,
        Trs {
            translation: Vec3::new(-11.7, 0.0, -1.0),
            rotation: Quat::from_rotation_y(FRAC_PI_2),
            ..Trs::default()
        },
    );
    let fan = {
        let mut c = Compound::default();
        c.add(cylinder(0.12, 0.15, 12), at(Vec3::new(0.0, -0.1, 0.0)));
        for k in 0..4 {
            let r = Quat::from_rotation_y(k as f32 * FRAC_PI_2 + 0.2);
            c.add(
                shapes::cuboid(Vec3::new(0.75, 0.02, 0.16)),
                Trs {
                    translation: r * Vec3::new(0.5, 0.0, 0.0),
                    rotation: r * Quat::from_rotation_x(0.2),
                    ..Trs::default()
                },
            );
        }
        c.into_mesh()
    };
    add_object(
        &mut b,
        "RoomA_CeilingFan_Rod",
        cylinder(0.02, ROOM_HEIGHT - landmarks::FAN.y, 6),
        steel,
        at(landmarks::FAN),
    );
    let fan = add_object(&mut b, "RoomA_CeilingFan", fan, brass, at(landmarks::FAN));
    // One and a half turns per second, as keys every 60°.
    b.animate_rotation(fan, turning(DURATION, 1.5 * TAU, Quat::IDENTITY));

    // --- Atrium: columns, stairs, benches, pedestal and revolving sculpture.
    for (k, (x, z)) in [(-2.6, -3.6), (2.6, -3.6), (-2.6, 3.6), (2.6, 3.6)]
        .into_iter()
        .enumerate()
    {
        let mut c = Compound::default();
        c.cuboid(Vec3::new(-0.35, 0.0, -0.35), Vec3::new(0.35, 0.3, 0.35));
        c.add(cylinder(0.25, ATRIUM_HEIGHT - 0.6, 16), at(Vec3::Y * 0.3));
        c.cuboid(
            Vec3::new(-0.35, ATRIUM_HEIGHT - 0.3, -0.35),
            Vec3::new(0.35, ATRIUM_HEIGHT, 0.35),
        );
        add_object(
            &mut b,
            format!("Atrium_Column_{k}"),
            c.into_mesh(),
            stone,
            at(Vec3::new(x, 0.0, z)),
        );
    }
    {
        // Stairs along the north wall, rising towards +x: 12 steps of 0.18 m.
        let mut c = Compound::default();
        for k in 0..12 {
            let x0 = -3.0 + k as f32 * 0.28;
            c.cuboid(
                Vec3::new(x0, 0.0, -5.9),
                Vec3::new(x0 + 0.28, 0.18 * (k + 1) as f32, -4.7),
            );
        }
        c.cuboid(Vec3::new(0.36, 2.06, -5.9), Vec3::new(3.9, 2.16, -4.7));
        object(&mut b, "Atrium_Stairs", c.into_mesh(), stone);
        let mut r = Compound::default();
        r.cuboid(Vec3::new(-3.0, 1.0, -4.72), Vec3::new(3.9, 3.2, -4.68));
        object(&mut b, "Atrium_Stairs_Balustrade", r.into_mesh(), glass);
    }
    for (k, x) in [(0, -2.6), (1, 2.6)] {
        add_object(
            &mut b,
            format!("Atrium_Bench_{k}"),
            bench(1.6),
            fabric,
            Trs {
                translation: Vec3::new(x, 0.0, 0.0),
                rotation: Quat::from_rotation_y(FRAC_PI_2),
                ..Trs::default()
            },
        );
    }
    add_object(
        &mut b,
        "Atrium_Pedestal",
        cylinder(0.6, 0.9, 24),
        stone,
        Trs::default(),
    );
    let sculpture = {
        // A twisted stack of slabs around a sphere.
        let mut c = Compound::default();
        for k in 0..6 {
            c.add(
                shapes::cuboid(Vec3::new(0.9, 0.12, 0.25)),
                Trs {
                    translation: Vec3::new(0.0, -0.6 + k as f32 * 0.24, 0.0),
                    rotation: Quat::from_rotation_y(k as f32 * 0.45),
                    ..Trs::default()
                },
            );
        }
        c.into_mesh()
    };
    let sculpture = add_object(
        &mut b,
        "Atrium_Sculpture",
        sculpture,
        red,
        at(landmarks::SCULPTURE),
    );
    b.animate_rotation(
        sculpture,
        turning(DURATION, TAU * DURATION / 10.0, Quat::IDENTITY),
    );
    let orb = b.add_sphere("Atrium_Sculpture_Orb", 0.22, 24, brass);
    b.add_node(
        NodeDesc::new("Atrium_Sculpture_Orb")
            .parent(sculpture)
            .mesh(orb)
            .translation(Vec3::new(0.0, 0.85, 0.0)),
    );

    // --- Room B: glass vitrine, shelves, table, lamp, cart, sliding door. The lamp is faint
    // (1.5 cd against the sun's 6 lx-like units) so that daylight dominates the tour.
    add_object(
        &mut b,
        "RoomB_Plinth",
        shapes::cuboid(Vec3::new(1.2, 0.8, 1.2)),
        stone,
        at(Vec3::new(landmarks::VITRINE.x, 0.4, landmarks::VITRINE.z)),
    );
    add_object(
        &mut b,
        "RoomB_GlassVitrine",
        shapes::cuboid(Vec3::new(1.0, 1.0, 1.0)),
        glass,
        at(landmarks::VITRINE),
    );
    add_object(
        &mut b,
        "RoomB_Vase",
        cylinder(0.15, 0.5, 16),
        terracotta,
        at(Vec3::new(landmarks::VITRINE.x, 0.8, landmarks::VITRINE.z)),
    );
    for (k, x) in [(0, 6.0), (1, 9.5)] {
        add_object(
            &mut b,
            format!("RoomB_Shelf_{k}"),
            shelf(2.4, 2.0, 0.4, 4),
            oak,
            at(Vec3::new(x, 0.0, -5.65)),
        );
    }
    add_object(
        &mut b,
        "RoomB_Table",
        table(1.6, 0.9, 0.75),
        walnut,
        at(Vec3::new(9.0, 0.0, 3.0)),
    );
    add_object(
        &mut b,
        "RoomB_Lamp",
        cylinder(0.25, 0.3, 16),
        lamp_shade,
        at(Vec3::new(9.0, 0.75, 3.0)),
    );
    b.add_node(
        NodeDesc::new("RoomB_Lamp_Light")
            .translation(Vec3::new(9.0, 1.3, 3.0))
            .light(LightDesc::point(Vec3::new(1.0, 0.85, 0.6), 1.5).named("RoomB_Lamp_Light")),
    );
    let cart = {
        let mut c = Compound::default();
        c.cuboid(Vec3::new(-0.5, 0.25, -0.3), Vec3::new(0.5, 0.75, 0.3));
        c.cuboid(Vec3::new(0.45, 0.75, -0.3), Vec3::new(0.5, 1.05, 0.3));
        for (x, z) in [(-0.4, -0.3), (0.4, -0.3), (-0.4, 0.3), (0.4, 0.3)] {
            c.add(
                cylinder(0.12, 0.06, 10),
                Trs {
                    translation: Vec3::new(x, 0.12, z - 0.03),
                    rotation: Quat::from_rotation_x(FRAC_PI_2),
                    ..Trs::default()
                },
            );
        }
        c.into_mesh()
    };
    let cart = add_object(&mut b, "RoomB_Cart", cart, red, Trs::default());
    // From the north-east corner across the room to the south-west and back, with smooth
    // starts and stops (cubic spline; tangents in metres per second).
    let (p0, p1, p2) = (
        Vec3::new(10.5, 0.0, -1.0),
        Vec3::new(7.0, 0.0, 1.5),
        Vec3::new(5.5, 0.0, 4.5),
    );
    let v1 = Vec3::new(-0.9, 0.0, 0.9);
    b.animate_translation(
        cart,
        Track::cubic_spline([
            (0.0, Vec3::ZERO, p0, Vec3::ZERO),
            (1.0, Vec3::ZERO, p0, Vec3::ZERO),
            (4.5, v1, p1, v1),
            (7.0, Vec3::ZERO, p2, Vec3::ZERO),
            (9.0, -v1, p1, -v1),
            (DURATION, Vec3::ZERO, p0, Vec3::ZERO),
        ]),
    );
    b.animate_rotation(
        cart,
        Track::linear([
            (0.0, Quat::from_rotation_y(-0.6)),
            (7.0, Quat::from_rotation_y(-1.1)),
            (DURATION, Quat::from_rotation_y(-0.6)),
        ]),
    );
    let door = add_object(
        &mut b,
        "RoomB_SlidingDoor",
        {
            let mut c = Compound::default();
            c.cuboid(
                Vec3::new(-0.04, 0.0, -1.05),
                Vec3::new(0.04, door_h - 0.02, 1.05),
            );
            c.cuboid(Vec3::new(-0.07, 1.0, 0.8), Vec3::new(-0.04, 1.1, 0.95));
            c.into_mesh()
        },
        walnut,
        Trs::default(),
    );
    // On the atrium side of the wall; closed over the doorway, slides south to open.
    let closed = Vec3::new(3.85, 0.0, 0.0);
    let open = Vec3::new(3.85, 0.0, 2.1);
    b.animate_translation(
        door,
        Track::linear([
            (0.0, closed),
            (0.5, closed),
            (2.5, open),
            (10.0, open),
            (12.0, closed),
            (DURATION, closed),
        ]),
    );
    let rail = {
        let mut c = Compound::default();
        c.cuboid(
            Vec3::new(3.78, door_h, -1.2),
            Vec3::new(3.9, door_h + 0.1, 3.3),
        );
        c.into_mesh()
    };
    object(&mut b, "RoomB_SlidingDoor_Rail", rail, steel);

    // --- The sun, and its path across the sky.
    let sun = b.add_node(
        NodeDesc::new(SUN)
            .translation(Vec3::new(0.0, 20.0, 0.0))
            .rotation(aim(sun_direction(0.0)))
            .light(LightDesc::directional(Vec3::new(1.0, 0.95, 0.85), 6.0).named(SUN)),
    );
    let keys: Vec<(f32, Quat)> = (0..=7)
        .map(|k| {
            let t = DURATION * k as f32 / 7.0;
            (t, aim(sun_direction(t)))
        })
        .collect();
    b.animate_rotation(sun, Track::linear(keys));
    b
}

/// Keys every 60° for a rotation about +Y of `angle` radians over `duration` seconds.
fn turning(duration: f32, angle: f32, start: Quat) -> Track<Quat> {
    let steps = (angle / (PI / 3.0)).ceil().max(1.0) as u32;
    Track::linear((0..=steps).map(|k| {
        let u = k as f32 / steps as f32;
        (u * duration, Quat::from_rotation_y(u * angle) * start)
    }))
}

/// A table `w` × `d`, `h` high, its feet on y = 0, centred on x and z.
fn table(w: f32, d: f32, h: f32) -> Mesh {
    let mut c = Compound::default();
    c.cuboid(
        Vec3::new(-w * 0.5, h - 0.05, -d * 0.5),
        Vec3::new(w * 0.5, h, d * 0.5),
    );
    for (sx, sz) in [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)] {
        let (x, z) = (sx * (w * 0.5 - 0.08), sz * (d * 0.5 - 0.08));
        c.cuboid(
            Vec3::new(x - 0.04, 0.0, z - 0.04),
            Vec3::new(x + 0.04, h - 0.05, z + 0.04),
        );
    }
    c.into_mesh()
}

/// A bench `w` long (along x), 0.45 m high.
fn bench(w: f32) -> Mesh {
    let mut c = Compound::default();
    c.cuboid(
        Vec3::new(-w * 0.5, 0.4, -0.18),
        Vec3::new(w * 0.5, 0.45, 0.18),
    );
    for x in [-w * 0.5 + 0.1, w * 0.5 - 0.1] {
        c.cuboid(
            Vec3::new(x - 0.04, 0.0, -0.15),
            Vec3::new(x + 0.04, 0.4, 0.15),
        );
    }
    c.into_mesh()
}

/// A shelf `w` wide (along x), `h` high, `d` deep (its back at z = −d/2), with `boards`
/// boards.
fn shelf(w: f32, h: f32, d: f32, boards: u32) -> Mesh {
    let mut c = Compound::default();
    let (hx, hz) = (w * 0.5, d * 0.5);
    c.cuboid(Vec3::new(-hx, 0.0, -hz), Vec3::new(-hx + 0.03, h, hz));
    c.cuboid(Vec3::new(hx - 0.03, 0.0, -hz), Vec3::new(hx, h, hz));
    c.cuboid(Vec3::new(-hx, 0.0, -hz), Vec3::new(hx, h, -hz + 0.02));
    for k in 0..boards {
        let y = 0.05 + (h - 0.08) * k as f32 / (boards - 1).max(1) as f32;
        c.cuboid(Vec3::new(-hx, y, -hz), Vec3::new(hx, y + 0.03, hz));
    }
    c.into_mesh()
}
