//! Serialisation of a [`SceneBuilder`] to glTF JSON and GLB.

use glam::{Mat4, Vec3};
use serde_json::{Map, Value, json};

use super::{CameraDesc, LightDesc, MeshDesc, NodeDesc, SceneBuilder, TrackDesc};
use crate::anim::{Interpolation, Track};
use crate::error::{Result, SceneError};
use crate::model::{LightKind, Mesh, WrapMode};

const FILE: &str = "<builder>";
const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;
const FLOAT: u32 = 5126;
const UNSIGNED_INT: u32 = 5125;

/// The glTF sampler code of a wrap mode.
fn wrap_code(mode: WrapMode) -> u32 {
    match mode {
        WrapMode::Repeat => 10497,
        WrapMode::ClampToEdge => 33071,
        WrapMode::MirroredRepeat => 33648,
    }
}

pub(super) fn invalid(element: impl Into<String>, problem: impl Into<String>) -> SceneError {
    SceneError::invalid(FILE, element, problem)
}

/// The binary buffer with its views and accessors.
#[derive(Default)]
struct Bin {
    data: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Bin {
    fn align(&mut self) {
        while !self.data.len().is_multiple_of(4) {
            self.data.push(0);
        }
    }

    fn view(&mut self, bytes: &[u8], target: Option<u32>) -> usize {
        self.align();
        let mut view = json!({
            "buffer": 0,
            "byteOffset": self.data.len(),
            "byteLength": bytes.len(),
        });
        if let Some(target) = target {
            view["target"] = json!(target);
        }
        self.data.extend_from_slice(bytes);
        self.views.push(view);
        self.views.len() - 1
    }

    /// Float accessor of `ty` ("SCALAR", "VEC2"…) over `values` (flattened).
    fn floats(
        &mut self,
        values: &[f32],
        components: usize,
        ty: &str,
        min_max: bool,
        target: Option<u32>,
    ) -> usize {
        let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        let view = self.view(&bytes, target);
        let mut accessor = json!({
            "bufferView": view,
            "componentType": FLOAT,
            "count": values.len() / components,
            "type": ty,
        });
        if min_max && !values.is_empty() {
            let mut min = vec![f32::INFINITY; components];
            let mut max = vec![f32::NEG_INFINITY; components];
            for chunk in values.chunks(components) {
                for (i, v) in chunk.iter().enumerate() {
                    min[i] = min[i].min(*v);
                    max[i] = max[i].max(*v);
                }
            }
            accessor["min"] = json!(min);
            accessor["max"] = json!(max);
        }
        self.accessors.push(accessor);
        self.accessors.len() - 1
    }

    fn indices(&mut self, triangles: &[[u32; 3]]) -> usize {
        let bytes: Vec<u8> = triangles
            .iter()
            .flatten()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        let view = self.view(&bytes, Some(ELEMENT_ARRAY_BUFFER));
        self.accessors.push(json!({
            "bufferView": view,
            "componentType": UNSIGNED_INT,
            "count": triangles.len() * 3,
            "type": "SCALAR",
        }));
        self.accessors.len() - 1
    }
}

pub(super) fn check_finite(element: &str, what: &str, values: &[f32]) -> Result<()> {
    if let Some(i) = values.iter().position(|v| !v.is_finite()) {
        return Err(invalid(
            element,
            format!("{what}: non-finite value at component {i}"),
        ));
    }
    Ok(())
}

fn check_mesh(element: &str, mesh: &Mesh) -> Result<()> {
    let n = mesh.positions.len();
    if n == 0 {
        return Err(invalid(element, "no positions"));
    }
    for (what, len) in [
        ("normals", mesh.normals.len()),
        ("uvs", mesh.uvs.len()),
        ("tangents", mesh.tangents.len()),
        ("colors", mesh.colors.len()),
    ] {
        if len != 0 && len != n {
            return Err(invalid(element, format!("{len} {what} for {n} positions")));
        }
    }
    check_finite(
        element,
        "positions",
        bytemuck_vec3(&mesh.positions).as_slice(),
    )?;
    check_finite(element, "normals", bytemuck_vec3(&mesh.normals).as_slice())?;
    if let Some(t) = mesh.triangles.iter().flatten().find(|&&i| i as usize >= n) {
        return Err(invalid(
            element,
            format!("index {t} out of range for {n} vertices"),
        ));
    }
    Ok(())
}

fn bytemuck_vec3(v: &[Vec3]) -> Vec<f32> {
    v.iter().flat_map(|p| p.to_array()).collect()
}

fn interpolation_name(i: Interpolation) -> &'static str {
    match i {
        Interpolation::Step => "STEP",
        Interpolation::Linear => "LINEAR",
        Interpolation::CubicSpline => "CUBICSPLINE",
    }
}

