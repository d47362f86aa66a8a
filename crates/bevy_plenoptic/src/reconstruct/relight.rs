//! Light groups on the GPU: each camera's resident keys relit at its
//! [`LightSettings`](crate::camera::LightSettings)
//! (docs/pack-format.md, "Light groups"; `plenoptic_recon::relight` holds the math).
//!
//! A pack with stored light-group layers keeps them beside its key texture in one storage
//! buffer ([`GroupLayers`], written with the keys by [`super::upload`]): per slot and stored
//! group, the six faces' (lighting, non-diffuse) RGB9E5 pairs. A camera on such a pack has
//! [`RelitKeys`]: its own key and shading textures with room for its lookups' keys
//! ([`MAX_LOOKUPS`] × 6 layers). Once per frame, before anything reads them, a compute pass
//! (`geometry/relight.rs`) writes each key the camera looks up into them, relit: lighting
//! and non-diffuse blended `base · total + Σ c · layer` over the groups whose weight differs
//! from the base, radiance scaled by the ratio of the relit light to the stored light (the
//! sky's multiplier where a texel sees no object). Every reader (the lookups, the key
//! blend, the screen fill, reflections, the background) then reads the camera's relit
//! textures, lookup `k`'s key at layers `6k..6k + 6`, at no extra cost per pixel. The runtime
//! sun, lamps, emission and environment are scaled in the camera's view buffer and object
//! uniforms, and the temporal-volume fallback blends its samples' layers where it reads them
//! (it is rare, and its samples are not per key).
//!
//! Why per key and not per pixel: a lookup's footprint is 4 texels, and a pixel makes up to
//! [`MAX_LOOKUPS`] of them, so blending per pixel reads `4 · lookups · layers` more texels
//! for every pixel of every frame; relighting the keys reads `(2 + layers)` texels per key
//! texel, `lookups · 6 · face²` of them, whatever the resolution (the cost counters'
//! `relit texels`, `docs/results/measurements.md`).

use std::collections::HashMap;

use bevy::asset::RenderAssetUsages;
use bevy::image::ImageSampler;
use bevy::prelude::*;
use bevy::render::extract_component::ExtractComponent;
use bevy::render::render_resource::{
    Buffer, BufferDescriptor, BufferUsages, Extent3d, ShaderType, TextureDimension, TextureFormat,
    TextureUsages,
};
use bevy::render::renderer::RenderDevice;
use bevy::render::storage::ShaderBuffer;
use plenoptic_pack::{MAX_LIGHT_GROUPS, Manifest};
use plenoptic_recon::relight::Relight;

use super::MAX_LOOKUPS;
use crate::asset::RadiancePack;

/// Bytes of one texel of one group layer: (lighting, non-diffuse) RGB9E5.
pub const GROUP_TEXEL_BYTES: u64 = 8;
/// Largest group-layer buffer (wgpu's default storage-binding limit): a grouped pack's key
/// slots are as many as fit in it.
pub const MAX_GROUP_BUFFER: u64 = 128 << 20;

/// Light groups whose layers `manifest`'s pack stores (0: none, the pack is shown as baked
/// or scaled as a whole).
pub fn stored_groups(manifest: &Manifest) -> u32 {
    let stored = manifest.light_groups.as_ref().map(|e| e.stored().len());
    stored.unwrap_or(0) as u32
}

/// A camera's relit keys (see the module doc), on cameras whose pack stores group layers.
/// Extracted onto its render-world view with what the pass reads.
#[derive(Component, Debug, Clone, ExtractComponent)]
pub struct RelitKeys {
    /// Per lookup, six faces of key texels (the pack key texture's layout), relit.
    pub image: Handle<Image>,
    /// Per lookup, six faces of (lighting, non-diffuse) texels, relit.
    pub shading: Handle<Image>,
    /// The keys' face size.
    pub face: u32,
    /// The pack.
    pub pack: AssetId<RadiancePack>,
    /// The pack's key texture and shading texture (what is relit).
    pub keys: Option<(Handle<Image>, Handle<Image>)>,
    /// Lookups this frame (the view buffer's `lookup_count`).
    pub lookups: u32,
    /// Stored groups of the pack.
    pub groups: u32,
    /// The camera's view buffer (the lookups' source layers and the blend).
    pub view: Handle<ShaderBuffer>,
}

