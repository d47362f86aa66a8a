//! GPU volume mode ([`ReconMode::Volume`]): `plenoptic_recon`'s volume mode with the warping
//! on the GPU.
//!
//! Per weighted base view (the view-space weights of the nearest
//! `ReconSettings::max_views` views, at most [`MAX_IMAGE_VIEWS`]), a cube of face size
//! `ReconSettings::volume_face_size` at the camera's time t is interpolated on the CPU from the view's
//! temporal-volume samples, exactly as `plenoptic_recon` does: sliced from the baked
//! (x, y, t) complex of the block of `bucket_of(t)` when the pack has its connectivity
//! ([`plenoptic_recon::volume::slice_to_cube`]), otherwise triangulated per face from the
//! samples within `t ± tε` with tent weights ([`plenoptic_recon::volume::samples_to_cube`],
//! at least three samples). The cubes (radiance as RGB9E5, distance, object id) are written
//! into one `Rgba32Uint` 2D-array texture, six layers per view ([`VolumeCubes`]), and the
//! image-mode passes ([`super`]) warp them as each view's single key (weight 1), blend
//! the views and fill the background. Every volume-mode camera has its own [`VolumeCubes`].
//!
//! The cubes are rebuilt when the camera's time, its views or their weights change, once all
//! the views' volume blocks of the window are resident in the stream cache. The rebuild is a
//! task on the I/O task pool (the blocks are read again from the pack: the resident
//! [`crate::streaming::BinnedVolume`]s are sorted by direction, and the baked connectivity
//! names the samples in stored order), never on the main thread; until it finishes the frame
//! shows the previous cubes, and one rebuild runs at a time, so a playing camera's cubes lag
//! its time by the rebuild's duration. A view without volume samples near t is left out (the
//! CPU warps its range images instead).

use std::sync::Arc;

use bevy::asset::RenderAssetUsages;
use bevy::prelude::*;
use bevy::render::render_resource::{Extent3d, TextureDimension, TextureFormat};
use bevy::tasks::{IoTaskPool, Task, futures::check_ready};
use plenoptic_pack::{ChunkKind, PackReader, cube::rgb9e5_pack};
use plenoptic_recon::relight::Relight;
use plenoptic_recon::volume::{Cubes, samples_to_cube, slice_to_cube};

use super::MAX_IMAGE_VIEWS;
use crate::asset::RadiancePack;
use crate::camera::ReconSettings;
use crate::camera::{PlenopticCamera, ReconMode};
use crate::reconstruct::ReconstructSystems;
use crate::reconstruct::relight::weight_bits;
use crate::settings::Backend;
use crate::settings::ResolvedBackend;
use crate::streaming::StreamCache;

/// A volume-mode camera's cubes, six layers per view (a component of the camera, added when
/// it first enters volume mode on the GPU backend).
#[derive(Component, Default)]
pub struct VolumeCubes {
    /// The texture (`Rgba32Uint`, [`VolumeCubes::face`]² per layer), once built.
    pub image: Option<Handle<Image>>,
    /// Face size of its cubes: the camera's `ReconSettings::volume_face_size`.
    pub face: u32,
    /// (base view, normalised view weight) of each view in the texture, in layer order.
    pub views: Vec<(usize, f32)>,
    /// What they were built for: pack, time bits, (view, weight bits) of the weighted views.
    built_for: Option<BuiltFor>,
    /// The rebuild in flight: what for, and its texels and views.
    task: Option<(BuiltFor, Task<Rebuilt>)>,
}

impl std::fmt::Debug for VolumeCubes {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("VolumeCubes")
            .field("image", &self.image)
            .field("views", &self.views)
            .field("built_for", &self.built_for)
            .field("rebuilding", &self.task.is_some())
            .finish()
    }
}

/// A finished rebuild: the texels of the cubes, and (view, weight) of each.
type Rebuilt = (Vec<u8>, Vec<(usize, f32)>);

/// Pack, time bits, face size, (view, weight bits) of the weighted views, and the bits of
/// the camera's light-group weights.
type BuiltFor = (AssetId<RadiancePack>, u32, u32, Vec<(usize, u32)>, Vec<u32>);

/// The cube of base view `view` at time `t`, as `plenoptic_recon`'s volume mode builds it;
/// `None` when the view has no usable volume near t.
/// `settings` give the face size, tε and the buckets; the samples are relit by `relight`
/// (the camera's light groups).
pub fn view_cube(
    r: &PackReader,
    view: usize,
    t: f32,
    settings: &ReconSettings,
    relight: &Relight,
) -> Option<Cubes> {
    let face = settings.volume_face_size.max(1);
    let m = r.manifest();
    let v = view as u32;
    // The baked complex of the block of bucket_of(t), if any.
    let bucket = m.bucket_of(t);
    if r.find(ChunkKind::VolumeConnectivity, v, bucket).is_some()
        && r.find(ChunkKind::VolumeBlock, v, bucket).is_some()
        && let (Ok(block), Ok(tets)) = (
            relight.volume_block(r, v, bucket),
            r.connectivity(v, bucket),
        )
        && let Ok(Some(c)) = slice_to_cube(&block, &tets, t, face)
    {
        return Some(c);
    }
    // The samples within t ± tε, tent-weighted.
    let eps = settings.time_epsilon_on(m);
    let mut samples = Vec::new();
    for b in settings.volume_buckets(m, t) {
        if r.find(ChunkKind::VolumeBlock, v, b).is_none() {
            continue;
        }
        let Ok(block) = relight.volume_block(r, v, b) else {
            continue;
        };
        for s in &block.samples {
            let dt = (s.t - t).abs();
            if dt <= eps {
                samples.push((*s, 1.0 - dt / eps));
            }
        }
    }
    (samples.len() >= 3).then(|| samples_to_cube(&samples, face))
}

