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

/// Builds the tour scene: the materials, then the shell (floors, ceilings, walls, windows),
/// then each part's furniture, the sun, and last the animations.
pub fn build() -> SceneBuilder {
    let mut b = SceneBuilder::new();
    let m = Materials::add(&mut b);
    let mut nodes = Nodes::default();
    nodes.add(&mut b, shell(&m));
    nodes.add(&mut b, room_a(&m));
    nodes.add(&mut b, atrium(&m));
    let sculpture = nodes.get("Atrium_Sculpture");
    let orb = b.add_sphere("Atrium_Sculpture_Orb", 0.22, 24, m.brass);
    b.add_node(
        NodeDesc::new("Atrium_Sculpture_Orb")
            .parent(sculpture)
            .mesh(orb)
            .translation(Vec3::new(0.0, 0.85, 0.0)),
    );
    nodes.add(&mut b, room_b(&m));
    // The lamp is faint (1.5 cd against the sun's 6 lx-like units) so that daylight
    // dominates the tour.
    b.add_node(
        NodeDesc::new("RoomB_Lamp_Light")
            .translation(Vec3::new(9.0, 1.3, 3.0))
            .light(LightDesc::point(Vec3::new(1.0, 0.85, 0.6), 1.5).named("RoomB_Lamp_Light")),
    );
    nodes.add(&mut b, room_b_moving(&m));
    let sun = b.add_node(
        NodeDesc::new(SUN)
            .translation(Vec3::new(0.0, 20.0, 0.0))
            .rotation(aim(sun_direction(0.0)))
            .light(LightDesc::directional(Vec3::new(1.0, 0.95, 0.85), 6.0).named(SUN)),
    );
    nodes.0.push((SUN.to_owned(), sun));
    for (name, motion) in motions() {
        let node = nodes.get(name);
        match motion {
            Motion::Translation(track) => b.animate_translation(node, track),
            Motion::Rotation(track) => b.animate_rotation(node, track),
        };
    }
    b
}

/// The tour's materials. The textured ones get a texture made in code ([`textures`]) whose
/// mean is their colour, repeating every `metres` of the meshes' metric UVs.
struct Materials {
    plaster: MaterialHandle,
    plaster_warm: MaterialHandle,
    plaster_blue: MaterialHandle,
    oak: MaterialHandle,
    walnut: MaterialHandle,
    stone: MaterialHandle,
    brick: MaterialHandle,
    fabric: MaterialHandle,
    terracotta: MaterialHandle,
    floor_tiles: MaterialHandle,
    mirror: MaterialHandle,
    glass: MaterialHandle,
    glazing: MaterialHandle,
    brass: MaterialHandle,
    red: MaterialHandle,
    steel: MaterialHandle,
    lamp_shade: MaterialHandle,
}

