//! The scene model: what the importer produces and the tracer consumes.
//!
//! Geometry is kept in object space, one [`Mesh`] per glTF primitive; an [`Object`] places one
//! mesh with one material under one node, and its world transform at time t comes from the
//! node hierarchy and its animation tracks ([`Scene::object_transform`]). Object ids are the
//! indices of [`Scene::objects`]: stable for a given file, in glTF node order then primitive
//! order, and carried by the pack's object table.
//!
//! Units: metres and seconds. Light quantities are glTF's photometric numbers used as
//! radiometric ones without the 683 lm/W factor: a point light of intensity I (glTF candela)
//! gives irradiance I·cosθ/r² at distance r; a directional light of intensity E (glTF lux)
//! gives irradiance E·cosθ; an emissive surface with factor e and strength s has radiance e·s.

use glam::{Affine3A, Quat, Vec2, Vec3, Vec4};

use crate::anim::TrsTrack;
pub use crate::texture::{AlphaMode, Texture, TextureRef, UvTransform, WrapMode};
pub use plenoptic_sky::{Environment, PlacedEnvironment, SunTrack, SunTrackSample};

/// Index of an object in [`Scene::objects`]; the object id of id-images and of the pack.
pub type ObjectId = u32;

/// Object id written where a ray hits nothing.
pub const NO_OBJECT: ObjectId = u32::MAX;

/// A triangle mesh in object space.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Unit vertex normals, one per position (computed by area weighting when the file has none).
    pub normals: Vec<Vec3>,
    /// Texture coordinates (set 0), one per position, or empty.
    pub uvs: Vec<Vec2>,
    /// Unit tangents with handedness in w, one per position, or empty (normal maps need them;
    /// computed from UVs when absent).
    pub tangents: Vec<Vec4>,
    /// Linear vertex colours with alpha (`COLOR_0`; alpha 1 for RGB files), one per position,
    /// or empty. They multiply the material's base colour and alpha.
    pub colors: Vec<Vec4>,
    /// Triangles as indices into the vertex arrays.
    pub triangles: Vec<[u32; 3]>,
}

impl Mesh {
    /// Tangents computed from the UVs, as the importer computes them for a normal-mapped mesh
    /// whose file has no TANGENT (Lengyel's per-vertex sum of UV gradients, orthogonalised
    /// against the normal, bitangent sign in w): unit xyz, w = ±1. Empty unless the mesh has a
    /// UV and a normal for every position.
    pub fn uv_tangents(&self) -> Vec<Vec4> {
        let n = self.positions.len();
        let indices_ok = self.triangles.iter().flatten().all(|&i| (i as usize) < n);
        if self.uvs.len() != n || self.normals.len() != n || !indices_ok {
            return Vec::new();
        }
        crate::import::mesh::uv_tangents(self)
    }
}

/// A glTF metallic-roughness material with the extensions plenoptic supports.
#[derive(Debug, Clone, PartialEq)]
pub struct Material {
    /// Name from the file, or empty.
    pub name: String,
    /// Linear base colour and alpha.
    pub base_color: Vec4,
    /// Multiplies `base_color` (colour and alpha).
    pub base_color_texture: Option<TextureRef>,
    /// Metalness in [0, 1].
    pub metallic: f32,
    /// Perceptual roughness in [0, 1] (GGX α = roughness²).
    pub roughness: f32,
    /// Blue channel multiplies metallic, green multiplies roughness.
    pub metallic_roughness_texture: Option<TextureRef>,
    /// Emitted radiance: emissive factor times `KHR_materials_emissive_strength`.
    pub emissive: Vec3,
    /// Multiplies `emissive`.
    pub emissive_texture: Option<TextureRef>,
    /// Tangent-space normal map.
    pub normal_texture: Option<TextureRef>,
    /// Normal map scale.
    pub normal_scale: f32,
    /// `KHR_materials_transmission` factor in [0, 1].
    pub transmission: f32,
    /// `KHR_materials_ior` (1.5 when absent).
    pub ior: f32,
    /// `KHR_materials_volume` thickness factor: 0 (the default, and when the extension is
    /// absent) makes a transmissive surface a *thin wall*, which light crosses without
    /// bending (glTF's default); above 0 the mesh bounds a solid that refracts.
    pub thickness: f32,
    /// Whether back faces are shaded as front faces.
    pub double_sided: bool,
    /// How base-colour alpha is used: opaque, cut out, or coverage.
    pub alpha_mode: AlphaMode,
}

