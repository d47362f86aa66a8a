//! GPU geometry-assisted reconstruction (thesis §8.2.3).
//!
//! Every proxy mesh is drawn with a [`PlenopticMaterial`] whose fragment shader
//! (`geometry.wgsl`, beside this file) does the lookups of `plenoptic_recon`'s geometry mode:
//! for each resident (base view, bracketing time key) the fragment's point is carried along
//! its object's motion, `p_τ = M_o(τ) M_o(t)⁻¹ p`, looked up (nearest texel) in that key's
//! cube, accepted if the cube saw the same object at the same distance, and blended with
//! weight `w_view · w_time · ((1 + cos θ)/2)^p`. The result is written unlit into the camera's
//! HDR target; depth comes from the rasterised proxy mesh.
//!
//! Where no lookup is accepted, the same fallbacks as `plenoptic_recon`, in its order:
//! 1. the temporal volumes ([`volume`]): samples of the object near the point's direction
//!    from each base view, within `t ± tε`;
//! 2. the same-object hole fill: the nearest ring of pixels (radius up to
//!    [`HOLE_FILL_RADIUS`]) whose points have a direct or volume lookup of this object, their
//!    mean. A fragment cannot read its neighbours' results, so it recomputes them: each ring
//!    pixel's ray is intersected with the fragment's surface plane (from screen-space
//!    derivatives) and that point is reconstructed. On planar faces this is the CPU's search
//!    exactly; it differs where a neighbour pixel shows another face of the object, or another
//!    object in front of the plane;
//! 3. the heaviest key's texel in the point's direction ("background").
//!
//! Resident keys live in one `Rgba32Uint` 2D-array texture per pack: texel = (radiance as
//! RGB9E5, distance as f32 bits, object id, oct-encoded RG16Snorm normal), six layers per
//! streaming slot: the pack's own texel bytes interleaved, one binding and `textureLoad` only
//! (distances and ids are not filterable anyway).

pub mod cpu;
pub mod volume;

use std::collections::{HashMap, HashSet};

use bevy::asset::{RenderAssetUsages, embedded_asset};
use bevy::prelude::*;
use bevy::render::render_resource::{
    AsBindGroup, Extent3d, ShaderType, TextureDimension, TextureFormat,
};
use bevy::render::storage::ShaderBuffer;
use bevy::shader::ShaderRef;
use plenoptic_recon::temporal::bracketing;
use plenoptic_recon::viewspace::ViewWeights;

use crate::asset::RadiancePack;
use crate::camera::PlenopticCamera;
use crate::proxy::{PlenopticScene, ProxyOf};
use crate::streaming::schedule::{time_epsilon, volume_buckets};
use crate::streaming::{StreamCache, key_bytes};
use crate::{Backend, PlenopticSettings, PlenopticSystems};

/// Most lookups (view × key) per fragment.
pub const MAX_LOOKUPS: usize = 16;
/// Radius, pixels, of the same-object hole fill (`plenoptic_recon`'s default).
pub const HOLE_FILL_RADIUS: u32 = 12;
/// Most array layers of the key texture (a common device limit is 2048).
const MAX_LAYERS: u32 = 2046;

/// Adds the GPU reconstruction material.
#[derive(Debug, Default)]
pub struct PlenopticReconstructPlugin;

impl Plugin for PlenopticReconstructPlugin {
    fn build(&self, app: &mut App) {
        embedded_asset!(app, "geometry.wgsl");
        app.add_plugins(MaterialPlugin::<PlenopticMaterial>::default())
            .init_resource::<KeyTextures>()
            .init_resource::<ResolvedBackend>()
            .init_resource::<volume::VolumeBuffers>()
            .add_systems(PreUpdate, resolve_backend)
            .add_systems(
                Update,
                (
                    upload_keys,
                    volume::upload_volumes,
                    attach_materials,
                    update_materials,
                )
                    .chain()
                    .after(PlenopticSystems::Streaming),
            );
    }