impl Materials {
    /// Adds the materials (and their textures) in the order of the fields.
    fn add(b: &mut SceneBuilder) -> Self {
        let plain = |b: &mut SceneBuilder, desc: MaterialDesc| b.add_material(desc);
        let diffuse = |name: &str| MaterialDesc::diffuse(Vec3::ONE).named(name);
        let rgb = Vec3::new;
        Materials {
            plaster: textured(
                b,
                diffuse("plaster"),
                textures::plaster(rgb(0.82, 0.80, 0.76)),
            ),
            plaster_warm: textured(
                b,
                diffuse("plaster_warm"),
                textures::plaster(rgb(0.85, 0.72, 0.58)),
            ),
            plaster_blue: textured(
                b,
                diffuse("plaster_blue"),
                textures::plaster(rgb(0.55, 0.65, 0.78)),
            ),
            oak: textured(
                b,
                diffuse("oak").roughness(0.6),
                textures::oak_planks(rgb(0.55, 0.36, 0.20)),
            ),
            walnut: plain(
                b,
                MaterialDesc::diffuse(rgb(0.30, 0.18, 0.10)).named("walnut"),
            ),
            stone: textured(
                b,
                diffuse("stone").roughness(0.8),
                textures::stone_slabs(rgb(0.70, 0.68, 0.64)),
            ),
            brick: textured(
                b,
                diffuse("brick").roughness(0.9),
                textures::brick(rgb(0.62, 0.30, 0.20)),
            ),
            fabric: textured(
                b,
                diffuse("fabric"),
                textures::fabric(rgb(0.25, 0.32, 0.45)),
            ),
            terracotta: plain(
                b,
                MaterialDesc::diffuse(rgb(0.70, 0.35, 0.22)).named("terracotta"),
            ),
            floor_tiles: textured(
                b,
                diffuse("floor_tiles"),
                textures::floor_tiles(rgb(0.45, 0.42, 0.40)),
            ),
            mirror: plain(
                b,
                MaterialDesc::metal(Vec3::splat(0.95), 0.0).named("mirror"),
            ),
            glass: plain(
                b,
                MaterialDesc::glass(1.5)
                    .transmission(1.0, 1.5)
                    .named("glass"),
            ),
            glazing: plain(
                b,
                MaterialDesc::diffuse(Vec3::splat(0.9))
                    .base_color_alpha(Vec4::new(0.9, 0.95, 0.95, 0.12))
                    .alpha_mode(AlphaMode::Blend)
                    .double_sided(true)
                    .named("glazing"),
            ),
            brass: plain(
                b,
                MaterialDesc::metal(rgb(0.90, 0.70, 0.35), 0.25).named("brass"),
            ),
            red: plain(
                b,
                MaterialDesc::diffuse(rgb(0.75, 0.12, 0.10)).named("red_paint"),
            ),
            steel: textured(
                b,
                MaterialDesc::metal(Vec3::ONE, 0.4).named("steel"),
                textures::brushed_steel(Vec3::splat(0.6)),
            ),
            lamp_shade: plain(
                b,
                MaterialDesc::diffuse(Vec3::splat(0.9))
                    .emissive(Vec3::new(1.0, 0.85, 0.6), 0.6)
                    .named("lamp_shade"),
            ),
        }
    }
}

/// Adds `texture` and a material `desc` that shows it, repeating every `texture.metres`.
fn textured(
    b: &mut SceneBuilder,
    desc: MaterialDesc,
    texture: textures::Texture,
) -> MaterialHandle {
    let tex = b.add_texture_rgba8(texture.size, texture.size, texture.rgba8);
    b.add_material(
        desc.base_color_texture(tex)
            .texture_transform(plenoptic_scene::UvTransform {
                offset: Vec2::ZERO,
                rotation: 0.0,
                scale: Vec2::splat(1.0 / texture.metres),
            }),
    )
}

/// One row of a part's table: an object's name, mesh, material and placement.
struct Piece {
    name: String,
    mesh: Mesh,
    material: MaterialHandle,
    place: Trs,
}

/// A piece at the origin (its mesh placed in scene coordinates).
fn piece(name: impl Into<String>, mesh: Mesh, material: MaterialHandle) -> Piece {
    placed(name, mesh, material, Trs::default())
}

/// A piece placed by `place`.
fn placed(name: impl Into<String>, mesh: Mesh, material: MaterialHandle, place: Trs) -> Piece {
    Piece {
        name: name.into(),
        mesh,
        material,
        place,
    }
}

/// A translation and a turn of `angle` radians about +Y.
fn turned(p: Vec3, angle: f32) -> Trs {
    Trs {
        translation: p,
        rotation: Quat::from_rotation_y(angle),
        ..Trs::default()
    }
}

/// The nodes of the pieces added so far, by name.
#[derive(Default)]
struct Nodes(Vec<(String, NodeHandle)>);

impl Nodes {
    /// Adds `pieces` in order as objects ([`add_object`]).
    fn add(&mut self, b: &mut SceneBuilder, pieces: Vec<Piece>) {
        for p in pieces {
            let node = add_object(b, p.name.clone(), p.mesh, p.material, p.place);
            self.0.push((p.name, node));
        }
    }