impl Default for Material {
    fn default() -> Self {
        // glTF's default material.
        Self {
            name: String::new(),
            base_color: Vec4::ONE,
            base_color_texture: None,
            metallic: 1.0,
            roughness: 1.0,
            metallic_roughness_texture: None,
            emissive: Vec3::ZERO,
            emissive_texture: None,
            normal_texture: None,
            normal_scale: 1.0,
            transmission: 0.0,
            ior: 1.5,
            thickness: 0.0,
            double_sided: false,
            alpha_mode: AlphaMode::Opaque,
        }
    }
}

/// A local transform as translation, rotation, scale.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Trs {
    /// Translation.
    pub translation: Vec3,
    /// Rotation.
    pub rotation: Quat,
    /// Scale.
    pub scale: Vec3,
}

impl Default for Trs {
    fn default() -> Self {
        Self {
            translation: Vec3::ZERO,
            rotation: Quat::IDENTITY,
            scale: Vec3::ONE,
        }
    }
}

impl Trs {
    /// The affine matrix T·R·S.
    pub fn to_affine(self) -> Affine3A {
        Affine3A::from_scale_rotation_translation(self.scale, self.rotation, self.translation)
    }
}

/// A node of the hierarchy.
#[derive(Debug, Clone, PartialEq)]
pub struct Node {
    /// Name from the file, or `node{index}`.
    pub name: String,
    /// Parent node, `None` for roots.
    pub parent: Option<usize>,
    /// The transform at rest (and wherever a track is absent).
    pub rest: Trs,
    /// Animation of this node, merged over the file's animations; `None` for static nodes.
    pub track: Option<TrsTrack>,
}

/// One drawable: a mesh with a material under a node. Its index is its [`ObjectId`].
#[derive(Debug, Clone, PartialEq)]
pub struct Object {
    /// Node name, with `#k` appended for the k-th primitive when the mesh has several.
    pub name: String,
    /// Path of node names from the root, `/`-separated, e.g. `/House/Door`.
    pub node_path: String,
    /// The node the object hangs under.
    pub node: usize,
    /// Index into [`Scene::meshes`].
    pub mesh: usize,
    /// Index into [`Scene::materials`].
    pub material: usize,
}

/// The kind of a punctual light.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LightKind {
    /// Emits equally in all directions from the node's origin.
    Point,
    /// A cone along the node's −Z axis.
    Spot {
        /// Angle (radians) inside which the intensity is full.
        inner_cone_angle: f32,
        /// Angle (radians) outside which the intensity is zero.
        outer_cone_angle: f32,
    },
    /// Parallel light travelling along the node's −Z axis.
    Directional,
}

/// A `KHR_lights_punctual` light.
#[derive(Debug, Clone, PartialEq)]
pub struct Light {
    /// Name from the file, or empty.
    pub name: String,
    /// Point, spot or directional.
    pub kind: LightKind,
    /// Linear colour.
    pub color: Vec3,
    /// Intensity (candela for point and spot, lux for directional).
    pub intensity: f32,
    /// Range beyond which the light is ignored; `None` for infinite.
    pub range: Option<f32>,
    /// Angular radius of a directional light's disc, radians: 0 is a delta light with hard
    /// shadows; the sun is 0.00465 (soft shadows). Ignored for point and spot lights.
    pub angular_radius: f32,
    /// The node that places the light.
    pub node: usize,
}

/// The sun: the directional light that drives the sky, and its path when a sun study moves
/// it (the recipe's `[sun]`).
#[derive(Debug, Clone, PartialEq)]
pub struct Sun {
    /// Index into [`Scene::lights`] of the sun's directional light.
    pub light: usize,
    /// The sun's direction and illuminance over time; `None`: the light's node and its
    /// colour × intensity decide, as for any light.
    pub track: Option<SunTrack>,
}

