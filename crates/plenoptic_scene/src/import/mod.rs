//! glTF 2.0 import: `.gltf` (external buffers and images relative to the file, or `data:`
//! URIs) and `.glb` into a [`Scene`].
//!
//! The document is parsed and validated by the `gltf` crate; buffers, accessors, the node
//! hierarchy and animation data are resolved and checked here, so that every malformed input
//! becomes a [`SceneError`] naming the file and the element
//! (`scene.gltf: accessor 3: index 812 out of range for 24 vertices`) and nothing is allocated
//! before its size has been checked against the data that backs it.
//!
//! Only the default scene (or scene 0) is imported. Its nodes are ordered depth first from the
//! roots in document order, so parents precede children; object ids follow the same order,
//! one per triangle primitive. Unsupported features — skinning, morph targets, non-triangle
//! primitives, orthographic cameras, morph weight animation, texture coordinate sets other
//! than 0, extensions other than [`SUPPORTED_EXTENSIONS`] — are named in [`Scene::warnings`]
//! with the element (`material 2 'Glass'`, `node 'Door'`); the bake prefixes each with the
//! file. An unsupported extension in `extensionsRequired` is an error.
//!
//! Materials keep `alphaMode` and `alphaCutoff` (a negative cutoff is an error),
//! `KHR_texture_transform` and the sampler's wrap modes on every texture reference, and
//! primitives their `COLOR_0` (float or normalised unsigned byte/short, VEC3 or VEC4).

mod data;
mod extensions;
mod material;
pub(crate) mod mesh;

pub use self::extensions::SUPPORTED_EXTENSIONS;

use std::collections::HashMap;
use std::path::Path;

use glam::{Mat4, Quat, Vec3, Vec4};
use gltf::accessor::Dimensions;
use gltf::animation::{Interpolation as GltfInterpolation, Property};

use self::data::Data;
use self::material::Materials;
use crate::anim::{Interpolation, Key, Track, TrsTrack};
use crate::error::{Result, SceneError};
use crate::model::{CameraDef, Light, LightKind, Node, Object, Scene, Trs};

/// Loads a `.gltf` or `.glb` file; external resources are resolved relative to its directory.
pub fn load(path: &Path) -> Result<Scene> {
    let bytes = std::fs::read(path).map_err(|source| SceneError::Io {
        file: path.to_owned(),
        source,
    })?;
    let name = path.display().to_string();
    let base_dir = path.parent().unwrap_or(Path::new("."));
    load_slice(&bytes, &name, Some(base_dir))
}

/// Loads glTF or GLB from memory. `name` names the data in errors; external files are
/// resolved relative to `base_dir` and are an error without one.
pub fn load_slice(bytes: &[u8], name: &str, base_dir: Option<&Path>) -> Result<Scene> {
    // The gltf crate validates indices between elements; a panic inside it would be a bug of
    // that crate, but bad input must still not take the process down.
    let parsed = std::panic::catch_unwind(|| gltf::Gltf::from_slice(bytes)).map_err(|_| {
        SceneError::Parse {
            file: name.to_owned(),
            message: "the glTF parser panicked on this input".to_owned(),
        }
    })?;
    let gltf = parsed.map_err(|e| match e {
        gltf::Error::Validation(errors) => {
            let (path, first) = &errors[0];
            SceneError::invalid(
                name,
                path.to_string(),
                format!(
                    "{first}{}",
                    if errors.len() > 1 {
                        format!(" (and {} more validation errors)", errors.len() - 1)
                    } else {
                        String::new()
                    }
                ),
            )
        }
        other => SceneError::Parse {
            file: name.to_owned(),
            message: other.to_string(),
        },
    })?;
    let gltf::Gltf { document, blob } = gltf;
    let data = Data::load(name, base_dir, &document, blob)?;
    let raw = extensions::raw_json(bytes);
    let scene = Scene {
        warnings: extensions::unsupported_warnings(&document, raw.as_ref()),
        ..Scene::default()
    };
    Importer {
        data: &data,
        document: &document,
        raw: raw.as_ref(),
        scene,
        materials: Materials::default(),
        material_map: HashMap::new(),
        mesh_map: HashMap::new(),
        node_map: HashMap::new(),
    }
    .run()
}

struct Importer<'a> {
    data: &'a Data<'a>,
    document: &'a gltf::Document,
    /// The document's JSON, for extension data the `gltf` crate does not expose.
    raw: Option<&'a serde_json::Value>,
    scene: Scene,
    materials: Materials,
    /// glTF material index (`None`: the default material) → index in the scene.
    material_map: HashMap<Option<usize>, usize>,
    /// (glTF mesh, primitive) → index in the scene.
    mesh_map: HashMap<(usize, usize), usize>,
    /// glTF node index → index in the scene.
    node_map: HashMap<usize, usize>,
}