    /// The node named `name`.
    fn get(&self, name: &str) -> NodeHandle {
        self.0
            .iter()
            .find(|(n, _)| *n == name)
            .unwrap_or_else(|| panic!("no node {name}"))
            .1
    }
}

/// Height of the doorways between the parts, metres.
const DOOR_H: f32 = 2.4;

/// A part of the building: its name, where it stands along x (it spans z ∈ [−6, 6]) and
/// its height.
struct Part {
    name: &'static str,
    x0: f32,
    x1: f32,
    height: f32,
}

const ROOM_A: Part = Part {
    name: "RoomA",
    x0: -12.0,
    x1: -4.0,
    height: ROOM_HEIGHT,
};
const ATRIUM: Part = Part {
    name: "Atrium",
    x0: -4.0,
    x1: 4.0,
    height: ATRIUM_HEIGHT,
};
const ROOM_B: Part = Part {
    name: "RoomB",
    x0: 4.0,
    x1: 12.0,
    height: ROOM_HEIGHT,
};

/// A wall of a part. South is +z (the sun's side), north −z, west −x, east +x.
#[derive(Clone, Copy, Debug)]
enum Side {
    South,
    North,
    West,
    East,
}

impl Part {
    /// The ends of the wall on `side`, on the floor (x, z); openings are measured from the
    /// first.
    fn wall_ends(&self, side: Side) -> (Vec2, Vec2) {
        let (x0, x1) = (self.x0, self.x1);
        match side {
            Side::South => (Vec2::new(x0, 6.0), Vec2::new(x1, 6.0)),
            Side::North => (Vec2::new(x0, -6.0), Vec2::new(x1, -6.0)),
            Side::West => (Vec2::new(x0, -6.0), Vec2::new(x0, 6.0)),
            Side::East => (Vec2::new(x1, -6.0), Vec2::new(x1, 6.0)),
        }
    }
}

/// The two windows in the south walls of rooms A and B.
const SOUTH_WINDOWS: [Opening; 2] = [opening(1.5, 3.3, 0.9, 2.5), opening(4.7, 6.5, 0.9, 2.5)];
/// The atrium's tall south window.
const ATRIUM_WINDOW: Opening = opening(2.5, 5.5, 1.0, 5.0);
/// The doorway between room A and the atrium.
const DOORWAY_A: Opening = opening(4.6, 7.4, 0.0, DOOR_H + 0.2);
/// The doorway between the atrium and room B, which the sliding door closes.
const DOORWAY_B: Opening = opening(5.0, 7.0, 0.0, DOOR_H);
/// Room B's east window.
const EAST_WINDOW: Opening = opening(4.5, 7.5, 1.0, 2.4);

/// The walls of the parts, with their openings.
fn walls(m: &Materials) -> Vec<Piece> {
    use Side::*;
    let walls: [(&Part, Side, &[Opening], MaterialHandle); 10] = [
        (&ROOM_A, South, &SOUTH_WINDOWS, m.plaster_warm),
        (&ROOM_A, North, &[], m.plaster_warm),
        (&ROOM_A, West, &[], m.plaster_warm),
        (&ATRIUM, South, &[ATRIUM_WINDOW], m.plaster),
        (&ATRIUM, North, &[], m.brick),
        (&ATRIUM, West, &[DOORWAY_A], m.plaster),
        (&ATRIUM, East, &[DOORWAY_B], m.plaster),
        (&ROOM_B, South, &SOUTH_WINDOWS, m.plaster_blue),
        (&ROOM_B, North, &[], m.plaster_blue),
        (&ROOM_B, East, &[EAST_WINDOW], m.plaster_blue),
    ];
    walls
        .into_iter()
        .map(|(part, side, openings, material)| {
            let (a, b) = part.wall_ends(side);
            let name = format!("{}_Wall_{side:?}", part.name);
            piece(name, wall(a, b, part.height, openings), material)
        })
        .collect()
}

