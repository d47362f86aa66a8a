//! Uploads of newly resident keys into a pack's key texture, layer range by layer range.
//!
//! The key texture ([`KeyTexture`]) exists only on the GPU: its `Image` asset has no texel data
//! (render world only), so Bevy creates the texture once and never re-uploads it. When a key
//! becomes resident, its six faces are interleaved into the texture's `Rgba32Uint` layout in
//! the main world and queued ([`KeyUploads`]); the render world takes the queue at extraction
//! and writes each key into its slot's six layers with `RenderQueue::write_texture`, before the
//! frame's passes. A key evicted from a slot is simply overwritten by the slot's next key.

use std::collections::{HashMap, HashSet};

use bevy::asset::RenderAssetUsages;
use bevy::image::ImageSampler;
use bevy::prelude::*;
use bevy::render::render_asset::RenderAssets;
use bevy::render::render_resource::{
    BufferDescriptor, BufferUsages, Extent3d, Origin3d, TexelCopyBufferLayout,
    TexelCopyTextureInfo, TextureAspect, TextureDimension, TextureFormat,
};
use bevy::render::renderer::{RenderDevice, RenderQueue};
use bevy::render::texture::GpuImage;
use bevy::render::{MainWorld, Render, RenderApp, RenderSystems};

use super::relight::{GROUP_TEXEL_BYTES, GroupLayers, MAX_GROUP_BUFFER, stored_groups};
use super::{KeyTexture, KeyTextures, MAX_LAYERS};
use crate::asset::RadiancePack;
use crate::camera::PlenopticCamera;
use crate::settings::PlenopticSettings;
use crate::streaming::{DecodedKey, StreamCache, key_bytes};

/// Bytes per texel of the key texture (`Rgba32Uint`).
const TEXEL_BYTES: usize = 16;
/// Bytes per texel of the shading texture (`Rg32Uint`: lighting, non-diffuse radiance).
const SHADING_BYTES: usize = 8;

/// One key's texels, interleaved, waiting to be written into its slot.
#[derive(Debug, Clone)]
pub struct KeyUpload {
    /// The key texture.
    pub image: AssetId<Image>,
    /// First array layer (6 × slot).
    pub first_layer: u32,
    /// Face size.
    pub face: u32,
    /// Six faces of `face`² texels of 16 bytes (`Rgba32Uint`).
    pub data: Vec<u8>,
    /// The pack's shading texture ([`KeyTexture::shading`]).
    pub shading_image: AssetId<Image>,
    /// Six faces of `face`² texels of 8 bytes (`Rg32Uint`).
    pub shading_data: Vec<u8>,
    /// The pack, whose [`GroupLayers`] buffer holds the key's group layers.
    pub pack: AssetId<RadiancePack>,
    /// The key's light-group layers ([`interleave_groups`]; empty for a pack without them),
    /// written at `slot ·` its length in a buffer of `slots ·` its length.
    pub group_data: Vec<u8>,
    /// The key's slot and the texture's slots.
    pub slot: u32,
    /// Slots of the pack's key texture.
    pub slots: u32,
}

/// Key uploads queued this frame (main world; taken by the render world at extraction).
#[derive(Resource, Debug, Default)]
pub struct KeyUploads(pub Vec<KeyUpload>);

/// Key uploads taken from the main world, written once their texture exists on the GPU.
#[derive(Resource, Debug, Default)]
struct PendingKeyUploads(Vec<KeyUpload>);

/// Statistics of the key uploads (render world figures, mirrored for tests and tools).
#[derive(Resource, Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct KeyUploadStats {
    /// Keys queued for upload.
    pub keys: u64,
    /// Bytes queued for upload (only the keys' own layers).
    pub bytes: u64,
}

/// Adds the queue and the render-world writer.
pub(super) fn build(app: &mut App) {
    app.init_resource::<KeyUploads>()
        .init_resource::<KeyUploadStats>();
    if let Some(render_app) = app.get_sub_app_mut(RenderApp) {
        render_app
            .init_resource::<PendingKeyUploads>()
            .init_resource::<GroupLayers>()
            .add_systems(ExtractSchedule, extract_key_uploads)
            .add_systems(
                Render,
                write_key_uploads.in_set(RenderSystems::PrepareResources),
            );
    }
}