impl Importer<'_> {
    fn err(&self, element: impl Into<String>, problem: impl Into<String>) -> SceneError {
        self.data.err(element, problem)
    }

    fn run(mut self) -> Result<Scene> {
        let order = self.node_order()?;
        let mut paths: Vec<String> = Vec::with_capacity(order.len());
        for (ours, &(index, parent)) in order.iter().enumerate() {
            let node = self
                .document
                .nodes()
                .nth(index)
                .expect("validated node index");
            let name = node
                .name()
                .map_or_else(|| format!("node{index}"), str::to_owned);
            let rest = self.rest_transform(&node, &name)?;
            let parent = parent.map(|p| self.node_map[&p]);
            let path = match parent {
                Some(p) => format!("{}/{name}", paths[p]),
                None => format!("/{name}"),
            };
            self.node_map.insert(index, ours);
            self.scene.nodes.push(Node {
                name: name.clone(),
                parent,
                rest,
                track: None,
            });
            self.attach(&node, ours, &name, &path)?;
            paths.push(path);
        }
        self.animations()?;
        self.scene.textures = std::mem::take(&mut self.materials.textures);
        Ok(self.scene)
    }

    /// Nodes of the imported scene depth first, with their glTF parents; checks for multiple
    /// parents and cycles over the whole document.
    fn node_order(&self) -> Result<Vec<(usize, Option<usize>)>> {
        let doc = self.document;
        let scene = doc
            .default_scene()
            .or_else(|| doc.scenes().next())
            .ok_or_else(|| self.err("scene", "the file has no scene"))?;
        let n = doc.nodes().len();
        let mut parent: Vec<Option<usize>> = vec![None; n];
        for node in doc.nodes() {
            for child in node.children() {
                let c = child.index();
                if let Some(p) = parent[c] {
                    return Err(self.err(
                        format!("node {c}"),
                        format!("has more than one parent (nodes {p} and {})", node.index()),
                    ));
                }
                parent[c] = Some(node.index());
            }
        }
        // Every node has at most one parent: walk up from each, marking the path.
        let mut state = vec![0u8; n]; // 0 unvisited, 1 on the current walk, 2 done
        for start in 0..n {
            let mut walk = Vec::new();
            let mut current = Some(start);
            while let Some(i) = current {
                match state[i] {
                    2 => break,
                    1 => {
                        return Err(self.err(
                            format!("node {i}"),
                            "is its own ancestor (recursive node hierarchy)",
                        ));
                    }
                    _ => {
                        state[i] = 1;
                        walk.push(i);
                        current = parent[i];
                    }
                }
            }
            for i in walk {
                state[i] = 2;
            }
        }
        let mut order = Vec::with_capacity(n);
        let mut seen = vec![false; n];
        for root in scene.nodes() {
            let r = root.index();
            if let Some(p) = parent[r] {
                return Err(self.err(
                    format!("scene {}", scene.index()),
                    format!("node {r} is listed as a root but is a child of node {p}"),
                ));
            }
            if seen[r] {
                return Err(self.err(
                    format!("scene {}", scene.index()),
                    format!("node {r} is listed twice"),
                ));
            }
            let mut stack = vec![root];
            while let Some(node) = stack.pop() {
                seen[node.index()] = true;
                order.push((node.index(), parent[node.index()]));
                let children: Vec<_> = node.children().collect();
                stack.extend(children.into_iter().rev());
            }
        }
        Ok(order)
    }

    fn rest_transform(&self, node: &gltf::Node, name: &str) -> Result<Trs> {
        let element = format!("node {} '{name}'", node.index());
        let (scale, rotation, translation) = match node.transform() {
            gltf::scene::Transform::Matrix { matrix } => {
                if matrix.iter().flatten().any(|v| !v.is_finite()) {
                    return Err(self.err(element, "non-finite matrix"));
                }
                let m = Mat4::from_cols_array_2d(&matrix);
                let (s, r, t) = m.to_scale_rotation_translation();
                (s, r, t)
            }
            gltf::scene::Transform::Decomposed {
                translation,
                rotation,
                scale,
            } => (
                Vec3::from_array(scale),
                Quat::from_array(rotation),
                Vec3::from_array(translation),
            ),
        };
        if !(scale.is_finite() && rotation.is_finite() && translation.is_finite()) {
            return Err(self.err(element, "non-finite transform"));
        }
        if rotation.length_squared() < 1e-12 {
            return Err(self.err(element, "zero rotation quaternion"));
        }
        Ok(Trs {
            translation,
            rotation: rotation.normalize(),
            scale,
        })
    }

    /// Objects, light and camera of glTF node `node`, imported as scene node `ours`.
    fn attach(&mut self, node: &gltf::Node, ours: usize, name: &str, path: &str) -> Result<()> {
        if node.skin().is_some() {
            self.scene.warnings.push(format!(
                "node '{name}': skinning is not supported; geometry imported at rest pose"
            ));
        }
        if let Some(mesh) = node.mesh() {
            let primitives: Vec<_> = mesh.primitives().collect();
            if primitives
                .iter()
                .any(|p| p.morph_targets().next().is_some())
            {
                self.scene.warnings.push(format!(
                    "node '{name}': morph targets are not supported; geometry imported at rest pose"
                ));
            }
            let several = primitives.len() > 1;
            for (k, primitive) in primitives.iter().enumerate() {
                if primitive.mode() != gltf::mesh::Mode::Triangles {
                    self.scene.warnings.push(format!(
                        "node '{name}': mesh {} primitive {k}: mode {:?} is not triangles; skipped",
                        mesh.index(),
                        primitive.mode()
                    ));
                    continue;
                }
                let material = self.material(&primitive.material())?;
                let key = (mesh.index(), k);
                let mesh_index = match self.mesh_map.get(&key) {
                    Some(&m) => m,
                    None => {
                        let label = format!("mesh {} primitive {k}", mesh.index());
                        let needs_tangents =
                            self.scene.materials[material].normal_texture.is_some();
                        let m = mesh::read_primitive(self.data, primitive, &label, needs_tangents)?;
                        self.scene.meshes.push(m);
                        self.mesh_map.insert(key, self.scene.meshes.len() - 1);
                        self.scene.meshes.len() - 1
                    }
                };
                let suffix = if several {
                    format!("#{k}")
                } else {
                    String::new()
                };
                self.scene.objects.push(Object {
                    name: format!("{name}{suffix}"),
                    node_path: path.to_owned(),
                    node: ours,
                    mesh: mesh_index,
                    material,
                });
            }
        }
        if let Some(light) = node.light() {
            let element = format!("light {}", light.index());
            let kind = match light.kind() {
                gltf::khr_lights_punctual::Kind::Point => LightKind::Point,
                gltf::khr_lights_punctual::Kind::Directional => LightKind::Directional,
                gltf::khr_lights_punctual::Kind::Spot {
                    inner_cone_angle,
                    outer_cone_angle,
                } => {
                    if !(inner_cone_angle.is_finite() && outer_cone_angle.is_finite()) {
                        return Err(self.err(element, "non-finite cone angle"));
                    }
                    LightKind::Spot {
                        inner_cone_angle,
                        outer_cone_angle,
                    }
                }
            };
            let color = Vec3::from_array(light.color());
            if !color.is_finite()
                || !light.intensity().is_finite()
                || light.range().is_some_and(|r| !r.is_finite())
            {
                return Err(self.err(element, "non-finite colour, intensity or range"));
            }
            self.scene.lights.push(Light {
                name: light.name().unwrap_or_default().to_owned(),
                kind,
                color,
                intensity: light.intensity(),
                range: light.range(),
                angular_radius: 0.0,
                node: ours,
            });
        }
        if let Some(camera) = node.camera() {
            match camera.projection() {
                gltf::camera::Projection::Perspective(p) => {
                    if !p.yfov().is_finite() || p.yfov() <= 0.0 {
                        return Err(self.err(
                            format!("camera {}", camera.index()),
                            "yfov must be positive and finite",
                        ));
                    }
                    self.scene.cameras.push(CameraDef {
                        name: camera.name().unwrap_or_default().to_owned(),
                        yfov: p.yfov(),
                        aspect_ratio: p.aspect_ratio(),
                        node: ours,
                    });
                }
                gltf::camera::Projection::Orthographic(_) => self.scene.warnings.push(format!(
                    "node '{name}': camera {} is orthographic; skipped",
                    camera.index()
                )),
            }
        }
        Ok(())
    }

    fn material(&mut self, material: &gltf::Material) -> Result<usize> {
        if let Some(&m) = self.material_map.get(&material.index()) {
            return Ok(m);
        }
        let raw = material.index().and_then(|i| {
            self.raw
                .and_then(|r| r.get("materials"))
                .and_then(|m| m.get(i))
        });
        let converted =
            self.materials
                .convert(self.data, material, raw, &mut self.scene.warnings)?;
        self.scene.materials.push(converted);
        let index = self.scene.materials.len() - 1;
        self.material_map.insert(material.index(), index);
        Ok(index)
    }

    /// Merges every animation's TRS channels into per-node tracks.
    fn animations(&mut self) -> Result<()> {
        for animation in self.document.animations() {
            for channel in animation.channels() {
                let target = channel.target();
                let element = format!(
                    "animation {} channel {}",
                    animation.index(),
                    channel.index()
                );
                let Some(&ours) = self.node_map.get(&target.node().index()) else {
                    continue; // a node outside the imported scene
                };
                let node_name = self.scene.nodes[ours].name.clone();
                let sampler = channel.sampler();
                let interpolation = match sampler.interpolation() {
                    GltfInterpolation::Step => Interpolation::Step,
                    GltfInterpolation::Linear => Interpolation::Linear,
                    GltfInterpolation::CubicSpline => Interpolation::CubicSpline,
                };
                let property = target.property();
                if property == Property::MorphTargetWeights {
                    self.scene.warnings.push(format!(
                        "node '{node_name}': {element} animates morph target weights; ignored"
                    ));
                    continue;
                }
                let input = sampler.input();
                let times =
                    self.data
                        .read_floats(&input, Dimensions::Scalar, false, "animation input")?;
                if let Some(k) = times.windows(2).position(|w| w[1] <= w[0]) {
                    return Err(self.err(
                        format!("accessor {}", input.index()),
                        format!(
                            "{element}: key times must increase strictly (key {} at {} after {})",
                            k + 1,
                            times[k + 1],
                            times[k]
                        ),
                    ));
                }
                let output = sampler.output();
                let per_key = if interpolation == Interpolation::CubicSpline {
                    3
                } else {
                    1
                };
                if output.count() != times.len() * per_key {
                    return Err(self.err(
                        format!("accessor {}", output.index()),
                        format!(
                            "{element}: {} output values for {} keys ({per_key} per key for {interpolation:?})",
                            output.count(),
                            times.len()
                        ),
                    ));
                }
                let track = self.scene.nodes[ours]
                    .track
                    .get_or_insert_with(TrsTrack::default);
                let duplicate = match property {
                    Property::Translation | Property::Scale => {
                        let values = self.data.read_floats(
                            &output,
                            Dimensions::Vec3,
                            false,
                            "animation output",
                        )?;
                        let values: Vec<Vec3> =
                            values.chunks_exact(3).map(Vec3::from_slice).collect();
                        let built = build_track(interpolation, &times, &values, Vec3::ZERO, |v| v);
                        let slot = if property == Property::Translation {
                            &mut track.translation
                        } else {
                            &mut track.scale
                        };
                        let duplicate = slot.is_some();
                        slot.get_or_insert(built);
                        duplicate
                    }
                    _ => {
                        let values = self.data.read_floats(
                            &output,
                            Dimensions::Vec4,
                            true,
                            "animation output",
                        )?;
                        let values: Vec<Quat> = values
                            .chunks_exact(4)
                            .map(|c| Quat::from_vec4(Vec4::from_slice(c)))
                            .collect();
                        let built = build_track(
                            interpolation,
                            &times,
                            &values,
                            Quat::from_xyzw(0.0, 0.0, 0.0, 0.0),
                            |q| q.normalize(),
                        );
                        let duplicate = track.rotation.is_some();
                        track.rotation.get_or_insert(built);
                        duplicate
                    }
                };
                if duplicate {
                    self.scene.warnings.push(format!(
                        "node '{node_name}': {element} animates {property:?} already animated by an earlier channel; ignored"
                    ));
                }
            }
        }
        Ok(())
    }
}

/// A track from key times and output values (triples for cubic splines); `fix` normalises
/// key values of linear and step tracks, whose tangents are `zero`.
fn build_track<T: Copy>(
    interpolation: Interpolation,
    times: &[f32],
    values: &[T],
    zero: T,
    fix: impl Fn(T) -> T,
) -> Track<T> {
    let keys = times
        .iter()
        .enumerate()
        .map(|(i, &time)| match interpolation {
            Interpolation::CubicSpline => Key {
                time,
                in_tangent: values[3 * i],
                value: values[3 * i + 1],
                out_tangent: values[3 * i + 2],
            },
            _ => Key {
                time,
                value: fix(values[i]),
                in_tangent: zero,
                out_tangent: zero,
            },
        })
        .collect();
    Track {
        interpolation,
        keys,
    }
}