/// A camera from the file.
#[derive(Debug, Clone, PartialEq)]
pub struct CameraDef {
    /// Name from the file, or empty.
    pub name: String,
    /// Vertical field of view in radians (perspective cameras; orthographic ones are skipped
    /// with a warning).
    pub yfov: f32,
    /// Width / height, when the file gives it.
    pub aspect_ratio: Option<f32>,
    /// The node that places the camera (looking along its −Z).
    pub node: usize,
}

/// A light placed in the world at some time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlacedLight {
    /// Index into [`Scene::lights`].
    pub light: usize,
    /// World position (unused for directional lights).
    pub position: Vec3,
    /// Unit world direction the light travels along (the node's −Z, or opposite the sun
    /// track's direction).
    pub direction: Vec3,
    /// Linear colour × intensity at this time.
    pub emitted: Vec3,
}

/// An imported scene: everything the tracer needs, with geometry in object space.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Scene {
    /// Node hierarchy; parents come before their children.
    pub nodes: Vec<Node>,
    /// Object-space meshes.
    pub meshes: Vec<Mesh>,
    /// Materials; objects refer to them by index.
    pub materials: Vec<Material>,
    /// Decoded textures.
    pub textures: Vec<Texture>,
    /// Drawables; the index is the object id.
    pub objects: Vec<Object>,
    /// Punctual lights.
    pub lights: Vec<Light>,
    /// What rays that leave the scene see.
    pub environment: Environment,
    /// The sun, when one light is the sun (sun studies, or the sky's sun).
    pub sun: Option<Sun>,
    /// Perspective cameras.
    pub cameras: Vec<CameraDef>,
    /// Warnings from import (unsupported features, named by node).
    pub warnings: Vec<String>,
    /// Which light group each emitter belongs to ([`crate::groups`]); empty: one group.
    pub light_groups: crate::groups::LightGroups,
    /// Multipliers of the sun and the environment ([`Scene::relit`]); one by default.
    pub weights: crate::groups::EmitterWeights,
}

impl Scene {
    /// The world transform of node `node` at time `t`.
    pub fn node_transform(&self, node: usize, t: f32) -> Affine3A {
        let mut transform = Affine3A::IDENTITY;
        let mut current = Some(node);
        // Parents precede children and the hierarchy is acyclic (checked on import), so this
        // walk ends; the bound guards hand-built scenes.
        let mut steps = 0;
        while let Some(index) = current {
            let n = &self.nodes[index];
            transform = self.local_trs(index, t).to_affine() * transform;
            current = n.parent;
            steps += 1;
            if steps > self.nodes.len() {
                break;
            }
        }
        transform
    }

    /// The local transform of `node` at time `t`: its track where it has one, else its rest.
    pub fn local_trs(&self, node: usize, t: f32) -> Trs {
        let n = &self.nodes[node];
        match &n.track {
            Some(track) => track.sample(t, n.rest),
            None => n.rest,
        }
    }

    /// The object-to-world transform of object `id` at time `t`.
    pub fn object_transform(&self, id: ObjectId, t: f32) -> Affine3A {
        self.node_transform(self.objects[id as usize].node, t)
    }

    /// The first object named `name` (node name, `#k` suffix for multi-primitive meshes).
    pub fn object_by_name(&self, name: &str) -> Option<ObjectId> {
        self.objects
            .iter()
            .position(|o| o.name == name)
            .map(|i| i as ObjectId)
    }

    /// The first node named `name`.
    pub fn node_by_name(&self, name: &str) -> Option<usize> {
        self.nodes.iter().position(|n| n.name == name)
    }

    /// The number of triangles over all objects (a mesh drawn twice counts twice).
    pub fn triangle_count(&self) -> usize {
        self.objects
            .iter()
            .map(|o| self.meshes[o.mesh].triangles.len())
            .sum()
    }

    /// Whether node `node` or one of its ancestors is animated.
    pub fn node_is_animated(&self, node: usize) -> bool {
        let mut current = Some(node);
        let mut steps = 0;
        while let Some(index) = current {
            if self.nodes[index].track.is_some() {
                return true;
            }
            current = self.nodes[index].parent;
            steps += 1;
            if steps > self.nodes.len() {
                break;
            }
        }
        false
    }

    /// Whether object `id` moves during the animation.
    pub fn object_is_animated(&self, id: ObjectId) -> bool {
        self.node_is_animated(self.objects[id as usize].node)
    }