/// Creates each shown pack's key texture and queues newly resident keys for upload into their
/// slot's layers.
#[expect(clippy::too_many_arguments, reason = "a Bevy system's parameters")]
pub(super) fn upload_keys(
    mut keys: ResMut<KeyTextures>,
    mut uploads: ResMut<KeyUploads>,
    mut stats: ResMut<KeyUploadStats>,
    cache: Res<StreamCache>,
    settings: Res<PlenopticSettings>,
    packs: Res<Assets<RadiancePack>>,
    cameras: Query<&PlenopticCamera>,
    mut images: ResMut<Assets<Image>>,
) {
    for cam in &cameras {
        let id = cam.pack.id();
        let Some(pack) = packs.get(id) else { continue };
        let tex = keys.0.entry(id).or_insert_with(|| {
            let face = pack.reader.manifest().bake.cube_face_size.max(1);
            let per_key = key_bytes(&pack.reader, (0, 0)).max(1);
            let groups = u64::from(stored_groups(pack.reader.manifest()));
            let per_slot_groups = groups * 6 * u64::from(face).pow(2) * GROUP_TEXEL_BYTES;
            let most = (MAX_LAYERS / 6) as u64;
            let most = most.min(MAX_GROUP_BUFFER / per_slot_groups.max(1));
            let slots = (settings.memory_budget_bytes / per_key).clamp(1, most.max(1)) as u32;
            let texture = |format| {
                let mut image = Image::new_uninit(
                    Extent3d {
                        width: face,
                        height: face,
                        depth_or_array_layers: 6 * slots,
                    },
                    TextureDimension::D2,
                    format,
                    // GPU only: keys are written into it in place (wgpu zero-initialises it).
                    RenderAssetUsages::RENDER_WORLD,
                );
                image.texture_view_descriptor = None;
                // Integer texels are gathered, never filtered (geometry/lookup.wgsl).
                image.sampler = ImageSampler::nearest();
                image
            };
            KeyTexture {
                image: images.add(texture(TextureFormat::Rgba32Uint)),
                shading: images.add(texture(TextureFormat::Rg32Uint)),
                face,
                slots,
                uploaded: HashMap::new(),
                normals: HashSet::new(),
            }
        });
        let mut fresh: Vec<_> = cache
            .resident
            .iter()
            .filter(|((p, v, k), r)| {
                *p == id && r.slot < tex.slots && tex.uploaded.get(&r.slot) != Some(&(*v, *k))
            })
            .map(|((_, v, k), r)| ((*v, *k), r.clone()))
            .collect();
        fresh.sort_by_key(|f| f.1.slot);
        for (vk, r) in fresh {
            let Some((data, shading_data, normals)) = interleave(&r.data, tex.face) else {
                warn_once!(
                    "plenoptic: GPU reconstruction needs RGB9E5 radiance, R32F distance and \
                     R32Uint ids at face size {}; key {vk:?} not shown",
                    tex.face
                );
                continue;
            };
            let Some(group_data) = interleave_groups(&r.data, tex.face) else {
                warn_once!(
                    "plenoptic: GPU light groups need RGB9E5 layers at face size {}; key {vk:?} \
                     not shown",
                    tex.face
                );
                continue;
            };
            stats.keys += 1;
            stats.bytes += (data.len() + shading_data.len() + group_data.len()) as u64;
            uploads.0.push(KeyUpload {
                image: tex.image.id(),
                first_layer: 6 * r.slot,
                face: tex.face,
                data,
                shading_image: tex.shading.id(),
                shading_data,
                pack: id,
                group_data,
                slot: r.slot,
                slots: tex.slots,
            });
            tex.uploaded.insert(r.slot, vk);
            if normals {
                tex.normals.insert(r.slot);
            } else {
                tex.normals.remove(&r.slot);
            }
        }
    }
}

