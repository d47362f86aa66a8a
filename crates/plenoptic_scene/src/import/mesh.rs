//! Primitives to [`Mesh`]es (with normals and tangents computed where missing) and glTF
//! materials to [`Material`]s with decoded textures.

use std::collections::HashMap;

use glam::{Vec2, Vec3, Vec4};
use gltf::Semantic;
use gltf::accessor::Dimensions;

use super::data::Data;
use crate::error::Result;
use crate::model::{Material, Mesh, Texture, TextureRef};

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

/// Materials and their decoded textures, each texture decoded once per colour space.
#[derive(Default)]
pub(super) struct Materials {
    pub(super) textures: Vec<Texture>,
    cache: HashMap<(usize, bool), usize>,
}

impl Materials {
    /// Converts a glTF material; `warnings` collects unsupported texture coordinate sets.
    pub(super) fn convert(
        &mut self,
        data: &Data,
        material: &gltf::Material,
        warnings: &mut Vec<String>,
    ) -> Result<Material> {
        let label = match material.index() {
            Some(i) => format!("material {i}"),
            None => "default material".to_owned(),
        };
        let pbr = material.pbr_metallic_roughness();
        let strength = material.emissive_strength().unwrap_or(1.0);
        let factors = [pbr.metallic_factor(), pbr.roughness_factor(), strength];
        if factors
            .iter()
            .chain(&pbr.base_color_factor())
            .chain(&material.emissive_factor())
            .any(|v| !v.is_finite())
        {
            return Err(data.err(label, "non-finite factor"));
        }
        let mut texture = |info: Option<(gltf::Texture, u32)>,
                           srgb: bool,
                           what: &str|
         -> Result<Option<TextureRef>> {
            let Some((tex, set)) = info else {
                return Ok(None);
            };
            if set != 0 {
                warnings.push(format!(
                    "{label}: {what} uses TEXCOORD_{set}; only set 0 is imported"
                ));
            }
            Ok(Some(self.texture(data, &tex, srgb)?))
        };
        let base_color_texture = texture(
            pbr.base_color_texture()
                .map(|i| (i.texture(), i.tex_coord())),
            true,
            "base colour texture",
        )?;
        let metallic_roughness_texture = texture(
            pbr.metallic_roughness_texture()
                .map(|i| (i.texture(), i.tex_coord())),
            false,
            "metallic-roughness texture",
        )?;
        let emissive_texture = texture(
            material
                .emissive_texture()
                .map(|i| (i.texture(), i.tex_coord())),
            true,
            "emissive texture",
        )?;
        let normal = material.normal_texture();
        let normal_scale = normal.as_ref().map_or(1.0, |n| n.scale());
        let normal_texture = texture(
            normal.map(|n| (n.texture(), n.tex_coord())),
            false,
            "normal texture",
        )?;
        let base = pbr.base_color_factor();
        Ok(Material {
            name: material.name().unwrap_or_default().to_owned(),
            base_color: Vec4::from_array(base),
            base_color_texture,
            metallic: pbr.metallic_factor(),
            roughness: pbr.roughness_factor(),
            metallic_roughness_texture,
            emissive: Vec3::from_array(material.emissive_factor()) * strength,
            emissive_texture,
            normal_texture,
            normal_scale,
            transmission: material
                .transmission()
                .map_or(0.0, |t| t.transmission_factor()),
            ior: material.ior().unwrap_or(1.5),
            double_sided: material.double_sided(),
        })
    }

    fn texture(&mut self, data: &Data, texture: &gltf::Texture, srgb: bool) -> Result<TextureRef> {
        let image = texture.source();
        let key = (image.index(), srgb);
        if let Some(&index) = self.cache.get(&key) {
            return Ok(TextureRef { texture: index });
        }
        let element = format!("image {}", image.index());
        let bytes = match image.source() {
            gltf::image::Source::View { view, .. } => data.view_bytes(&view)?.to_vec(),
            gltf::image::Source::Uri { uri, .. } => data.resolve_uri(&element, uri)?,
        };
        let decoded = image::load_from_memory(&bytes)
            .map_err(|e| data.err(&element, format!("cannot decode: {e}")))?;
        let rgba = decoded.to_rgba32f();
        let (width, height) = rgba.dimensions();
        let texels = rgba
            .pixels()
            .map(|p| {
                let [r, g, b, a] = p.0;
                if srgb {
                    Vec4::new(srgb_to_linear(r), srgb_to_linear(g), srgb_to_linear(b), a)
                } else {
                    Vec4::new(r, g, b, a)
                }
            })
            .collect();
        self.textures.push(Texture {
            width,
            height,
            texels,
        });
        let index = self.textures.len() - 1;
        self.cache.insert(key, index);
        Ok(TextureRef { texture: index })
    }
}

/// The sRGB transfer function's inverse.
pub(crate) fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}