impl RelitKeys {
    /// The camera's two textures at face size `face`.
    pub fn textures(face: u32, images: &mut Assets<Image>) -> (Handle<Image>, Handle<Image>) {
        let layers = 6 * MAX_LOOKUPS as u32;
        (
            images.add(storage_image(face, layers, TextureFormat::Rgba32Uint)),
            images.add(storage_image(face, layers, TextureFormat::Rg32Uint)),
        )
    }
}

/// The bits of every weight of `w`: what a result built at these weights is keyed on.
pub fn weight_bits(w: &plenoptic_pack::GroupWeights) -> Vec<u32> {
    let all = std::iter::once(w.default).chain(w.groups.iter().copied());
    all.flat_map(|c| c.to_array().map(f32::to_bits)).collect()
}

/// A texture of `layers` layers of `face` × `face` texels of `format`, written by a pass over
/// a camera's keys and read by the lookups (with their nearest sampler, as the pack's key
/// texture).
pub(crate) fn storage_image(face: u32, layers: u32, format: TextureFormat) -> Image {
    let mut image = Image::new_uninit(
        Extent3d {
            width: face,
            height: face,
            depth_or_array_layers: layers,
        },
        TextureDimension::D2,
        format,
        RenderAssetUsages::RENDER_WORLD,
    );
    image.texture_descriptor.usage =
        TextureUsages::STORAGE_BINDING | TextureUsages::TEXTURE_BINDING;
    image.texture_view_descriptor = None;
    image.sampler = ImageSampler::nearest();
    image
}

/// A 16-byte storage buffer, bound as the group layers of a pack without them (bindings may
/// not be missing).
pub(crate) fn no_group_layers(device: &RenderDevice) -> Buffer {
    device.create_buffer(&BufferDescriptor {
        label: Some("plenoptic no light-group layers"),
        size: 16,
        usage: BufferUsages::STORAGE,
        mapped_at_creation: false,
    })
}

/// Each pack's group layers on the GPU (render world): one storage buffer, per slot and
/// stored group, six faces of `face`² [`GROUP_TEXEL_BYTES`]-byte texels.
#[derive(Resource, Debug, Default)]
pub struct GroupLayers(pub HashMap<AssetId<RadiancePack>, Buffer>);

/// One layer of a light-group blend in a pass's uniforms (`LightLayer` in `relight.wgsl`).
#[derive(ShaderType, Debug, Clone, Copy, Default, PartialEq)]
pub struct LightLayerParams {
    /// Its coefficient (colour × intensity relative to the stored light).
    pub coefficient: Vec3,
    /// The stored group it scales.
    pub group: u32,
}

/// A [`Relight`]'s blend as the passes' uniforms take it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BlendUniforms {
    /// The total's weight (xyz).
    pub base: Vec4,
    /// The sky's multiplier (xyz): relit radiance where a texel sees no object.
    pub sky: Vec4,
    /// The layers blended (`count` of them).
    pub layers: [LightLayerParams; MAX_LIGHT_GROUPS],
    /// Layers blended.
    pub count: u32,
}

impl BlendUniforms {
    /// The uniforms of `relight`.
    pub fn new(relight: &Relight) -> Self {
        let mut out = Self {
            base: relight.blend.base.extend(0.0),
            sky: relight.sky.extend(0.0),
            layers: [LightLayerParams::default(); MAX_LIGHT_GROUPS],
            count: 0,
        };
        for (slot, (g, c)) in out.layers.iter_mut().zip(&relight.blend.layers) {
            *slot = LightLayerParams {
                coefficient: *c,
                group: *g,
            };
            out.count += 1;
        }
        out
    }
}