/// The building's shell: floors, ceilings, the atrium's roof and skylight, the walls
/// ([`walls`]), and the windows' mullions, sills and pane.
fn shell(m: &Materials) -> Vec<Piece> {
    let floors = [
        (&ROOM_A, m.oak),
        (&ATRIUM, m.floor_tiles),
        (&ROOM_B, m.stone),
    ];
    let mut pieces: Vec<Piece> = floors
        .into_iter()
        .map(|(part, material)| {
            let name = format!("{}_Floor", part.name);
            piece(name, floor(part.x0, part.x1), material)
        })
        .collect();
    let y = ATRIUM_HEIGHT;
    pieces.extend([
        piece("RoomA_Ceiling", slab(-12.1, -4.0, ROOM_HEIGHT), m.plaster),
        piece("RoomB_Ceiling", slab(4.0, 12.1, ROOM_HEIGHT), m.plaster),
        // The atrium's roof with a 4 m × 4 m skylight opening, and its frame beams.
        piece(
            "Atrium_Roof",
            boxes(&[
                (Vec3::new(-4.1, y, -6.1), Vec3::new(4.1, y + 0.2, -2.0)),
                (Vec3::new(-4.1, y, 2.0), Vec3::new(4.1, y + 0.2, 6.1)),
                (Vec3::new(-4.1, y, -2.0), Vec3::new(-2.0, y + 0.2, 2.0)),
                (Vec3::new(2.0, y, -2.0), Vec3::new(4.1, y + 0.2, 2.0)),
            ]),
            m.plaster,
        ),
        piece("Atrium_Skylight_Frame", skylight_frame(), m.steel),
    ]);
    pieces.extend(walls(m));
    // The window openings themselves are open to the sky, except the east window of room B,
    // glazed as CAD exporters write glass: one pane, 1 cm thick, of `alphaMode: BLEND` with
    // alpha 0.12.
    pieces.extend([
        piece("Windows_Mullions", south_mullions(), m.walnut),
        piece("Atrium_Window_Mullions", atrium_mullions(), m.walnut),
        piece(
            "RoomB_Window_East_Mullion",
            boxes(&[
                (Vec3::new(11.85, 0.95, -1.5), Vec3::new(12.2, 1.0, 1.5)),
                (Vec3::new(11.95, 1.0, -0.04), Vec3::new(12.05, 2.4, 0.04)),
            ]),
            m.walnut,
        ),
        piece(
            "RoomB_Window_East_Pane",
            boxes(&[(Vec3::new(11.995, 1.0, -1.5), Vec3::new(12.005, 2.4, 1.5))]),
            m.glazing,
        ),
    ]);
    pieces
}

/// Room A: the mirror, the table and benches, the bookshelf and the ceiling fan.
fn room_a(m: &Materials) -> Vec<Piece> {
    vec![
        placed(
            "RoomA_Mirror",
            shapes::cuboid(Vec3::new(3.0, 2.0, 0.03)),
            m.mirror,
            at(landmarks::MIRROR),
        ),
        placed(
            "RoomA_Mirror_Frame",
            boxes(&[
                (Vec3::new(-1.6, -1.1, -0.04), Vec3::new(1.6, -1.0, 0.04)),
                (Vec3::new(-1.6, 1.0, -0.04), Vec3::new(1.6, 1.1, 0.04)),
                (Vec3::new(-1.6, -1.0, -0.04), Vec3::new(-1.5, 1.0, 0.04)),
                (Vec3::new(1.5, -1.0, -0.04), Vec3::new(1.6, 1.0, 0.04)),
            ]),
            m.brass,
            at(landmarks::MIRROR),
        ),
        placed(
            "RoomA_Table",
            table(2.2, 1.0, 0.75),
            m.oak,
            at(Vec3::new(-8.0, 0.0, 1.5)),
        ),
        placed(
            "RoomA_Bench_0",
            bench(2.0),
            m.walnut,
            at(Vec3::new(-8.0, 0.0, 0.6)),
        ),
        placed(
            "RoomA_Bench_1",
            bench(2.0),
            m.walnut,
            at(Vec3::new(-8.0, 0.0, 2.4)),
        ),
        placed(
            "RoomA_Bookshelf",
            shelf(3.0, 2.2, 0.35, 5),
            m.walnut,
            turned(Vec3::new(-11.7, 0.0, -1.0), FRAC_PI_2),
        ),
        placed(
            "RoomA_CeilingFan_Rod",
            cylinder(0.02, ROOM_HEIGHT - landmarks::FAN.y, 6),
            m.steel,
            at(landmarks::FAN),
        ),
        placed("RoomA_CeilingFan", fan(), m.brass, at(landmarks::FAN)),
    ]
}