    fn finish(&self, app: &mut App) {
        // Like bevy_solari: check the device once; a missing capability is a warning and the
        // CPU backend, never a panic.
        let layers = app
            .get_sub_app(bevy::render::RenderApp)
            .and_then(|r| {
                r.world()
                    .get_resource::<bevy::render::renderer::RenderDevice>()
            })
            .map(|d| d.limits().max_texture_array_layers);
        let supported = layers.is_some_and(|l| l >= 6);
        if !supported {
            warn!(
                "plenoptic: the GPU reconstruction needs 2D array textures of at least 6 layers \
                 (device: {layers:?}); Backend::Auto uses the CPU backend"
            );
        }
        app.insert_resource(GpuSupport(supported));
    }
}

/// Whether the device supports the GPU reconstruction (decided in `Plugin::finish`).
#[derive(Resource, Debug, Clone, Copy)]
pub struct GpuSupport(pub bool);

/// The backend in use: [`PlenopticSettings::backend`] with `Auto` resolved.
#[derive(Resource, Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ResolvedBackend(pub Backend);

fn resolve_backend(
    settings: Res<PlenopticSettings>,
    support: Option<Res<GpuSupport>>,
    mut resolved: ResMut<ResolvedBackend>,
) {
    let gpu = support.is_some_and(|s| s.0);
    let b = match settings.backend {
        Backend::Auto if gpu => Backend::Gpu,
        Backend::Auto => Backend::Cpu,
        b => b,
    };
    if resolved.0 != b {
        resolved.0 = b;
    }
}

/// The proxy material of the GPU path: one instance per proxy object.
#[derive(Asset, TypePath, AsBindGroup, Debug, Clone)]
pub struct PlenopticMaterial {
    /// Resident keys (see the module doc).
    #[texture(0, dimension = "2d_array", sample_type = "u_int")]
    pub cubes: Handle<Image>,
    /// Lookups of this frame for this material's object.
    #[uniform(1)]
    pub params: ReconParams,
    /// Resident temporal-volume samples of the pack ([`volume::PackVolumes::samples`]).
    #[storage(2, read_only)]
    pub volume_samples: Handle<ShaderBuffer>,
    /// Their bin offsets ([`volume::PackVolumes::bins`]).
    #[storage(3, read_only)]
    pub volume_bins: Handle<ShaderBuffer>,
}

impl Material for PlenopticMaterial {
    fn fragment_shader() -> ShaderRef {
        "embedded://bevy_plenoptic/reconstruct/geometry.wgsl".into()
    }
}

/// The per-frame uniform of a [`PlenopticMaterial`].
#[derive(ShaderType, Debug, Clone, Default)]
pub struct ReconParams {
    /// x: lookup count, y: object id, z: face size, w: volume block count.
    pub header: Vec4,
    /// x: relative depth tolerance, y: angular power, z: time t, w: temporal window tε.
    pub tuning: Vec4,
    /// x: same-object hole-fill radius in pixels, y: index of the heaviest lookup (the
    /// "background" fallback; ≥ the lookup count when there is none).
    pub fill: Vec4,
    /// Base view position (xyz) and first array layer (w) per lookup.
    pub base: [Vec4; MAX_LOOKUPS],
    /// Weight (x) and whether the key has normals (y: 1 or 0) per lookup.
    pub weight: [Vec4; MAX_LOOKUPS],
    /// `M_o(τ) M_o(t)⁻¹` per lookup.
    pub motion: [Mat4; MAX_LOOKUPS],
    /// Base view position (xyz) and view weight (w) per volume block.
    pub volume: [Vec4; volume::MAX_VOLUMES],
    /// First sample (x) and first bin offset (y) per volume block in the pack's buffers.
    pub volume_range: [UVec4; volume::MAX_VOLUMES],
}

/// The key texture of each pack and which key each slot holds.
#[derive(Resource, Debug, Default)]
pub struct KeyTextures(pub HashMap<AssetId<RadiancePack>, KeyTexture>);

/// One pack's key texture.
#[derive(Debug, Clone)]
pub struct KeyTexture {
    /// The texture.
    pub image: Handle<Image>,
    /// Face size.
    pub face: u32,
    /// Slots it has room for.
    pub slots: u32,
    /// (view, key) uploaded in each slot.
    pub uploaded: HashMap<u32, (u32, u32)>,
    /// Slots whose key came with normals (an all-zero texel is the +Z normal, so presence
    /// cannot be read from the texels).
    pub normals: HashSet<u32>,
}