/// Input and output accessors of a track; `flatten` turns a value into its components.
fn track_accessors<T: Copy>(
    bin: &mut Bin,
    element: &str,
    track: &Track<T>,
    components: usize,
    ty: &str,
    flatten: impl Fn(T) -> Vec<f32>,
) -> Result<(usize, usize)> {
    if track.keys.is_empty() {
        return Err(invalid(element, "track without keys"));
    }
    let times: Vec<f32> = track.keys.iter().map(|k| k.time).collect();
    check_finite(element, "key times", &times)?;
    if times.windows(2).any(|w| w[1] <= w[0]) {
        return Err(invalid(element, "key times must increase strictly"));
    }
    let mut values = Vec::new();
    for k in &track.keys {
        if track.interpolation == Interpolation::CubicSpline {
            values.extend(flatten(k.in_tangent));
            values.extend(flatten(k.value));
            values.extend(flatten(k.out_tangent));
        } else {
            values.extend(flatten(k.value));
        }
    }
    check_finite(element, "key values", &values)?;
    let input = bin.floats(&times, 1, "SCALAR", true, None);
    let output = bin.floats(&values, components, ty, false, None);
    Ok((input, output))
}

/// The glTF JSON document and its binary buffer (not yet referenced by a buffer entry).
fn document(b: &SceneBuilder) -> Result<(Map<String, Value>, Vec<u8>)> {
    let mut bin = Bin::default();
    let mut used = Vec::<String>::new();
    let images = images(b, &mut bin)?;
    let materials = super::material::materials(b, &mut used)?;
    let meshes = b
        .meshes
        .iter()
        .enumerate()
        .map(|(i, mesh)| mesh_json(b, &mut bin, i, mesh))
        .collect::<Result<Vec<_>>>()?;
    let graph = graph(b)?;
    if !graph.lights.is_empty() {
        used.push("KHR_lights_punctual".to_owned());
    }
    let (channels, anim_samplers) = animations(b, &mut bin)?;

    bin.align();
    let mut root = Map::new();
    root.insert(
        "asset".into(),
        json!({"version": "2.0", "generator": "plenoptic_scene builder"}),
    );
    root.insert("scene".into(), json!(0));
    root.insert("scenes".into(), json!([{"nodes": graph.roots}]));
    root.insert("nodes".into(), Value::Array(graph.nodes));
    let mut put = |key: &str, v: Vec<Value>| {
        if !v.is_empty() {
            root.insert(key.into(), Value::Array(v));
        }
    };
    put("meshes", meshes);
    put("materials", materials);
    put("images", images.images);
    put("textures", images.textures);
    put("samplers", images.samplers);
    put("cameras", graph.cameras);
    put("accessors", bin.accessors);
    put("bufferViews", bin.views);
    if !channels.is_empty() {
        put(
            "animations",
            vec![json!({"name": "animation", "channels": channels, "samplers": anim_samplers})],
        );
    }
    if !graph.lights.is_empty() {
        root.insert(
            "extensions".into(),
            json!({"KHR_lights_punctual": {"lights": graph.lights}}),
        );
    }
    if !used.is_empty() {
        root.insert("extensionsUsed".into(), json!(used));
    }
    Ok((root, bin.data))
}

