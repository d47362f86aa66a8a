//! Primitives to [`Mesh`]es: positions, indices, normals and tangents (computed where
//! missing), texture coordinates and `COLOR_0` vertex colours.

use glam::{Vec2, Vec3, Vec4};
use gltf::Semantic;
use gltf::accessor::Dimensions;

use super::data::Data;
use crate::error::Result;
use crate::model::Mesh;

/// Reads one triangle primitive. `label` names it in errors (`mesh 2 primitive 0`).
pub(super) fn read_primitive(
    data: &Data,
    primitive: &gltf::Primitive,
    label: &str,
    needs_tangents: bool,
) -> Result<Mesh> {
    let positions_accessor = primitive
        .get(&Semantic::Positions)
        .ok_or_else(|| data.err(label, "has no POSITION attribute"))?;
    let positions =
        to_vec3(&data.read_floats(&positions_accessor, Dimensions::Vec3, false, "POSITION")?);
    let n = positions.len();
    let same_count = |accessor: &gltf::Accessor, what: &str| {
        if accessor.count() == n {
            Ok(())
        } else {
            Err(data.err(
                format!("accessor {}", accessor.index()),
                format!("{what} has {} elements for {n} positions", accessor.count()),
            ))
        }
    };

    let triangles = match primitive.indices() {
        Some(accessor) => {
            let indices = data.read_indices(&accessor)?;
            let element = format!("accessor {}", accessor.index());
            if !indices.len().is_multiple_of(3) {
                return Err(data.err(
                    element,
                    format!("{} indices is not a multiple of 3", indices.len()),
                ));
            }
            if let Some(bad) = indices.iter().find(|&&i| i as usize >= n) {
                return Err(data.err(
                    element,
                    format!("index {bad} out of range for {n} vertices"),
                ));
            }
            indices
                .chunks_exact(3)
                .map(|t| [t[0], t[1], t[2]])
                .collect()
        }
        None => {
            if !n.is_multiple_of(3) {
                return Err(data.err(
                    label,
                    format!("{n} non-indexed vertices is not a multiple of 3"),
                ));
            }
            let n = u32::try_from(n).map_err(|_| data.err(label, "too many vertices"))?;
            (0..n / 3).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect()
        }
    };

    let mut mesh = Mesh {
        positions,
        triangles,
        ..Mesh::default()
    };
    match primitive.get(&Semantic::Normals) {
        Some(accessor) => {
            same_count(&accessor, "NORMAL")?;
            let normals =
                to_vec3(&data.read_floats(&accessor, Dimensions::Vec3, false, "NORMAL")?);
            mesh.normals = normals
                .into_iter()
                .map(|v| v.normalize_or(Vec3::Z))
                .collect();
        }
        None => mesh.normals = area_weighted_normals(&mesh),
    }
    if let Some(accessor) = primitive.get(&Semantic::TexCoords(0)) {
        same_count(&accessor, "TEXCOORD_0")?;
        let uv = data.read_floats(&accessor, Dimensions::Vec2, true, "TEXCOORD_0")?;
        mesh.uvs = uv.chunks_exact(2).map(|c| Vec2::new(c[0], c[1])).collect();
    }
    if let Some(accessor) = primitive.get(&Semantic::Colors(0)) {
        same_count(&accessor, "COLOR_0")?;
        mesh.colors = read_colors(data, &accessor)?;
    }
    if let Some(accessor) = primitive.get(&Semantic::Tangents) {
        same_count(&accessor, "TANGENT")?;
        let t = data.read_floats(&accessor, Dimensions::Vec4, false, "TANGENT")?;
        mesh.tangents = t
            .chunks_exact(4)
            .map(|c| {
                let xyz = Vec3::new(c[0], c[1], c[2]).normalize_or(Vec3::X);
                xyz.extend(if c[3] < 0.0 { -1.0 } else { 1.0 })
            })
            .collect();
    } else if needs_tangents && !mesh.uvs.is_empty() {
        mesh.tangents = uv_tangents(&mesh);
    }
    Ok(mesh)
}

