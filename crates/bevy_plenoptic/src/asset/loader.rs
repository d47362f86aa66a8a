//! The `.pack` asset loader.

use std::io::Cursor;
use std::path::PathBuf;
use std::sync::Arc;

use bevy::asset::io::Reader;
use bevy::asset::{AssetLoader, LoadContext, RenderAssetUsages};
use bevy::mesh::PrimitiveTopology;
use bevy::prelude::*;
use plenoptic_pack::{PackError, PackReader};
use plenoptic_recon::flat_rays::FlatRays;

use super::{ProxyObject, RadiancePack};

/// Loads `.pack` files as [`RadiancePack`]s.
#[derive(TypePath, Debug, Clone, Default)]
pub struct RadiancePackLoader {
    /// The file-system directory assets are read from (the `AssetPlugin`'s `file_path`
    /// resolved against the base path), used to open packs for random access. `None`: the
    /// whole file is read through Bevy's reader instead.
    pub asset_root: Option<PathBuf>,
}

/// Why a pack could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum RadiancePackLoaderError {
    /// The pack's header, manifest or directory is invalid, or a read failed; the message
    /// names the section or chunk.
    #[error("radiance pack {path}: {source}")]
    Pack {
        /// The asset path.
        path: String,
        /// The pack error.
        source: PackError,
    },
    /// Reading the asset's bytes failed.
    #[error("radiance pack {path}: {source}")]
    Io {
        /// The asset path.
        path: String,
        /// The I/O error.
        source: std::io::Error,
    },
}

impl AssetLoader for RadiancePackLoader {
    type Asset = RadiancePack;
    type Settings = ();
    type Error = RadiancePackLoaderError;

    async fn load(
        &self,
        reader: &mut dyn Reader,
        _settings: &(),
        load_context: &mut LoadContext<'_>,
    ) -> Result<RadiancePack, Self::Error> {
        let name = load_context.path().to_string();
        let file = self
            .asset_root
            .as_ref()
            .map(|root| root.join(load_context.path().path()))
            .filter(|p| p.is_file());
        let pack = match &file {
            // Random access: only header, manifest and directory are read now.
            Some(path) => PackReader::open(path),
            None => {
                let mut bytes = Vec::new();
                reader.read_to_end(&mut bytes).await.map_err(|source| {
                    RadiancePackLoaderError::Io {
                        path: name.clone(),
                        source,
                    }
                })?;
                PackReader::from_reader(Cursor::new(bytes))
            }
        }
        .map_err(|source| RadiancePackLoaderError::Pack {
            path: name.clone(),
            source,
        })?;

        let (read, mut failed) = plenoptic_recon::proxy::read_proxies(&pack);
        // What reflected rays are cast against (the CPU's escape test, on the GPU), with the
        // glazing in BVHs of its own for the runtime sun.
        let glazing: Vec<(u32, f32)> = (pack.manifest().objects.iter())
            .filter_map(|o| Some((o.id, o.coverage?)))
            .collect();
        let rays = plenoptic_recon::ProxyGeometry::from_proxies(&read)
            .map_or_else(FlatRays::none, |g| {
                FlatRays::with_see_through(&g, glazing.iter().copied())
            });
        // The environment (its image chunk, if any, is read now: every frame needs it).
        let (environment, env_error) =
            plenoptic_recon::background::PackEnvironment::from_pack(&pack);
        failed.extend(env_error.map(|e| ("environment".to_string(), e)));
        let mut proxies = Vec::new();
        for proxy in read {
            // The proxy's UVs and tangents (pack 1.2+), for the material textures.
            let (uvs, tangents) = match pack.proxy_attributes(proxy.id) {
                Ok(a) => a.map(|a| (a.uvs, a.tangents)).unwrap_or_default(),
                Err(e) => {
                    failed.push((format!("UVs of object {}", proxy.id), e.to_string()));
                    Default::default()
                }
            };
            let mesh = proxy_to_mesh(&proxy.mesh, &uvs, &tangents);
            let handle = load_context.add_labeled_asset(format!("proxy{}", proxy.id), mesh);
            proxies.push(ProxyObject {
                id: proxy.id,
                name: proxy.name,
                mesh: handle,
                track: proxy.track,
            });
        }
        let usable_views = super::usable_views(&pack);
        // The material textures, as Bevy loads KTX2 (base colour and emissive sRGB).
        let mut textures = Vec::new();
        for (i, entry) in pack.textures().iter().enumerate() {
            let image = pack
                .texture_ktx2(i as u32)
                .map_err(|e| e.to_string())
                .and_then(|bytes| {
                    Image::from_buffer(
                        &bytes,
                        bevy::image::ImageType::Extension("ktx2"),
                        bevy::image::CompressedImageFormats::NONE,
                        entry.colour_space.is_srgb(),
                        texture_sampler(&pack, i as u32),
                        RenderAssetUsages::RENDER_WORLD,
                    )
                    .map_err(|e| e.to_string())
                });
            textures.push(match image {
                Ok(image) => Some(load_context.add_labeled_asset(format!("texture{i}"), image)),
                Err(e) => {
                    failed.push((format!("material texture {i}"), e));
                    None
                }
            });
        }
        Ok(RadiancePack {
            textures,
            reader: Arc::new(pack),
            proxies,
            failed,
            file,
            usable_views,
            environment,
            rays: Arc::new(rays),
        })
    }

