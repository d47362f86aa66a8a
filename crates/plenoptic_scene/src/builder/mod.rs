//! A programmatic scene builder that writes glTF 2.0.
//!
//! Tests, benchmarks and tour scenes describe a scene in code — meshes (boxes, planes, UV
//! spheres or any [`Mesh`]), materials, a node hierarchy with punctual lights and cameras, and
//! TRS animation tracks — and write it as `.glb` or `.gltf` (with an embedded base64 buffer).
//! [`SceneBuilder::build_scene`] goes through the bytes and the real importer, so a scene made
//! here is exactly what a baker loading the file would see.
//!
//! Handles ([`MaterialHandle`], [`MeshHandle`], [`NodeHandle`], [`TextureHandle`]) index the
//! builder that returned them. Nodes are written in the order they were added; the importer
//! orders them depth first from the roots, so look nodes and objects up by name
//! ([`Scene::node_by_name`], [`Scene::object_by_name`]) rather than by handle index.
//!
//! ```
//! use glam::{Quat, Vec3};
//! use plenoptic_scene::builder::{LightDesc, MaterialDesc, NodeDesc, SceneBuilder};
//! use plenoptic_scene::Track;
//!
//! let mut b = SceneBuilder::new();
//! let red = b.add_material(MaterialDesc::diffuse(Vec3::new(0.8, 0.1, 0.1)).named("red"));
//! let floor = b.add_plane("floor", glam::Vec2::splat(10.0), 4, red);
//! b.add_node(NodeDesc::new("Floor").mesh(floor));
//! let ball = b.add_sphere("ball", 0.5, 32, red);
//! let arm = b.add_node(NodeDesc::new("Arm").translation(Vec3::Y));
//! b.add_node(NodeDesc::new("Ball").parent(arm).mesh(ball).translation(Vec3::X));
//! b.add_node(NodeDesc::new("Sun").light(LightDesc::directional(Vec3::ONE, 3.0)));
//! b.animate_rotation(
//!     arm,
//!     Track::linear([(0.0, Quat::IDENTITY), (2.0, Quat::from_rotation_y(1.0))]),
//! );
//! let scene = b.build_scene().unwrap();
//! assert_eq!(scene.objects.len(), 2);
//! let ball = scene.object_by_name("Ball").unwrap();
//! assert!(scene.object_is_animated(ball));
//! ```

mod material;
pub mod shapes;
mod write;

use std::path::Path;

use glam::{Quat, Vec2, Vec3};

pub use self::material::MaterialDesc;
use crate::anim::Track;
use crate::error::{Result, SceneError};
use crate::model::{LightKind, Mesh, Scene, Trs, WrapMode};

/// A punctual light of the builder (`KHR_lights_punctual`).
#[derive(Debug, Clone, PartialEq)]
pub struct LightDesc {
    /// Name written to the file.
    pub name: String,
    /// Point, spot or directional.
    pub kind: LightKind,
    /// Linear colour.
    pub color: Vec3,
    /// Candela (point, spot) or lux (directional).
    pub intensity: f32,
    /// Range, `None` for infinite.
    pub range: Option<f32>,
}

impl LightDesc {
    /// A point light.
    pub fn point(color: Vec3, intensity: f32) -> Self {
        Self {
            name: String::new(),
            kind: LightKind::Point,
            color,
            intensity,
            range: None,
        }
    }
    /// A spot light along the node's −Z with cone angles in radians.
    pub fn spot(color: Vec3, intensity: f32, inner_cone_angle: f32, outer_cone_angle: f32) -> Self {
        Self {
            kind: LightKind::Spot {
                inner_cone_angle,
                outer_cone_angle,
            },
            ..Self::point(color, intensity)
        }
    }
    /// A directional light along the node's −Z.
    pub fn directional(color: Vec3, intensity: f32) -> Self {
        Self {
            kind: LightKind::Directional,
            ..Self::point(color, intensity)
        }
    }
    /// Sets the name.
    pub fn named(mut self, name: impl Into<String>) -> Self {
        self.name = name.into();
        self
    }
    /// Sets the range.
    pub fn range(mut self, range: f32) -> Self {
        self.range = Some(range);
        self
    }
}

/// A perspective camera of the builder.
#[derive(Debug, Clone, PartialEq)]
pub struct CameraDesc {
    /// Name written to the file.
    pub name: String,
    /// Vertical field of view in radians.
    pub yfov: f32,
    /// Width / height, if fixed.
    pub aspect_ratio: Option<f32>,
    /// Near plane distance.
    pub znear: f32,
    /// Far plane distance, `None` for infinite.
    pub zfar: Option<f32>,
}

impl CameraDesc {
    /// A perspective camera with vertical field of view `yfov` (radians), near plane 0.01.
    pub fn perspective(yfov: f32) -> Self {
        Self {
            name: String::new(),
            yfov,
            aspect_ratio: None,
            znear: 0.01,
            zfar: None,
        }
    }
    /// Sets the name.
    pub fn named(mut self, name: impl Into<String>) -> Self {
        self.name = name.into();
        self
    }
    /// Sets the aspect ratio.
    pub fn aspect_ratio(mut self, aspect_ratio: f32) -> Self {
        self.aspect_ratio = Some(aspect_ratio);
        self
    }
}