/// The document's images, textures and samplers.
struct Images {
    images: Vec<Value>,
    textures: Vec<Value>,
    samplers: Vec<Value>,
}

/// The textures as PNG images in buffer views, each with a sampler where it does not repeat.
fn images(b: &SceneBuilder, bin: &mut Bin) -> Result<Images> {
    let mut out = Images {
        images: Vec::new(),
        textures: Vec::new(),
        samplers: Vec::new(),
    };
    for (i, t) in b.textures.iter().enumerate() {
        let element = format!("texture {i}");
        let expected = 4 * t.width as usize * t.height as usize;
        if t.width == 0 || t.height == 0 || t.rgba8.len() != expected {
            return Err(invalid(
                element,
                format!("{} bytes for {}×{} RGBA", t.rgba8.len(), t.width, t.height),
            ));
        }
        let mut png = Vec::new();
        image::ImageEncoder::write_image(
            image::codecs::png::PngEncoder::new(&mut png),
            &t.rgba8,
            t.width,
            t.height,
            image::ExtendedColorType::Rgba8,
        )
        .map_err(|e| invalid(element, format!("PNG encoding: {e}")))?;
        let view = bin.view(&png, None);
        out.images
            .push(json!({"bufferView": view, "mimeType": "image/png"}));
        if (t.wrap_s, t.wrap_t) == (WrapMode::Repeat, WrapMode::Repeat) {
            out.textures.push(json!({"source": i}));
        } else {
            out.textures
                .push(json!({"source": i, "sampler": out.samplers.len()}));
            out.samplers
                .push(json!({"wrapS": wrap_code(t.wrap_s), "wrapT": wrap_code(t.wrap_t)}));
        }
    }
    Ok(out)
}

/// Mesh `i`: its primitives' attributes and indices in the buffer.
fn mesh_json(b: &SceneBuilder, bin: &mut Bin, i: usize, mesh: &MeshDesc) -> Result<Value> {
    let mut primitives = Vec::new();
    for (k, (geometry, material)) in mesh.primitives.iter().enumerate() {
        let element = format!("mesh {i} '{}' primitive {k}", mesh.name);
        check_mesh(&element, geometry)?;
        if material.0 >= b.materials.len() {
            return Err(invalid(element, "material handle from another builder"));
        }
        let attributes = attributes(bin, &element, geometry)?;
        let indices = bin.indices(&geometry.triangles);
        primitives.push(json!({
            "attributes": attributes,
            "indices": indices,
            "material": material.0,
            "mode": 4,
        }));
    }
    let mut m = json!({"primitives": primitives});
    if !mesh.name.is_empty() {
        m["name"] = json!(mesh.name);
    }
    Ok(m)
}

/// A primitive's vertex attributes as accessors: positions (with their bounds), and the
/// normals, UVs, colours and tangents it has.
fn attributes(bin: &mut Bin, element: &str, geometry: &Mesh) -> Result<Map<String, Value>> {
    let mut attributes = Map::new();
    let mut put = |name: &str, values: &[f32], components: usize, ty: &str, min_max: bool| {
        let a = bin.floats(values, components, ty, min_max, Some(ARRAY_BUFFER));
        attributes.insert(name.into(), json!(a));
    };
    let positions = bytemuck_vec3(&geometry.positions);
    put("POSITION", &positions, 3, "VEC3", true);
    if !geometry.normals.is_empty() {
        let normals = bytemuck_vec3(&geometry.normals);
        put("NORMAL", &normals, 3, "VEC3", false);
    }
    if !geometry.uvs.is_empty() {
        let uv: Vec<f32> = geometry.uvs.iter().flat_map(|v| v.to_array()).collect();
        check_finite(element, "uvs", &uv)?;
        put("TEXCOORD_0", &uv, 2, "VEC2", false);
    }
    if !geometry.colors.is_empty() {
        let c: Vec<f32> = geometry.colors.iter().flat_map(|v| v.to_array()).collect();
        if let Some(i) = c.iter().position(|v| !(0.0..=1.0).contains(v)) {
            return Err(invalid(
                element,
                format!("colors: component {i} is {} outside [0, 1]", c[i]),
            ));
        }
        put("COLOR_0", &c, 4, "VEC4", false);
    }
    if !geometry.tangents.is_empty() {
        let t: Vec<f32> = geometry
            .tangents
            .iter()
            .flat_map(|v| v.to_array())
            .collect();
        check_finite(element, "tangents", &t)?;
        put("TANGENT", &t, 4, "VEC4", false);
    }
    Ok(attributes)
}

