//! The CPU backend ([`crate::Backend::Cpu`]): `plenoptic_recon`'s [`Reconstructor`] renders
//! each frame on the async compute pool (never on the main thread); the finished frame is
//! copied into an `Rgba32Float` image that the proxy meshes show in screen space
//! (`cpu.wgsl`), so depth compositing with Bevy meshes is the same as on the GPU path. The
//! image lags the camera by the time a frame takes. Every camera has its own reconstructor,
//! frame task and image.
//!
//! The reconstructor reads no cube from the pack: the streaming scheduler decodes the keys of
//! every camera's working set for it, inside the same memory budget as the GPU's
//! ([`crate::streaming::decode_cpu_key`]), and each frame task is handed the keys resident
//! when it starts ([`ResidentKeys`], a `plenoptic_recon::KeySource`), so the CPU frame is
//! reconstructed from exactly the keys the GPU would look up. A task holds its keys until it
//! finishes, so for one frame an evicted key can outlive its place in the budget. Temporal
//! volume blocks are still read by the reconstructor's own chunk cache.

use std::collections::HashMap;
use std::sync::Arc;

use bevy::asset::{RenderAssetUsages, embedded_asset};
use bevy::prelude::*;
use bevy::render::render_resource::{AsBindGroup, Extent3d, TextureDimension, TextureFormat};
use bevy::shader::ShaderRef;
use bevy::tasks::{AsyncComputeTaskPool, Task, futures::check_ready};
use plenoptic_pack::ChunkKind;
use plenoptic_recon::{Camera as ReconCamera, Frame, KeySource, Reconstructor, StreamedCube};

use crate::asset::RadiancePack;
use crate::camera::PlenopticCamera;
use crate::proxy::{PlenopticScene, ProxyOf};
use crate::reconstruct::ReconstructSystems;
use crate::reconstruct::frames::{CpuFrameImage, FrameReplaced};
use crate::settings::{Backend, PlenopticEvent, ResolvedBackend};
use crate::streaming::StreamCache;

/// Adds the CPU backend.
#[derive(Debug, Default)]
pub struct PlenopticCpuPlugin;

impl Plugin for PlenopticCpuPlugin {
    fn build(&self, app: &mut App) {
        embedded_asset!(app, "cpu.wgsl");
        app.add_plugins(MaterialPlugin::<CpuFrameMaterial>::default())
            .init_resource::<CpuFrames>()
            .add_systems(
                Update,
                (
                    attach_cpu_materials.in_set(ReconstructSystems::Attach),
                    run_cpu_frames.in_set(ReconstructSystems::Jobs),
                ),
            );
    }
}

/// Proxy material of the CPU backend: shows the reconstructed frame in screen space.
#[derive(Asset, TypePath, AsBindGroup, Debug, Clone)]
pub struct CpuFrameMaterial {
    /// The latest reconstructed frame (linear radiance).
    #[texture(0, sample_type = "float", filterable = false)]
    pub frame: Handle<Image>,
}

impl Material for CpuFrameMaterial {
    fn fragment_shader() -> ShaderRef {
        "embedded://bevy_plenoptic/reconstruct/cpu/cpu.wgsl".into()
    }
}

type FrameTask = Task<Result<Frame, String>>;

/// Per camera: the reconstructor, the frame in flight and the displayed image.
#[derive(Resource, Default)]
pub struct CpuFrames(HashMap<Entity, CpuFrame>);

struct CpuFrame {
    pack: AssetId<RadiancePack>,
    rec: Option<Arc<Reconstructor>>,
    task: Option<FrameTask>,
    image: Handle<Image>,
    /// Frames completed.
    done: u64,
}

impl CpuFrames {
    /// The image showing `camera`'s latest CPU frame, once the backend has one for it.
    pub fn image(&self, camera: Entity) -> Option<Handle<Image>> {
        self.0.get(&camera).map(|f| f.image.clone())
    }

    /// Frames the CPU backend has completed for `camera`.
    pub fn frames_done(&self, camera: Entity) -> u64 {
        self.0.get(&camera).map_or(0, |f| f.done)
    }

    /// Chunks `camera`'s reconstructor has read from the pack itself (its cubes come from the
    /// streaming, so only temporal-volume blocks count).
    pub fn chunks_read(&self, camera: Entity) -> u64 {
        self.0
            .get(&camera)
            .and_then(|f| f.rec.as_ref())
            .map_or(0, |r| r.chunks_read())
    }
}

/// The keys of one pack resident in the streaming cache, as a frame task's reconstructor
/// looks them up.
#[derive(Default)]
pub struct ResidentKeys(HashMap<(ChunkKind, u32, u32), StreamedCube>);

impl ResidentKeys {
    /// The CPU-decoded keys of pack `id` resident in `cache`.
    pub fn of(cache: &StreamCache, id: AssetId<RadiancePack>) -> Self {
        let mut cubes = HashMap::new();
        for (&(pack, view, key), r) in &cache.resident {
            if pack != id {
                continue;
            }
            for (kind, cube) in &r.data.cpu {
                cubes.insert((*kind, view, key), cube.clone());
            }
        }
        ResidentKeys(cubes)
    }

    /// Whether it holds no key.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }
}

impl KeySource for ResidentKeys {
    fn cube(&self, kind: ChunkKind, view: u32, key: u32) -> Option<StreamedCube> {
        self.0.get(&(kind, view, key)).cloned()
    }
}

/// Proxies still on the placeholder material.
type Unattached = (With<ProxyOf>, With<MeshMaterial3d<StandardMaterial>>);