fn attach_materials(
    mut commands: Commands,
    backend: Res<ResolvedBackend>,
    keys: Res<KeyTextures>,
    volumes: Res<volume::VolumeBuffers>,
    roots: Query<&PlenopticScene>,
    proxies: Query<(Entity, &ChildOf, &ProxyOf), With<MeshMaterial3d<StandardMaterial>>>,
    mut materials: ResMut<Assets<PlenopticMaterial>>,
) {
    if backend.0 != Backend::Gpu {
        return;
    }
    for (entity, parent, _) in &proxies {
        let Ok(scene) = roots.get(parent.parent()) else {
            continue;
        };
        let (Some(tex), Some(vol)) = (
            keys.0.get(&scene.pack.id()),
            volumes.0.get(&scene.pack.id()),
        ) else {
            continue;
        };
        let m = materials.add(PlenopticMaterial {
            cubes: tex.image.clone(),
            params: ReconParams::default(),
            volume_samples: vol.samples.clone(),
            volume_bins: vol.bins.clone(),
        });
        commands
            .entity(entity)
            .remove::<MeshMaterial3d<StandardMaterial>>()
            .insert(MeshMaterial3d(m));
    }
}

/// Copies newly resident keys into their slot's layers of the pack's key texture.
fn upload_keys(
    mut keys: ResMut<KeyTextures>,
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
            let slots =
                (settings.memory_budget_bytes / per_key).clamp(1, (MAX_LAYERS / 6) as u64) as u32;
            let mut image = Image::new_fill(
                Extent3d {
                    width: face,
                    height: face,
                    depth_or_array_layers: 6 * slots,
                },
                TextureDimension::D2,
                &[0; 16],
                TextureFormat::Rgba32Uint,
                // Kept in the main world too: newly resident keys are written into it.
                RenderAssetUsages::default(),
            );
            image.texture_view_descriptor = None;
            KeyTexture {
                image: images.add(image),
                face,
                slots,
                uploaded: HashMap::new(),
                normals: HashSet::new(),
            }
        });
        let fresh: Vec<_> = cache
            .resident
            .iter()
            .filter(|((p, v, k), r)| {
                *p == id && r.slot < tex.slots && tex.uploaded.get(&r.slot) != Some(&(*v, *k))
            })
            .map(|((_, v, k), r)| ((*v, *k), r.clone()))
            .collect();
        if fresh.is_empty() {
            continue;
        }
        let Some(mut image) = images.get_mut(&tex.image) else {
            continue;
        };
        let Some(data) = image.data.as_mut() else {
            continue;
        };
        for (vk, r) in fresh {
            let d = &r.data;
            let texels = (6 * d.face_size * d.face_size) as usize;
            if d.face_size != tex.face
                || d.radiance.len() != texels * 4
                || d.distance.len() != texels * 4
                || d.object_id.len() != texels * 4
            {
                warn_once!(
                    "plenoptic: GPU reconstruction needs RGB9E5 radiance, R32F distance and \
                     R32Uint ids at face size {}; key {vk:?} not shown",
                    tex.face
                );
                continue;
            }
            let normals = d.normal.as_ref().filter(|n| n.len() == texels * 4);
            let base = r.slot as usize * texels * 16;
            for i in 0..texels {
                let o = base + i * 16;
                data[o..o + 4].copy_from_slice(&d.radiance[i * 4..i * 4 + 4]);
                data[o + 4..o + 8].copy_from_slice(&d.distance[i * 4..i * 4 + 4]);
                data[o + 8..o + 12].copy_from_slice(&d.object_id[i * 4..i * 4 + 4]);
                // Oct-encoded RG16Snorm normal (without normals the shader skips the plane
                // test, as plenoptic_recon does).
                if let Some(n) = normals {
                    data[o + 12..o + 16].copy_from_slice(&n[i * 4..i * 4 + 4]);
                }
            }
            tex.uploaded.insert(r.slot, vk);
            if normals.is_some() {
                tex.normals.insert(r.slot);
            } else {
                tex.normals.remove(&r.slot);
            }
        }
    }
}

