//! The `.pack` asset loader.

use std::io::Cursor;
use std::path::PathBuf;
use std::sync::Arc;

use bevy::asset::io::Reader;
use bevy::asset::{AssetLoader, LoadContext, RenderAssetUsages};
use bevy::mesh::PrimitiveTopology;
use bevy::prelude::*;
use plenoptic_pack::{PackError, PackReader};

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
        // The environment (its image chunk, if any, is read now: every frame needs it).
        let (environment, env_error) =
            plenoptic_recon::background::PackEnvironment::from_pack(&pack);
        failed.extend(env_error.map(|e| ("environment".to_string(), e)));
        let mut proxies = Vec::new();
        for proxy in read {
            let mesh = proxy_to_mesh(&proxy.mesh);
            let handle = load_context.add_labeled_asset(format!("proxy{}", proxy.id), mesh);
            proxies.push(ProxyObject {
                id: proxy.id,
                name: proxy.name,
                mesh: handle,
                track: proxy.track,
            });
        }
        let usable_views = super::usable_views(&pack);
        Ok(RadiancePack {
            reader: Arc::new(pack),
            proxies,
            failed,
            file,
            usable_views,
            environment,
        })
    }

    fn extensions(&self) -> &[&str] {
        &["pack"]
    }
}

/// A proxy mesh as a flat-shaded Bevy triangle mesh (vertices duplicated per face).
pub fn proxy_to_mesh(proxy: &plenoptic_pack::ProxyMesh) -> Mesh {
    let positions: Vec<[f32; 3]> = proxy
        .indices
        .iter()
        .filter_map(|&i| proxy.positions.get(i as usize))
        .map(|p| p.to_array())
        .collect();
    let n = positions.len() / 3 * 3;
    let mut mesh = Mesh::new(
        PrimitiveTopology::TriangleList,
        RenderAssetUsages::default(),
    )
    .with_inserted_attribute(Mesh::ATTRIBUTE_POSITION, positions[..n].to_vec());
    mesh.compute_flat_normals();
    mesh
}