    fn extensions(&self) -> &[&str] {
        &["pack"]
    }
}

/// The sampler of pack texture `index`: trilinear, wrapping as the first material binding
/// that uses it says (`plenoptic_recon` wraps per binding; two bindings of one texture with
/// different wrap modes get the first one's here).
fn texture_sampler(pack: &PackReader, index: u32) -> bevy::image::ImageSampler {
    use bevy::image::{ImageAddressMode, ImageFilterMode, ImageSampler, ImageSamplerDescriptor};
    use plenoptic_pack::WrapMode;
    let binding = pack.materials().iter().find_map(|m| {
        [m.base_colour_texture, m.metallic_roughness_texture]
            .into_iter()
            .flatten()
            .find(|b| b.texture == index)
    });
    let mode = |w: WrapMode| match w {
        WrapMode::Repeat => ImageAddressMode::Repeat,
        WrapMode::ClampToEdge => ImageAddressMode::ClampToEdge,
        WrapMode::MirroredRepeat => ImageAddressMode::MirrorRepeat,
    };
    let (s, t) = binding.map_or((WrapMode::Repeat, WrapMode::Repeat), |b| {
        (b.wrap_s, b.wrap_t)
    });
    ImageSampler::Descriptor(ImageSamplerDescriptor {
        address_mode_u: mode(s),
        address_mode_v: mode(t),
        mag_filter: ImageFilterMode::Linear,
        min_filter: ImageFilterMode::Linear,
        mipmap_filter: ImageFilterMode::Linear,
        ..default()
    })
}

/// A proxy mesh as a Bevy triangle mesh (vertices duplicated per face), with the pack's vertex
/// normals where it has one per vertex (flat normals otherwise), TEXCOORD_0 when `uvs` has one per proxy vertex and TANGENT when `tangents` has (each
/// corner's w the bitangent sign of its triangle's first vertex, as `plenoptic_recon` and the
/// path tracer take it). Triangles with an index outside the positions are dropped whole, as
/// `plenoptic_recon` drops them.
pub fn proxy_to_mesh(proxy: &plenoptic_pack::ProxyMesh, uvs: &[Vec2], tangents: &[Vec4]) -> Mesh {
    let n = proxy.positions.len();
    let corners: Vec<usize> = proxy
        .indices
        .chunks_exact(3)
        .filter(|t| t.iter().all(|&i| (i as usize) < n))
        .flatten()
        .map(|&i| i as usize)
        .collect();
    let positions: Vec<[f32; 3]> = corners
        .iter()
        .map(|&i| proxy.positions[i].to_array())
        .collect();
    let mut mesh = Mesh::new(
        PrimitiveTopology::TriangleList,
        RenderAssetUsages::default(),
    )
    .with_inserted_attribute(Mesh::ATTRIBUTE_POSITION, positions);
    if uvs.len() == n && n > 0 {
        let uv: Vec<[f32; 2]> = corners.iter().map(|&i| uvs[i].to_array()).collect();
        mesh.insert_attribute(Mesh::ATTRIBUTE_UV_0, uv);
    }
    if tangents.len() == n && n > 0 {
        let t: Vec<[f32; 4]> = corners
            .chunks_exact(3)
            .flat_map(|tri| {
                let sign = if tangents[tri[0]].w < 0.0 { -1.0 } else { 1.0 };
                tri.iter()
                    .map(move |&i| tangents[i].truncate().extend(sign).to_array())
            })
            .collect();
        mesh.insert_attribute(Mesh::ATTRIBUTE_TANGENT, t);
    }
    // The pack's vertex normals where it has them (curved surfaces shade smoothly, as on the
    // CPU, which interpolates them); the triangles' own normals elsewhere.
    match proxy.normals.as_deref() {
        Some(normals) if normals.len() == n && n > 0 => {
            let normals: Vec<[f32; 3]> = corners.iter().map(|&i| normals[i].to_array()).collect();
            mesh.insert_attribute(Mesh::ATTRIBUTE_NORMAL, normals);
        }
        _ => mesh.compute_flat_normals(),
    }
    mesh
}