/// Fills every proxy material's lookups for its pack's (first) camera.
#[expect(clippy::too_many_arguments, reason = "a Bevy system's parameters")]
fn update_materials(
    keys: Res<KeyTextures>,
    volumes: Res<volume::VolumeBuffers>,
    cache: Res<StreamCache>,
    settings: Res<PlenopticSettings>,
    packs: Res<Assets<RadiancePack>>,
    cameras: Query<(&PlenopticCamera, &GlobalTransform)>,
    roots: Query<&PlenopticScene>,
    proxies: Query<(&ChildOf, &ProxyOf, &MeshMaterial3d<PlenopticMaterial>)>,
    mut materials: ResMut<Assets<PlenopticMaterial>>,
) {
    for (parent, of, handle) in &proxies {
        let Ok(scene) = roots.get(parent.parent()) else {
            continue;
        };
        let id = scene.pack.id();
        let (Some(pack), Some(tex)) = (packs.get(id), keys.0.get(&id)) else {
            continue;
        };
        let Some((cam, transform)) = cameras.iter().find(|(c, _)| c.pack.id() == id) else {
            continue;
        };
        let m = pack.reader.manifest();
        let usable = vec![true; m.base_views.len()];
        let mut views = ViewWeights::new(&m.view_space, &m.base_views, &usable)
            .weights(transform.translation());
        views.truncate(settings.max_views.max(1));
        let s: f32 = views.iter().map(|v| v.1).sum();
        let inv_now = pack.proxy(of.id).map_or(Mat4::IDENTITY, |p| {
            p.transform_at(cam.time).to_matrix().inverse()
        });
        let mut params = ReconParams {
            header: Vec4::new(0.0, of.id as f32, tex.face as f32, 0.0),
            tuning: Vec4::new(0.03, 8.0, 0.0, 0.0),
            ..default()
        };
        let views: Vec<(usize, f32)> = views
            .into_iter()
            .map(|(v, w)| (v, if s > 0.0 { w / s } else { w }))
            .collect();
        let positions: Vec<Vec3> = m.base_views.iter().map(|b| b.position).collect();
        volume::fill_params(
            &mut params,
            volumes.0.get(&id),
            &views,
            &positions,
            volume_buckets(m, cam.time),
            cam.time,
            time_epsilon(m),
        );
        let mut n = 0;
        // (weight, index) of the heaviest lookup.
        let mut heaviest = (f32::NEG_INFINITY, MAX_LOOKUPS);
        for (v, w) in views {
            let bv = &m.base_views[v];
            let Some((k0, k1, f)) = bracketing(&bv.time_keys, cam.time) else {
                continue;
            };
            let mut pairs = vec![(k0, 1.0 - f)];
            if k1 != k0 {
                pairs.push((k1, f));
            }
            let got: Vec<_> = pairs
                .into_iter()
                .filter_map(|(k, wt)| {
                    let r = cache.get(id, (v as u32, k as u32))?;
                    (tex.uploaded.get(&r.slot) == Some(&(v as u32, k as u32)))
                        .then_some((k, wt, r.slot))
                })
                .collect();
            let total: f32 = got.iter().map(|g| g.1).sum::<f32>().max(1e-9);
            for (k, wt, slot) in got {
                if n == MAX_LOOKUPS || w * wt / total <= 1e-4 {
                    continue;
                }
                let tau = bv.time_keys[k];
                let motion = pack
                    .proxy(of.id)
                    .map_or(Mat4::IDENTITY, |p| p.transform_at(tau).to_matrix())
                    * inv_now;
                if w * wt / total >= heaviest.0 {
                    heaviest = (w * wt / total, n);
                }
                params.base[n] = bv.position.extend((slot * 6) as f32);
                let normals = if tex.normals.contains(&slot) {
                    1.0
                } else {
                    0.0
                };
                params.weight[n] = Vec4::new(w * wt / total, normals, 0.0, 0.0);
                params.motion[n] = motion;
                n += 1;
            }
        }
        params.header.x = n as f32;
        params.fill = Vec4::new(HOLE_FILL_RADIUS as f32, heaviest.1 as f32, 0.0, 0.0);
        if let Some(mut mat) = materials.get_mut(&handle.0) {
            mat.params = params;
        }
    }
}