    /// Light `light` placed at time `t`: the sun follows its track when it has one, times
    /// [`EmitterWeights::sun`](crate::groups::EmitterWeights::sun).
    pub fn placed_light(&self, light: usize, t: f32) -> PlacedLight {
        let mut placed = self.placed_light_unweighted(light, t);
        if self.sun.as_ref().is_some_and(|s| s.light == light) {
            placed.emitted *= self.weights.sun;
        }
        placed
    }

    /// [`Scene::placed_light`] before the sun's weight.
    fn placed_light_unweighted(&self, light: usize, t: f32) -> PlacedLight {
        let l = &self.lights[light];
        let m = self.node_transform(l.node, t);
        let mut placed = PlacedLight {
            light,
            position: m.translation.into(),
            direction: m.transform_vector3(Vec3::NEG_Z).normalize_or(Vec3::NEG_Z),
            emitted: l.color * l.intensity,
        };
        if let Some(Sun {
            light: sun,
            track: Some(track),
        }) = &self.sun
            && *sun == light
        {
            let (towards, illuminance) = track.at(t);
            placed.direction = -towards;
            placed.emitted = illuminance;
        }
        placed
    }

    /// Unit direction towards the sun and its illuminance at time `t`, when the scene has a
    /// sun.
    pub fn sun_at(&self, t: f32) -> Option<(Vec3, Vec3)> {
        let sun = self.sun.as_ref()?;
        let p = self.placed_light(sun.light, t);
        Some((-p.direction, p.emitted))
    }

    /// The environment at time `t` (a sky, and its ground, lit by the sun then), times
    /// [`EmitterWeights::sky`](crate::groups::EmitterWeights::sky). The ground is lit by the
    /// sun at its own intensity: it is part of the sky's light group.
    pub fn environment_at(&self, t: f32) -> PlacedEnvironment {
        let sun = self.sun.as_ref().map(|s| {
            let p = self.placed_light_unweighted(s.light, t);
            (-p.direction, p.emitted)
        });
        self.environment.at_lit(sun).scaled(self.weights.sky)
    }

    /// Whether the environment changes over time: a sky whose sun moves or changes.
    pub fn environment_is_animated(&self) -> bool {
        self.environment.follows_the_sun() && self.sun_is_animated()
    }

    /// Whether the sun moves or changes: its track does, or its light's node is animated.
    pub fn sun_is_animated(&self) -> bool {
        self.sun.as_ref().is_some_and(|s| match &s.track {
            Some(track) => track.is_animated(),
            None => self.node_is_animated(self.lights[s.light].node),
        })
    }

    /// The sun over `[start, end]` as the runtime needs it: the sun study's track, or the
    /// sun light sampled at `samples` times (one sample when it does not move). `None`
    /// without a sun. The sun at its own intensity, whatever [`Scene::weights`] says.
    pub fn sun_track(&self, start: f32, end: f32, samples: usize) -> Option<SunTrack> {
        let sun = self.sun.as_ref()?;
        if let Some(track) = &sun.track {
            return Some(track.clone());
        }
        if !self.sun_is_animated() || end <= start {
            let p = self.placed_light_unweighted(sun.light, start);
            let (d, e) = (-p.direction, p.emitted);
            return Some(SunTrack::fixed(d, e));
        }
        let n = samples.clamp(2, SunTrack::MAX_SAMPLES);
        let list = (0..n)
            .map(|i| {
                let t = start + (end - start) * i as f32 / (n - 1) as f32;
                let p = self.placed_light_unweighted(sun.light, t);
                SunTrackSample {
                    time: t,
                    direction: -p.direction,
                    illuminance: p.emitted,
                }
            })
            .collect();
        SunTrack::new(list).ok()
    }

    /// The time range covered by the animation tracks, `(0, 0)` for a static scene.
    pub fn animation_range(&self) -> (f32, f32) {
        let mut range: Option<(f32, f32)> = None;
        for node in &self.nodes {
            if let Some((a, b)) = node.track.as_ref().and_then(TrsTrack::time_range) {
                range = Some(match range {
                    Some((lo, hi)) => (lo.min(a), hi.max(b)),
                    None => (a, b),
                });
            }
        }
        range.unwrap_or((0.0, 0.0))
    }
}