/// The node graph: the nodes, the roots, and the lights and cameras the nodes refer to.
struct Graph {
    nodes: Vec<Value>,
    roots: Vec<usize>,
    lights: Vec<Value>,
    cameras: Vec<Value>,
}

/// The nodes with their transforms, meshes, lights, cameras and children.
fn graph(b: &SceneBuilder) -> Result<Graph> {
    let mut g = Graph {
        nodes: Vec::new(),
        roots: Vec::new(),
        lights: Vec::new(),
        cameras: Vec::new(),
    };
    for (i, n) in b.nodes.iter().enumerate() {
        let element = format!("node {i} '{}'", n.name);
        let mut node = node_transform(&element, n)?;
        if let Some(mesh) = n.mesh {
            if mesh.0 >= b.meshes.len() {
                return Err(invalid(element, "mesh handle from another builder"));
            }
            node["mesh"] = json!(mesh.0);
        }
        if let Some(l) = &n.light {
            node["extensions"] = json!({"KHR_lights_punctual": {"light": g.lights.len()}});
            g.lights.push(light_json(l));
        }
        if let Some(c) = &n.camera {
            node["camera"] = json!(g.cameras.len());
            g.cameras.push(camera_json(c));
        }
        match n.parent {
            None => g.roots.push(i),
            Some(p) if p.0 < i => {
                let children = g.nodes[p.0]
                    .as_object_mut()
                    .expect("nodes are objects")
                    .entry("children")
                    .or_insert_with(|| json!([]));
                children
                    .as_array_mut()
                    .expect("children is an array")
                    .push(json!(i));
            }
            Some(p) => {
                return Err(invalid(
                    element,
                    format!("parent {} must be added before the child", p.0),
                ));
            }
        }
        g.nodes.push(node);
    }
    Ok(g)
}

/// A node's name and transform: a matrix where the node asks for one, else translation,
/// rotation and scale.
fn node_transform(element: &str, n: &NodeDesc) -> Result<Value> {
    let t = n.transform;
    check_finite(
        element,
        "transform",
        &[
            t.translation.x,
            t.translation.y,
            t.translation.z,
            t.rotation.x,
            t.rotation.y,
            t.rotation.z,
            t.rotation.w,
            t.scale.x,
            t.scale.y,
            t.scale.z,
        ],
    )?;
    let mut node = json!({"name": n.name});
    if n.write_matrix {
        let m =
            Mat4::from_scale_rotation_translation(t.scale, t.rotation.normalize(), t.translation);
        node["matrix"] = json!(m.to_cols_array());
    } else {
        node["translation"] = json!(t.translation.to_array());
        node["rotation"] = json!(t.rotation.normalize().to_array());
        node["scale"] = json!(t.scale.to_array());
    }
    Ok(node)
}