#[expect(clippy::too_many_arguments, reason = "a Bevy system's parameters")]
fn attach_cpu_materials(
    mut commands: Commands,
    backend: Res<ResolvedBackend>,
    mut frames: ResMut<CpuFrames>,
    packs: Res<Assets<RadiancePack>>,
    roots: Query<&PlenopticScene>,
    proxies: Query<(Entity, &ChildOf), Unattached>,
    mut materials: ResMut<Assets<CpuFrameMaterial>>,
    mut images: ResMut<Assets<Image>>,
    mut events: MessageWriter<PlenopticEvent>,
) {
    if backend.0 != Backend::Cpu {
        return;
    }
    for (entity, parent) in &proxies {
        let Ok(scene) = roots.get(parent.parent()) else {
            continue;
        };
        let id = scene.pack.id();
        let Some(pack) = packs.get(id) else { continue };
        if frames.0.get(&scene.camera).is_some_and(|f| f.pack != id) {
            frames.0.remove(&scene.camera);
        }
        let frame = frames.0.entry(scene.camera).or_insert_with(|| {
            let rec = match pack.file.as_ref().map(Reconstructor::open) {
                Some(Ok(r)) => Some(Arc::new(r)),
                Some(Err(e)) => {
                    events.write(PlenopticEvent::ChunkFailed {
                        chunk: "pack (CPU backend)".into(),
                        reason: e.to_string(),
                    });
                    None
                }
                None => {
                    warn!("plenoptic: the CPU backend needs a pack on the file system");
                    None
                }
            };
            let image = Image::new_fill(
                Extent3d::default(),
                TextureDimension::D2,
                &[0; 16],
                TextureFormat::Rgba32Float,
                RenderAssetUsages::default(),
            );
            CpuFrame {
                pack: id,
                rec,
                task: None,
                image: images.add(image),
                done: 0,
            }
        });
        commands
            .entity(scene.camera)
            .try_insert(CpuFrameImage(frame.image.clone()));
        let m = materials.add(CpuFrameMaterial {
            frame: frame.image.clone(),
        });
        commands
            .entity(entity)
            .remove::<MeshMaterial3d<StandardMaterial>>()
            .insert(MeshMaterial3d(m));
    }
}

pub(crate) fn run_cpu_frames(
    mut frames: ResMut<CpuFrames>,
    cache: Res<StreamCache>,
    cameras: Query<(&PlenopticCamera, &Camera, &Projection, &GlobalTransform)>,
    mut images: ResMut<Assets<Image>>,
    mut materials: ResMut<Assets<CpuFrameMaterial>>,
    mut replaced: MessageWriter<FrameReplaced>,
    mut events: MessageWriter<PlenopticEvent>,
) {
    frames.0.retain(|camera, _| cameras.contains(*camera));
    for (camera, f) in frames.0.iter_mut() {
        if let Some(task) = f.task.as_mut()
            && let Some(result) = check_ready(task)
        {
            f.task = None;
            match result {
                Ok(frame) => {
                    let data: Vec<u8> = frame
                        .radiance
                        .iter()
                        .flat_map(|c| [c.x, c.y, c.z, 1.0])
                        .flat_map(f32::to_le_bytes)
                        .collect();
                    if let Some(mut image) = images.get_mut(&f.image) {
                        *image = Image::new(
                            Extent3d {
                                width: frame.width,
                                height: frame.height,
                                depth_or_array_layers: 1,
                            },
                            TextureDimension::D2,
                            data,
                            TextureFormat::Rgba32Float,
                            RenderAssetUsages::default(),
                        );
                    }
                    // Touch the materials showing it so their bind groups pick up the new
                    // texture.
                    let users: Vec<_> = materials
                        .iter()
                        .filter(|(_, m)| m.frame == f.image)
                        .map(|(id, _)| id)
                        .collect();
                    for m in users {
                        if let Some(mut m) = materials.get_mut(m) {
                            m.frame = f.image.clone();
                        }
                    }
                    replaced.write(FrameReplaced(f.image.id()));
                    f.done += 1;
                }
                Err(reason) => {
                    events.write(PlenopticEvent::ChunkFailed {
                        chunk: "frame (CPU backend)".into(),
                        reason,
                    });
                }
            }
        }
        if f.task.is_some() {
            continue;
        }
        let Ok((cam, camera, projection, transform)) = cameras.get(*camera) else {
            continue;
        };
        // The camera's settings, applied while no frame task shares the reconstructor.
        if let Some(r) = f.rec.as_mut().and_then(Arc::get_mut) {
            if r.settings != cam.settings {
                r.settings = cam.settings.clone();
            }
            match cam.lights.weights(r.pack().manifest()) {
                Ok(w) if w != *r.light_weights() => r.set_light_weights(w),
                Ok(_) => {}
                Err(e) => warn_once!("plenoptic: {e}; the camera shows the pack as baked"),
            }
        }
        let Some(rec) = f.rec.clone() else {
            continue;
        };
        // The keys the streaming has resident for this pack; none yet: no frame.
        let keys = ResidentKeys::of(&cache, f.pack);
        if keys.is_empty() {
            continue;
        }
        rec.set_key_source(Some(Arc::new(keys)));
        let Some(size) = camera.physical_viewport_size() else {
            continue;
        };
        let vfov = match projection {
            Projection::Perspective(p) => p.fov,
            _ => std::f32::consts::FRAC_PI_4,
        };
        let (_, rotation, position) = transform.to_scale_rotation_translation();
        let (t, mode) = (cam.time, cam.mode.into());
        f.task = Some(AsyncComputeTaskPool::get().spawn(async move {
            let c = ReconCamera::new(position, rotation, vfov, size.x, size.y)
                .map_err(|e| e.to_string())?;
            rec.render(&c, t, mode)
                .map(|(frame, _)| frame)
                .map_err(|e| e.to_string())
        }));
    }
}