/// `COLOR_0`: VEC3 or VEC4 of floats or normalised unsigned bytes/shorts (glTF 2.0 §3.7.2.1),
/// as linear RGBA (alpha 1 for VEC3). Float values must lie in [0, 1] as the specification
/// requires; anything else is an error naming the accessor.
fn read_colors(data: &Data, accessor: &gltf::Accessor) -> Result<Vec<Vec4>> {
    use gltf::accessor::DataType;
    let element = format!("accessor {}", accessor.index());
    let dims = accessor.dimensions();
    let components = match dims {
        Dimensions::Vec3 => 3,
        Dimensions::Vec4 => 4,
        other => {
            return Err(data.err(
                element,
                format!("COLOR_0 must be Vec3 or Vec4, found {other:?}"),
            ));
        }
    };
    let ty = accessor.data_type();
    if !(ty == DataType::F32
        || (matches!(ty, DataType::U8 | DataType::U16) && accessor.normalized()))
    {
        return Err(data.err(
            element,
            format!(
                "COLOR_0 must be float or normalized unsigned byte/short, found {ty:?}{}",
                if accessor.normalized() {
                    " (normalized)"
                } else {
                    ""
                }
            ),
        ));
    }
    let values = data.read_floats(accessor, dims, true, "COLOR_0")?;
    if let Some(i) = values.iter().position(|v| !(0.0..=1.0).contains(v)) {
        return Err(data.err(
            element,
            format!(
                "COLOR_0: value {} at element {} outside [0, 1]",
                values[i],
                i / components
            ),
        ));
    }
    Ok(values
        .chunks_exact(components)
        .map(|c| Vec4::new(c[0], c[1], c[2], c.get(3).copied().unwrap_or(1.0)))
        .collect())
}

fn to_vec3(v: &[f32]) -> Vec<Vec3> {
    v.chunks_exact(3).map(Vec3::from_slice).collect()
}

/// Vertex normals as the sum of the adjacent faces' (area-weighted) normals.
pub(crate) fn area_weighted_normals(mesh: &Mesh) -> Vec<Vec3> {
    let mut normals = vec![Vec3::ZERO; mesh.positions.len()];
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
        let n = (b - a).cross(c - a);
        for &i in t {
            normals[i as usize] += n;
        }
    }
    normals
        .into_iter()
        .map(|n| n.normalize_or(Vec3::Z))
        .collect()
}

/// Tangents from UV gradients (Lengyel's method), orthogonalised against the normal, with the
/// bitangent's handedness in w.
pub(crate) fn uv_tangents(mesh: &Mesh) -> Vec<Vec4> {
    let mut tan = vec![Vec3::ZERO; mesh.positions.len()];
    let mut bitan = vec![Vec3::ZERO; mesh.positions.len()];
    for t in &mesh.triangles {
        let [i0, i1, i2] = t.map(|i| i as usize);
        let (e1, e2) = (
            mesh.positions[i1] - mesh.positions[i0],
            mesh.positions[i2] - mesh.positions[i0],
        );
        let (d1, d2) = (mesh.uvs[i1] - mesh.uvs[i0], mesh.uvs[i2] - mesh.uvs[i0]);
        let r = d1.x * d2.y - d2.x * d1.y;
        if r.abs() < 1e-20 {
            continue;
        }
        let s = (e1 * d2.y - e2 * d1.y) / r;
        let b = (e2 * d1.x - e1 * d2.x) / r;
        for i in [i0, i1, i2] {
            tan[i] += s;
            bitan[i] += b;
        }
    }
    mesh.normals
        .iter()
        .zip(tan.iter().zip(&bitan))
        .map(|(&n, (&t, &b))| {
            let t = (t - n * n.dot(t)).normalize_or(n.any_orthonormal_vector());
            let w = if n.cross(t).dot(b) < 0.0 { -1.0 } else { 1.0 };
            t.extend(w)
        })
        .collect()
}

/// The sRGB transfer function's inverse.
pub(crate) fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}