/// A `KHR_lights_punctual` light.
fn light_json(l: &LightDesc) -> Value {
    let mut light = json!({
        "color": l.color.to_array(),
        "intensity": l.intensity,
    });
    if !l.name.is_empty() {
        light["name"] = json!(l.name);
    }
    match l.kind {
        LightKind::Point => light["type"] = json!("point"),
        LightKind::Directional => light["type"] = json!("directional"),
        LightKind::Spot {
            inner_cone_angle,
            outer_cone_angle,
        } => {
            light["type"] = json!("spot");
            light["spot"] = json!({
                "innerConeAngle": inner_cone_angle,
                "outerConeAngle": outer_cone_angle,
            });
        }
    }
    if let Some(range) = l.range {
        light["range"] = json!(range);
    }
    light
}

/// A perspective camera.
fn camera_json(c: &CameraDesc) -> Value {
    let mut p = json!({"yfov": c.yfov, "znear": c.znear});
    if let Some(a) = c.aspect_ratio {
        p["aspectRatio"] = json!(a);
    }
    if let Some(f) = c.zfar {
        p["zfar"] = json!(f);
    }
    let mut camera = json!({"type": "perspective", "perspective": p});
    if !c.name.is_empty() {
        camera["name"] = json!(c.name);
    }
    camera
}

/// The animation's channels and samplers: one per track, its keys in the buffer.
fn animations(b: &SceneBuilder, bin: &mut Bin) -> Result<(Vec<Value>, Vec<Value>)> {
    let mut channels = Vec::new();
    let mut samplers = Vec::new();
    for (k, (node, track)) in b.tracks.iter().enumerate() {
        let element = format!("track {k} (node {})", node.0);
        if node.0 >= b.nodes.len() {
            return Err(invalid(element, "node handle from another builder"));
        }
        let (path, interpolation, (input, output)) = match track {
            TrackDesc::Translation(t) => (
                "translation",
                t.interpolation,
                track_accessors(bin, &element, t, 3, "VEC3", |v| v.to_array().to_vec())?,
            ),
            TrackDesc::Scale(t) => (
                "scale",
                t.interpolation,
                track_accessors(bin, &element, t, 3, "VEC3", |v| v.to_array().to_vec())?,
            ),
            TrackDesc::Rotation(t) => (
                "rotation",
                t.interpolation,
                track_accessors(bin, &element, t, 4, "VEC4", |v| v.to_array().to_vec())?,
            ),
        };
        channels.push(json!({"sampler": samplers.len(), "target": {"node": node.0, "path": path}}));
        samplers.push(json!({
            "input": input,
            "output": output,
            "interpolation": interpolation_name(interpolation),
        }));
    }
    Ok((channels, samplers))
}

/// Binary glTF: 12-byte header, JSON chunk padded with spaces, BIN chunk padded with zeros.
pub(super) fn to_glb(b: &SceneBuilder) -> Result<Vec<u8>> {
    let (mut root, data) = document(b)?;
    if !data.is_empty() {
        root.insert("buffers".into(), json!([{"byteLength": data.len()}]));
    }
    let mut json =
        serde_json::to_vec(&Value::Object(root)).map_err(|e| invalid("document", e.to_string()))?;
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let bin_chunk = if data.is_empty() { 0 } else { 8 + data.len() };
    let total = 12 + 8 + json.len() + bin_chunk;
    let total32 = u32::try_from(total).map_err(|_| invalid("document", "larger than 4 GiB"))?;
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&total32.to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    if !data.is_empty() {
        out.extend_from_slice(&(data.len() as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(&data);
    }
    Ok(out)
}

/// glTF JSON with the buffer embedded as a base64 `data:` URI.
pub(super) fn to_gltf(b: &SceneBuilder) -> Result<String> {
    let (mut root, data) = document(b)?;
    if !data.is_empty() {
        let uri = format!(
            "data:application/octet-stream;base64,{}",
            crate::util::base64_encode(&data)
        );
        root.insert(
            "buffers".into(),
            json!([{"byteLength": data.len(), "uri": uri}]),
        );
    }
    serde_json::to_string_pretty(&Value::Object(root))
        .map_err(|e| invalid("document", e.to_string()))
}
