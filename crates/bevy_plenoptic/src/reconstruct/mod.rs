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
pub mod upload;
pub mod volume;

use std::collections::{HashMap, HashSet};

use bevy::asset::embedded_asset;
use bevy::prelude::*;
use bevy::render::render_resource::{AsBindGroup, ShaderType};
use bevy::render::storage::ShaderBuffer;
use bevy::shader::ShaderRef;
use plenoptic_recon::temporal::bracketing;
use plenoptic_recon::viewspace::ViewWeights;

use crate::asset::RadiancePack;
use crate::camera::{PlenopticCamera, ReconMode};
use crate::proxy::{PlenopticScene, ProxyOf};
use crate::streaming::StreamCache;
use crate::streaming::schedule::{time_epsilon, volume_buckets};
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
        upload::build(app);
        app.add_plugins(MaterialPlugin::<PlenopticMaterial>::default())
            .init_resource::<KeyTextures>()
            .init_resource::<ResolvedBackend>()
            .init_resource::<volume::VolumeBuffers>()
            .add_systems(PreUpdate, resolve_backend)
            .add_systems(
                Update,
                (
                    upload::upload_keys,
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
        if cam.mode != ReconMode::GeometryAssisted {
            warn_once!(
                "plenoptic: the GPU backend reconstructs in geometry-assisted mode only; \
                 {:?} mode needs Backend::Cpu",
                cam.mode
            );
        }
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