/// A key's texels in the key texture's layout: per texel (radiance RGB9E5, distance f32 bits,
/// object id, oct-encoded RG16Snorm normal or 0); in the shading texture's layout: per texel
/// (lighting RGB9E5, non-diffuse RGB9E5), zero for a pack without them; and whether it had
/// normals. `None` when its formats or face size do not fit.
pub fn interleave(d: &DecodedKey, face: u32) -> Option<(Vec<u8>, Vec<u8>, bool)> {
    let texels = (6 * d.face_size * d.face_size) as usize;
    if d.face_size != face
        || d.radiance.len() != texels * 4
        || d.distance.len() != texels * 4
        || d.object_id.len() != texels * 4
    {
        return None;
    }
    // Without normals the shader skips the plane test, as plenoptic_recon does.
    let normals = d.normal.as_ref().filter(|n| n.len() == texels * 4);
    let mut data = vec![0u8; texels * TEXEL_BYTES];
    for (i, o) in data.chunks_exact_mut(TEXEL_BYTES).enumerate() {
        let src = i * 4..i * 4 + 4;
        o[0..4].copy_from_slice(&d.radiance[src.clone()]);
        o[4..8].copy_from_slice(&d.distance[src.clone()]);
        o[8..12].copy_from_slice(&d.object_id[src.clone()]);
        if let Some(n) = normals {
            o[12..16].copy_from_slice(&n[src]);
        }
    }
    let rgb9e5 = |c: &Option<Vec<u8>>| c.as_ref().filter(|c| c.len() == texels * 4).cloned();
    let (lighting, non_diffuse) = (rgb9e5(&d.lighting), rgb9e5(&d.non_diffuse));
    let mut shading = vec![0u8; texels * SHADING_BYTES];
    for (i, o) in shading.chunks_exact_mut(SHADING_BYTES).enumerate() {
        let src = i * 4..i * 4 + 4;
        if let Some(l) = &lighting {
            o[0..4].copy_from_slice(&l[src.clone()]);
        }
        if let Some(s) = &non_diffuse {
            o[4..8].copy_from_slice(&s[src]);
        }
    }
    Some((data, shading, normals.is_some()))
}

/// A key's light-group layers in the [`GroupLayers`] layout: per stored group, six faces
/// of (lighting, non-diffuse) RGB9E5 texels. `None` when one is not RGB9E5 at face `face`.
pub fn interleave_groups(d: &DecodedKey, face: u32) -> Option<Vec<u8>> {
    let texels = (6 * face * face) as usize;
    let mut out = Vec::with_capacity(d.groups.len() * texels * GROUP_TEXEL_BYTES as usize);
    for [lighting, non_diffuse] in &d.groups {
        if lighting.len() != texels * 4 || non_diffuse.len() != texels * 4 {
            return None;
        }
        for (l, n) in lighting.chunks_exact(4).zip(non_diffuse.chunks_exact(4)) {
            out.extend_from_slice(l);
            out.extend_from_slice(n);
        }
    }
    Some(out)
}

fn extract_key_uploads(mut main: ResMut<MainWorld>, mut pending: ResMut<PendingKeyUploads>) {
    if let Some(mut uploads) = main.get_resource_mut::<KeyUploads>() {
        pending.0.append(&mut uploads.0);
    }
}

/// Writes the pending keys into their layers, in the order they were queued (a slot reused
/// later in the queue ends with its latest key); keys whose texture is not on the GPU yet
/// wait.
fn write_key_uploads(
    mut pending: ResMut<PendingKeyUploads>,
    mut groups: ResMut<GroupLayers>,
    images: Res<RenderAssets<GpuImage>>,
    (device, queue): (Res<RenderDevice>, Res<RenderQueue>),
) {
    pending.0.retain(|u| {
        let (Some(gpu), Some(shading)) = (images.get(u.image), images.get(u.shading_image)) else {
            return true;
        };
        if !u.group_data.is_empty() {
            let per_slot = u.group_data.len() as u64;
            let buffer = groups.0.entry(u.pack).or_insert_with(|| {
                device.create_buffer(&BufferDescriptor {
                    label: Some("plenoptic light-group layers"),
                    size: per_slot * u64::from(u.slots),
                    usage: BufferUsages::STORAGE | BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                })
            });
            if buffer.size() >= per_slot * u64::from(u.slot + 1) {
                queue.write_buffer(buffer, per_slot * u64::from(u.slot), &u.group_data);
            }
        }
        for (texture, data, bytes) in [
            (&gpu.texture, &u.data, TEXEL_BYTES),
            (&shading.texture, &u.shading_data, SHADING_BYTES),
        ] {
            queue.write_texture(
                TexelCopyTextureInfo {
                    texture,
                    mip_level: 0,
                    origin: Origin3d {
                        x: 0,
                        y: 0,
                        z: u.first_layer,
                    },
                    aspect: TextureAspect::All,
                },
                data,
                TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(u.face * bytes as u32),
                    rows_per_image: Some(u.face),
                },
                Extent3d {
                    width: u.face,
                    height: u.face,
                    depth_or_array_layers: 6,
                },
            );
        }
        false
    });
}