/// A node of the builder: a name, a parent, a local transform and what hangs under it.
#[derive(Debug, Clone, PartialEq)]
pub struct NodeDesc {
    /// Node name (objects take their names from it).
    pub name: String,
    /// Parent, `None` for a root of the scene.
    pub parent: Option<NodeHandle>,
    /// Local transform at rest.
    pub transform: Trs,
    /// Write the transform as a column-major `matrix` instead of TRS properties.
    pub write_matrix: bool,
    /// Mesh drawn at this node (one object per primitive).
    pub mesh: Option<MeshHandle>,
    /// Light placed by this node.
    pub light: Option<LightDesc>,
    /// Camera placed by this node.
    pub camera: Option<CameraDesc>,
}

impl NodeDesc {
    /// An empty root node named `name` at the origin.
    pub fn new(name: impl Into<String>) -> Self {
        Self {
            name: name.into(),
            parent: None,
            transform: Trs::default(),
            write_matrix: false,
            mesh: None,
            light: None,
            camera: None,
        }
    }
    /// Sets the parent.
    pub fn parent(mut self, parent: NodeHandle) -> Self {
        self.parent = Some(parent);
        self
    }
    /// Sets the local translation.
    pub fn translation(mut self, translation: Vec3) -> Self {
        self.transform.translation = translation;
        self
    }
    /// Sets the local rotation.
    pub fn rotation(mut self, rotation: Quat) -> Self {
        self.transform.rotation = rotation;
        self
    }
    /// Sets the local scale.
    pub fn scale(mut self, scale: Vec3) -> Self {
        self.transform.scale = scale;
        self
    }
    /// Sets the whole local transform.
    pub fn transform(mut self, transform: Trs) -> Self {
        self.transform = transform;
        self
    }
    /// Writes the transform as a matrix (exercises the importer's decomposition).
    pub fn as_matrix(mut self) -> Self {
        self.write_matrix = true;
        self
    }
    /// Hangs a mesh under the node.
    pub fn mesh(mut self, mesh: MeshHandle) -> Self {
        self.mesh = Some(mesh);
        self
    }
    /// Places a light at the node.
    pub fn light(mut self, light: LightDesc) -> Self {
        self.light = Some(light);
        self
    }
    /// Places a camera at the node.
    pub fn camera(mut self, camera: CameraDesc) -> Self {
        self.camera = Some(camera);
        self
    }
}

/// A material added to a [`SceneBuilder`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct MaterialHandle(usize);
/// A mesh (one or more primitives) added to a [`SceneBuilder`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct MeshHandle(usize);
/// A node added to a [`SceneBuilder`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct NodeHandle(usize);
/// A texture added to a [`SceneBuilder`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct TextureHandle(usize);

impl NodeHandle {
    /// The node's index in the written glTF (insertion order).
    pub fn gltf_index(self) -> usize {
        self.0
    }
}

/// An 8-bit RGBA texture, stored as PNG in the file.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct TextureDesc {
    pub(crate) width: u32,
    pub(crate) height: u32,
    pub(crate) rgba8: Vec<u8>,
    pub(crate) wrap_s: WrapMode,
    pub(crate) wrap_t: WrapMode,
}

/// A mesh of the builder: named, one primitive per (geometry, material).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct MeshDesc {
    pub(crate) name: String,
    pub(crate) primitives: Vec<(Mesh, MaterialHandle)>,
}

/// One animated property of one node.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum TrackDesc {
    Translation(Track<Vec3>),
    Rotation(Track<Quat>),
    Scale(Track<Vec3>),
}

/// Builds a glTF scene in code; see the [module documentation](self).
#[derive(Debug, Clone, Default)]
pub struct SceneBuilder {
    pub(crate) materials: Vec<MaterialDesc>,
    pub(crate) textures: Vec<TextureDesc>,
    pub(crate) meshes: Vec<MeshDesc>,
    pub(crate) nodes: Vec<NodeDesc>,
    pub(crate) tracks: Vec<(NodeHandle, TrackDesc)>,
}

impl SceneBuilder {
    /// An empty builder.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds a material.
    pub fn add_material(&mut self, material: MaterialDesc) -> MaterialHandle {
        self.materials.push(material);
        MaterialHandle(self.materials.len() - 1)
    }

    /// Adds an 8-bit RGBA texture, `width × height` texels row by row from the top
    /// (`rgba8.len()` must be `4 · width · height`, checked when writing).
    pub fn add_texture_rgba8(&mut self, width: u32, height: u32, rgba8: Vec<u8>) -> TextureHandle {
        self.textures.push(TextureDesc {
            width,
            height,
            rgba8,
            wrap_s: WrapMode::Repeat,
            wrap_t: WrapMode::Repeat,
        });
        TextureHandle(self.textures.len() - 1)
    }