/// The atrium: four columns, the stairs and their glass balustrade, two benches, and the
/// sculpture on its pedestal.
fn atrium(m: &Materials) -> Vec<Piece> {
    let columns = [
        "Atrium_Column_0",
        "Atrium_Column_1",
        "Atrium_Column_2",
        "Atrium_Column_3",
    ];
    let at_columns = [(-2.6, -3.6), (2.6, -3.6), (-2.6, 3.6), (2.6, 3.6)];
    let mut pieces: Vec<Piece> = columns
        .into_iter()
        .zip(at_columns)
        .map(|(name, (x, z))| placed(name, column(), m.stone, at(Vec3::new(x, 0.0, z))))
        .collect();
    pieces.extend([
        piece("Atrium_Stairs", stairs(), m.stone),
        piece(
            "Atrium_Stairs_Balustrade",
            boxes(&[(Vec3::new(-3.0, 1.0, -4.72), Vec3::new(3.9, 3.2, -4.68))]),
            m.glass,
        ),
        placed(
            "Atrium_Bench_0",
            bench(1.6),
            m.fabric,
            turned(Vec3::new(-2.6, 0.0, 0.0), FRAC_PI_2),
        ),
        placed(
            "Atrium_Bench_1",
            bench(1.6),
            m.fabric,
            turned(Vec3::new(2.6, 0.0, 0.0), FRAC_PI_2),
        ),
        piece("Atrium_Pedestal", cylinder(0.6, 0.9, 24), m.stone),
        placed(
            "Atrium_Sculpture",
            sculpture(),
            m.red,
            at(landmarks::SCULPTURE),
        ),
    ]);
    pieces
}

/// Room B's still furniture: the glass vitrine on its plinth with a vase, the shelves, the
/// table and the lamp.
fn room_b(m: &Materials) -> Vec<Piece> {
    let vitrine = landmarks::VITRINE;
    vec![
        placed(
            "RoomB_Plinth",
            shapes::cuboid(Vec3::new(1.2, 0.8, 1.2)),
            m.stone,
            at(Vec3::new(vitrine.x, 0.4, vitrine.z)),
        ),
        placed(
            "RoomB_GlassVitrine",
            shapes::cuboid(Vec3::new(1.0, 1.0, 1.0)),
            m.glass,
            at(vitrine),
        ),
        placed(
            "RoomB_Vase",
            cylinder(0.15, 0.5, 16),
            m.terracotta,
            at(Vec3::new(vitrine.x, 0.8, vitrine.z)),
        ),
        placed(
            "RoomB_Shelf_0",
            shelf(2.4, 2.0, 0.4, 4),
            m.oak,
            at(Vec3::new(6.0, 0.0, -5.65)),
        ),
        placed(
            "RoomB_Shelf_1",
            shelf(2.4, 2.0, 0.4, 4),
            m.oak,
            at(Vec3::new(9.5, 0.0, -5.65)),
        ),
        placed(
            "RoomB_Table",
            table(1.6, 0.9, 0.75),
            m.walnut,
            at(Vec3::new(9.0, 0.0, 3.0)),
        ),
        placed(
            "RoomB_Lamp",
            cylinder(0.25, 0.3, 16),
            m.lamp_shade,
            at(Vec3::new(9.0, 0.75, 3.0)),
        ),
    ]
}

