//! The main-world side of image mode: each camera's [`ImageJob`] for this frame (its
//! weighted base views, their resident keys and Bézier weights, and every tunable from its
//! `ReconSettings`), which Bevy extracts onto the camera's render-world view entity; the
//! camera's [`ImageFrame`] is resized to it.

use bevy::prelude::*;
use plenoptic_recon::temporal::bezier_weights;

use super::volume::VolumeCubes;
use super::{ImageJob, ImageParams, ImageWork, KEYS_PER_VIEW, MAX_IMAGE_VIEWS, frame_image};
use crate::asset::RadiancePack;
use crate::camera::LightSettings;
use crate::camera::{PlenopticCamera, ReconMode};
use crate::reconstruct::KeyTextures;
use crate::reconstruct::frames::{FrameReplaced, ImageFrame};
use crate::reconstruct::relight::{BlendUniforms, stored_groups};
use crate::settings::{Backend, ResolvedBackend};
use crate::streaming::StreamCache;

/// A camera in image or volume mode: the components [`prepare_jobs`] reads for its job.
type WarpCamera<'a> = (
    &'a PlenopticCamera,
    &'a Camera,
    &'a Projection,
    &'a GlobalTransform,
    Option<&'a VolumeCubes>,
);

/// Fills each camera's [`ImageJob`] (warping its [`VolumeCubes`] in volume mode) and resizes
/// its [`ImageFrame`] to it (a [`FrameReplaced`] message tells the materials that bind it).
pub fn prepare_jobs(
    backend: Res<ResolvedBackend>,
    keys: Res<KeyTextures>,
    cache: Res<StreamCache>,
    packs: Res<Assets<RadiancePack>>,
    mut cameras: Query<(WarpCamera, &mut ImageFrame, &mut ImageJob)>,
    mut images: ResMut<Assets<Image>>,
    mut replaced: MessageWriter<FrameReplaced>,
) {
    for (camera, mut frame, mut job) in &mut cameras {
        let work = job_for(&backend, &keys, &cache, &packs, camera, &frame.image);
        if let Some(w) = &work {
            let size = UVec2::new(w.params.size.x, w.params.size.y);
            if images.get(&frame.image).is_some_and(|i| i.size() != size) {
                images
                    .insert(&frame.image, frame_image(size.x, size.y))
                    .ok();
                replaced.write(FrameReplaced(frame.image.id()));
            }
        }
        let active = work.is_some();
        if frame.active != active {
            frame.active = active;
        }
        job.0 = work;
    }
}

/// The image-mode work of one camera, if it is in image or volume mode on the GPU backend.
fn job_for(
    backend: &ResolvedBackend,
    keys: &KeyTextures,
    cache: &StreamCache,
    packs: &Assets<RadiancePack>,
    (cam, camera, projection, transform, volume): WarpCamera,
    frame: &Handle<Image>,
) -> Option<ImageWork> {
    if backend.0 != Backend::Gpu || !matches!(cam.mode, ReconMode::Image | ReconMode::Volume) {
        return None;
    }
    let id = cam.pack.id();
    let (pack, tex) = (packs.get(id)?, keys.0.get(&id)?);
    let volume_mode = cam.mode == ReconMode::Volume;
    let size = camera.physical_viewport_size()?;
    let vfov = match projection {
        Projection::Perspective(p) => p.fov,
        _ => std::f32::consts::FRAC_PI_4,
    };
    let (_, rotation, position) = transform.to_scale_rotation_translation();
    let basis = plenoptic_recon::Camera::new(position, rotation, vfov, size.x, size.y)
        .ok()?
        .basis();
    let mut params = ImageParams {
        eye: basis.position.extend(basis.focal_px),
        right: basis.right.extend(basis.tan_x),
        up: basis.up.extend(basis.tan_y),
        forward: basis.forward.extend(cam.settings.depth_tolerance),
        size: UVec4::new(size.x, size.y, tex.face, 0),
        misc: UVec4::new(cam.settings.background_passes, 0, 0, 0),
        splat: Vec4::new(
            cam.settings.same_surface,
            cam.settings.max_splat_px,
            0.0,
            0.0,
        ),
        ..default()
    };
    if volume_mode {
        // Each view's cube at t is its single key.
        let volume = volume?;
        let image = volume.image.clone()?;
        params.size.z = volume.face;
        for (n, &(v, w)) in volume.views.iter().enumerate() {
            let layer = 6 * n as u32;
            params.views[n] = pack.reader.manifest().base_views[v].position.extend(w);
            params.nearest[n] = UVec4::new(layer, 1, 0, 0);
            params.layers[n][0] = layer;
            params.key_weights[n][0] = 1.0;
        }
        params.size.w = volume.views.len() as u32;
        return Some(ImageWork {
            cubes: image,
            shading: tex.shading.clone(),
            pack: id,
            output: frame.clone(),
            params,
        });
    }
    let m = pack.reader.manifest();
    let t = cam.time;
    let views = cam.settings.view_weights(m, &pack.usable_views, position);
    let mut n = 0;
    for (v, w) in views {
        if n == MAX_IMAGE_VIEWS {
            break;
        }
        let times = &m.base_views[v].time_keys;
        let wanted = bezier_weights(times, t);
        let resident: Vec<(usize, f32, u32)> = wanted
            .iter()
            .filter_map(|&(k, wk)| {
                let r = cache.get(id, (v as u32, k as u32))?;
                (tex.uploaded.get(&r.slot) == Some(&(v as u32, k as u32)))
                    .then_some((k, wk, r.slot))
            })
            .take(KEYS_PER_VIEW)
            .collect();
        if resident.is_empty() {
            continue;
        }
        let weights: Vec<f32> = if resident.len() == wanted.len() {
            resident.iter().map(|r| r.1).collect()
        } else {
            resident
                .iter()
                .map(|r| 1.0 / ((times[r.0] - t).abs() + 1e-4))
                .collect()
        };
        let total: f32 = weights.iter().sum();
        let nearest = resident
            .iter()
            .min_by(|a, b| (times[a.0] - t).abs().total_cmp(&(times[b.0] - t).abs()))?;
        params.views[n] = m.base_views[v].position.extend(w);
        params.nearest[n] = UVec4::new(nearest.2 * 6, resident.len() as u32, 0, 0);
        for (k, (r, wk)) in resident.iter().zip(&weights).enumerate() {
            params.layers[n][k] = r.2 * 6;
            params.key_weights[n][k] = wk / total;
        }
        n += 1;
    }
    if n == 0 {
        return None;
    }
    params.size.w = n as u32;
    relight(&mut params, &cam.lights, pack);
    Some(ImageWork {
        cubes: tex.image.clone(),
        shading: tex.shading.clone(),
        pack: id,
        output: frame.clone(),
        params,
    })
}

/// The light-group fields of `params`: the keys' radiance relit per texel at `lights`
/// (`plenoptic_recon::relight`'s ratio of the relit to the stored light) unless they are as
/// baked.
fn relight(params: &mut ImageParams, lights: &LightSettings, pack: &RadiancePack) {
    let m = pack.reader.manifest();
    let relight = lights.relight(m);
    if relight.blend.is_identity() && relight.sky == Vec3::ONE {
        return;
    }
    let b = BlendUniforms::new(&relight);
    params.light = UVec4::new(stored_groups(m), b.count, 1, 0);
    params.light_base = b.base;
    params.light_sky = b.sky;
    params.light_layers = b.layers;
}