    /// Sets the wrap modes of `texture`'s sampler (REPEAT in both directions by default; a
    /// sampler is written only for other modes). Fails for a handle of another builder.
    pub fn set_texture_wrap(
        &mut self,
        texture: TextureHandle,
        wrap_s: WrapMode,
        wrap_t: WrapMode,
    ) -> Result<&mut Self> {
        let t = self.textures.get_mut(texture.0).ok_or_else(|| {
            SceneError::invalid(
                "<builder>",
                format!("texture {}", texture.0),
                "handle from another builder",
            )
        })?;
        t.wrap_s = wrap_s;
        t.wrap_t = wrap_t;
        Ok(self)
    }

    /// Adds a mesh of one primitive. Normals may be empty (the importer computes them), UVs,
    /// tangents and vertex colours may be empty (colours are written as float `COLOR_0`).
    pub fn add_mesh(
        &mut self,
        name: impl Into<String>,
        mesh: Mesh,
        material: MaterialHandle,
    ) -> MeshHandle {
        self.add_mesh_primitives(name, vec![(mesh, material)])
    }

    /// Adds a mesh of several primitives, each with its own material; each becomes an object
    /// named `Node#k` on import.
    pub fn add_mesh_primitives(
        &mut self,
        name: impl Into<String>,
        primitives: Vec<(Mesh, MaterialHandle)>,
    ) -> MeshHandle {
        self.meshes.push(MeshDesc {
            name: name.into(),
            primitives,
        });
        MeshHandle(self.meshes.len() - 1)
    }

    /// Adds a box mesh ([`shapes::cuboid`]).
    pub fn add_box(
        &mut self,
        name: impl Into<String>,
        size: Vec3,
        material: MaterialHandle,
    ) -> MeshHandle {
        self.add_mesh(name, shapes::cuboid(size), material)
    }

    /// Adds a plane mesh in the x-z plane facing +Y ([`shapes::plane`]).
    pub fn add_plane(
        &mut self,
        name: impl Into<String>,
        size: Vec2,
        subdivisions: u32,
        material: MaterialHandle,
    ) -> MeshHandle {
        self.add_mesh(name, shapes::plane(size, subdivisions), material)
    }

    /// Adds a UV sphere mesh ([`shapes::uv_sphere`]; 320 segments give over 100k triangles).
    pub fn add_sphere(
        &mut self,
        name: impl Into<String>,
        radius: f32,
        segments: u32,
        material: MaterialHandle,
    ) -> MeshHandle {
        self.add_mesh(name, shapes::uv_sphere(radius, segments), material)
    }

    /// Adds a node.
    pub fn add_node(&mut self, node: NodeDesc) -> NodeHandle {
        self.nodes.push(node);
        NodeHandle(self.nodes.len() - 1)
    }

    /// Convenience: adds a mesh of one primitive and a root node named `name` drawing it at
    /// `transform`.
    pub fn add_object(
        &mut self,
        name: impl Into<String>,
        mesh: Mesh,
        material: MaterialHandle,
        transform: Trs,
    ) -> NodeHandle {
        let name = name.into();
        let mesh = self.add_mesh(name.clone(), mesh, material);
        self.add_node(NodeDesc::new(name).mesh(mesh).transform(transform))
    }

    /// Animates the translation of `node`.
    pub fn animate_translation(&mut self, node: NodeHandle, track: Track<Vec3>) -> &mut Self {
        self.tracks.push((node, TrackDesc::Translation(track)));
        self
    }

    /// Animates the rotation of `node`.
    pub fn animate_rotation(&mut self, node: NodeHandle, track: Track<Quat>) -> &mut Self {
        self.tracks.push((node, TrackDesc::Rotation(track)));
        self
    }

    /// Animates the scale of `node`.
    pub fn animate_scale(&mut self, node: NodeHandle, track: Track<Vec3>) -> &mut Self {
        self.tracks.push((node, TrackDesc::Scale(track)));
        self
    }

    /// The scene as binary glTF.
    pub fn to_glb_bytes(&self) -> Result<Vec<u8>> {
        write::to_glb(self)
    }

    /// The scene as glTF JSON with the buffer embedded as a base64 `data:` URI.
    pub fn to_gltf_string(&self) -> Result<String> {
        write::to_gltf(self)
    }

    /// Writes the scene as binary glTF to `path`.
    pub fn write_glb(&self, path: &Path) -> Result<()> {
        let bytes = self.to_glb_bytes()?;
        std::fs::write(path, bytes).map_err(|source| SceneError::Io {
            file: path.to_owned(),
            source,
        })
    }

    /// Writes the scene as glTF JSON with an embedded buffer to `path`.
    pub fn write_gltf(&self, path: &Path) -> Result<()> {
        let text = self.to_gltf_string()?;
        std::fs::write(path, text).map_err(|source| SceneError::Io {
            file: path.to_owned(),
            source,
        })
    }

    /// Writes the scene to bytes and imports them: the scene exactly as a file would give it.
    pub fn build_scene(&self) -> Result<Scene> {
        let bytes = self.to_glb_bytes()?;
        crate::import::load_slice(&bytes, "<builder>.glb", None)
    }
}