/// A cube's texels in the image-mode passes' key layout: (radiance RGB9E5, distance f32 bits,
/// object id, 0).
fn texels((radiance, distance, ids): &Cubes) -> Vec<u8> {
    let mut out = Vec::with_capacity(radiance.texels.len() * 16);
    for ((r, d), o) in radiance
        .texels
        .iter()
        .zip(&distance.texels)
        .zip(&ids.texels)
    {
        out.extend_from_slice(&rgb9e5_pack(*r).to_le_bytes());
        out.extend_from_slice(&d.to_bits().to_le_bytes());
        out.extend_from_slice(&o.to_le_bytes());
        out.extend_from_slice(&0u32.to_le_bytes());
    }
    out
}

/// Volume mode on the GPU: each volume-mode camera's cubes at its time, which the
/// image-mode passes warp (part of [`super::WarpPlugin`]).
#[derive(Debug, Default)]
pub struct VolumeModePlugin;

impl Plugin for VolumeModePlugin {
    fn build(&self, app: &mut App) {
        app.add_systems(
            Update,
            prepare_cubes
                .in_set(ReconstructSystems::Jobs)
                .before(super::extract::prepare_jobs),
        );
    }
}

/// Rebuilds each volume-mode camera's [`VolumeCubes`] on the GPU backend when its time or
/// views change and their volume blocks are resident.
fn prepare_cubes(
    mut commands: Commands,
    backend: Res<ResolvedBackend>,
    cache: Res<StreamCache>,
    packs: Res<Assets<RadiancePack>>,
    mut cameras: Query<(
        Entity,
        &PlenopticCamera,
        &GlobalTransform,
        Option<&mut VolumeCubes>,
    )>,
    mut images: ResMut<Assets<Image>>,
) {
    if backend.0 != Backend::Gpu {
        return;
    }
    for (entity, cam, transform, cubes) in &mut cameras {
        if cam.mode != ReconMode::Volume {
            continue;
        }
        match cubes {
            Some(mut cubes) => prepare(&cache, &packs, cam, transform, &mut cubes, &mut images),
            None => {
                commands.entity(entity).insert(VolumeCubes::default());
            }
        }
    }
}

/// [`prepare_cubes`] for one camera.
fn prepare(
    cache: &StreamCache,
    packs: &Assets<RadiancePack>,
    cam: &PlenopticCamera,
    transform: &GlobalTransform,
    cubes: &mut VolumeCubes,
    images: &mut Assets<Image>,
) {
    // A rebuild in flight: apply it when done; start no other meanwhile.
    if let Some((_, task)) = cubes.task.as_mut() {
        let Some(result) = check_ready(task) else {
            return;
        };
        if let Some((key, _)) = cubes.task.take() {
            apply(cubes, images, key, result);
        }
    }
    let id = cam.pack.id();
    let Some(pack) = packs.get(id) else {
        return;
    };
    let m = pack.reader.manifest();
    let (t, position) = (cam.time, transform.translation());
    let settings = cam.settings.clone();
    let relight = cam.lights.relight(m);
    let mut views = settings.view_weights(m, &pack.usable_views, position);
    views.truncate(MAX_IMAGE_VIEWS);
    let key = (
        id,
        t.to_bits(),
        settings.volume_face_size.max(1),
        views.iter().map(|&(v, w)| (v, w.to_bits())).collect(),
        weight_bits(&relight.weights),
    );
    if cubes.built_for.as_ref() == Some(&key) {
        return;
    }
    let resident = views.iter().all(|&(v, _)| {
        settings.volume_buckets(m, t).all(|b| {
            pack.reader
                .find(ChunkKind::VolumeBlock, v as u32, b)
                .is_none()
                || cache.volume(id, (v as u32, b)).is_some()
        })
    });
    if !resident {
        return;
    }
    let reader: Arc<PackReader> = pack.reader.clone();
    cubes.task = Some((
        key,
        IoTaskPool::get().spawn(async move {
            let mut data = Vec::new();
            let mut built = Vec::new();
            for (v, w) in views {
                if let Some(c) = view_cube(&reader, v, t, &settings, &relight) {
                    data.extend_from_slice(&texels(&c));
                    built.push((v, w));
                }
            }
            (data, built)
        }),
    ));
}

/// Applies a finished rebuild: the views, and the texture (re)created.
fn apply(
    cubes: &mut VolumeCubes,
    images: &mut Assets<Image>,
    key: BuiltFor,
    (data, built): Rebuilt,
) {
    let face = key.2;
    cubes.built_for = Some(key);
    cubes.views = built;
    cubes.face = face;
    if cubes.views.is_empty() {
        cubes.image = None;
        return;
    }
    let image = Image::new(
        Extent3d {
            width: face,
            height: face,
            depth_or_array_layers: 6 * cubes.views.len() as u32,
        },
        TextureDimension::D2,
        data,
        TextureFormat::Rgba32Uint,
        RenderAssetUsages::RENDER_WORLD,
    );
    if let Some(h) = &cubes.image
        && images.get(h).is_some()
    {
        images.insert(h, image).ok();
    } else {
        cubes.image = Some(images.add(image));
    }
}