/// Room B's moving things (their motions are in [`motions`]): the cart, and the sliding
/// door on the atrium side of the wall with its rail.
fn room_b_moving(m: &Materials) -> Vec<Piece> {
    vec![
        piece("RoomB_Cart", cart(), m.red),
        piece(
            "RoomB_SlidingDoor",
            boxes(&[
                (
                    Vec3::new(-0.04, 0.0, -1.05),
                    Vec3::new(0.04, DOOR_H - 0.02, 1.05),
                ),
                (Vec3::new(-0.07, 1.0, 0.8), Vec3::new(-0.04, 1.1, 0.95)),
            ]),
            m.walnut,
        ),
        piece(
            "RoomB_SlidingDoor_Rail",
            boxes(&[(
                Vec3::new(3.78, DOOR_H, -1.2),
                Vec3::new(3.9, DOOR_H + 0.1, 3.3),
            )]),
            m.steel,
        ),
    ]
}

/// How an animated node moves.
enum Motion {
    Translation(Track<Vec3>),
    Rotation(Track<Quat>),
}

/// The animations, in the order they are written: which node, and how it moves.
fn motions() -> [(&'static str, Motion); 6] {
    // The cart goes from the north-east corner across the room to the south-west and back,
    // with smooth starts and stops (cubic spline; tangents in metres per second).
    let (p0, p1, p2) = (
        Vec3::new(10.5, 0.0, -1.0),
        Vec3::new(7.0, 0.0, 1.5),
        Vec3::new(5.5, 0.0, 4.5),
    );
    let v1 = Vec3::new(-0.9, 0.0, 0.9);
    // The door is closed over the doorway and slides south to open.
    let closed = Vec3::new(3.85, 0.0, 0.0);
    let open = Vec3::new(3.85, 0.0, 2.1);
    // The sun's path across the sky.
    let sun: Vec<(f32, Quat)> = (0..=7)
        .map(|k| {
            let t = DURATION * k as f32 / 7.0;
            (t, aim(sun_direction(t)))
        })
        .collect();
    [
        // One and a half turns per second, as keys every 60°.
        (
            "RoomA_CeilingFan",
            Motion::Rotation(turning(DURATION, 1.5 * TAU, Quat::IDENTITY)),
        ),
        (
            "Atrium_Sculpture",
            Motion::Rotation(turning(DURATION, TAU * DURATION / 10.0, Quat::IDENTITY)),
        ),
        (
            "RoomB_Cart",
            Motion::Translation(Track::cubic_spline([
                (0.0, Vec3::ZERO, p0, Vec3::ZERO),
                (1.0, Vec3::ZERO, p0, Vec3::ZERO),
                (4.5, v1, p1, v1),
                (7.0, Vec3::ZERO, p2, Vec3::ZERO),
                (9.0, -v1, p1, -v1),
                (DURATION, Vec3::ZERO, p0, Vec3::ZERO),
            ])),
        ),
        (
            "RoomB_Cart",
            Motion::Rotation(Track::linear([
                (0.0, Quat::from_rotation_y(-0.6)),
                (7.0, Quat::from_rotation_y(-1.1)),
                (DURATION, Quat::from_rotation_y(-0.6)),
            ])),
        ),
        (
            "RoomB_SlidingDoor",
            Motion::Translation(Track::linear([
                (0.0, closed),
                (0.5, closed),
                (2.5, open),
                (10.0, open),
                (12.0, closed),
                (DURATION, closed),
            ])),
        ),
        (SUN, Motion::Rotation(Track::linear(sun))),
    ]
}

/// A mesh of axis-aligned boxes, each from its `min` to its `max`.
fn boxes(corners: &[(Vec3, Vec3)]) -> Mesh {
    let mut c = Compound::default();
    for &(min, max) in corners {
        c.cuboid(min, max);
    }
    c.into_mesh()
}

/// A floor slab under the walkable floor (y = 0), from x0 to x1 across the building.
fn floor(x0: f32, x1: f32) -> Mesh {
    boxes(&[(Vec3::new(x0, -0.1, -6.0), Vec3::new(x1, 0.0, 6.0))])
}

/// A ceiling slab 0.2 m thick from `y` up, from x0 to x1 across the building.
fn slab(x0: f32, x1: f32, y: f32) -> Mesh {
    boxes(&[(Vec3::new(x0, y, -6.1), Vec3::new(x1, y + 0.2, 6.1))])
}

/// The steel beams across the atrium's skylight.
fn skylight_frame() -> Mesh {
    let y = ATRIUM_HEIGHT;
    let mut f = Compound::default();
    for k in [-1.0, 0.0, 1.0] {
        f.cuboid(
            Vec3::new(k - 0.05, y, -2.0),
            Vec3::new(k + 0.05, y + 0.15, 2.0),
        );
    }
    f.cuboid(Vec3::new(-2.0, y, -0.05), Vec3::new(2.0, y + 0.15, 0.05));
    f.into_mesh()
}

/// The sills and mullions of the four south windows of rooms A and B.
fn south_mullions() -> Mesh {
    let mut c = Compound::default();
    for x0 in [-10.5, -7.3, 5.5, 8.7] {
        c.cuboid(Vec3::new(x0, 0.85, 5.85), Vec3::new(x0 + 1.8, 0.9, 6.2));
        c.cuboid(
            Vec3::new(x0 + 0.87, 0.9, 5.95),
            Vec3::new(x0 + 0.93, 2.5, 6.05),
        );
    }
    c.into_mesh()
}

/// The sill, mullions and transom of the atrium's tall south window.
fn atrium_mullions() -> Mesh {
    let mut c = Compound::default();
    c.cuboid(Vec3::new(-1.5, 0.95, 5.85), Vec3::new(1.5, 1.0, 6.2));
    for x in [-0.55, 0.55] {
        c.cuboid(
            Vec3::new(x - 0.04, 1.0, 5.95),
            Vec3::new(x + 0.04, 5.0, 6.05),
        );
    }
    c.cuboid(Vec3::new(-1.5, 2.96, 5.95), Vec3::new(1.5, 3.04, 6.05));
    c.into_mesh()
}

/// The ceiling fan: a hub and four tilted blades, around its centre.
fn fan() -> Mesh {
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
}

/// A column from the floor to the atrium's roof: base, shaft and capital.
fn column() -> Mesh {
    let mut c = Compound::default();
    c.cuboid(Vec3::new(-0.35, 0.0, -0.35), Vec3::new(0.35, 0.3, 0.35));
    c.add(cylinder(0.25, ATRIUM_HEIGHT - 0.6, 16), at(Vec3::Y * 0.3));
    c.cuboid(
        Vec3::new(-0.35, ATRIUM_HEIGHT - 0.3, -0.35),
        Vec3::new(0.35, ATRIUM_HEIGHT, 0.35),
    );
    c.into_mesh()
}

/// Stairs along the atrium's north wall, rising towards +x: 12 steps of 0.18 m, and a landing.
fn stairs() -> Mesh {
    let mut c = Compound::default();
    for k in 0..12 {
        let x0 = -3.0 + k as f32 * 0.28;
        c.cuboid(
            Vec3::new(x0, 0.0, -5.9),
            Vec3::new(x0 + 0.28, 0.18 * (k + 1) as f32, -4.7),
        );
    }
    c.cuboid(Vec3::new(0.36, 2.06, -5.9), Vec3::new(3.9, 2.16, -4.7));
    c.into_mesh()
}

/// The sculpture: a twisted stack of slabs (the orb on top is a child node).
fn sculpture() -> Mesh {
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
}

/// The cart: a body, a handle and four wheels.
fn cart() -> Mesh {
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
