//! Light probes at the base views: the app's meshes near a base view are lit by that view's
//! own radiance cube, wherever the camera is.
//!
//! For each pack a camera shows and each of its base views, the plugin keeps a Bevy
//! [`LightProbe`] centred on the base view with a [`GeneratedEnvironmentMapLight`] whose
//! source cubemap is the view's radiance at the time of the pack's first camera, its two
//! bracketing keys blended with their linear time weights. Bevy lights a mesh inside a
//! probe's box with that probe's filtered maps; meshes outside every probe keep the camera's
//! environment light ([`super::PackEnvironmentLight`]). A probe's box is a cube whose side is
//! the distance to the nearest other base view (the scene's diagonal for a single view), so
//! the boxes of a regular plan tile the view space without overlapping.
//!
//! Probes need every base view's radiance, not only the views around the camera that
//! streaming keeps resident, and only the radiance, at low resolution: each probe key's
//! radiance chunk is read and decoded on the I/O task pool and box-filtered to at most
//! [`PROBE_FACE`] texels a face ([`ProbeKeys`]), two keys per base view at a time (6 · 64² ·
//! 12 bytes, 295 KB, per key), outside the streaming budget.
//!
//! Where the device has no binding arrays Bevy ignores reflection probes ([`ReflectionProbes`]):
//! the probes then keep only their ambient cubes, for the irradiance volume.
//!
//! Bevy's light probes are world entities, not per view: two cameras at different times of
//! one pack share the first camera's probes (their own environment lights are their own).
//! A probe whose keys are evicted keeps its last cubemap until they return.

use std::collections::HashMap;
use std::sync::Arc;

use bevy::light::{GeneratedEnvironmentMapLight, LightProbe};
use bevy::prelude::*;
use bevy::tasks::{IoTaskPool, Task, futures::check_ready};
use plenoptic_pack::PackReader;
use plenoptic_pack::cube::{direction_to_texel, texel_direction};
use plenoptic_recon::temporal::bracketing;

use plenoptic_recon::relight::Relight;

use super::{Source, source_face, source_image, texel_map};
use crate::asset::RadiancePack;
use crate::camera::{LightSettings, PlenopticCamera};
use crate::reconstruct::relight::weight_bits;
use crate::settings::PlenopticSettings;

/// Largest face of a probe's radiance (a power of two).
pub const PROBE_FACE: u32 = 64;

/// (pack, base view, key, bits of the light-group weights it is relit at).
type ProbeKey = (AssetId<RadiancePack>, u32, u32, Vec<u32>);
/// A probe key's radiance: face and texels.
type ProbeCube = (u32, Vec<Vec3>);

/// The probes' decoded keys: radiance box-filtered to [`probe_face`], and the reads in
/// flight. Keys no probe needs are dropped each frame.
#[derive(Resource, Default)]
pub struct ProbeKeys {
    cubes: HashMap<ProbeKey, Arc<ProbeCube>>,
    tasks: HashMap<ProbeKey, Task<Option<ProbeCube>>>,
}

/// The face of a probe's radiance for a pack face of `face` texels: the largest power of two
/// not above it, at most [`PROBE_FACE`].
pub fn probe_face(face: u32) -> u32 {
    let f = face.max(1);
    (1u32 << (31 - f.leading_zeros())).min(PROBE_FACE)
}

/// `texels` (a cube of face `face`) box-filtered to a cube of face `out ≤ face`: each texel
/// of the output is the mean of the input texels whose centres fall in it.
pub fn downsample(face: u32, texels: &[Vec3], out: u32) -> Vec<Vec3> {
    let mut sum = vec![Vec3::ZERO; 6 * (out as usize).pow(2)];
    let mut count = vec![0u32; sum.len()];
    for (i, t) in texels.iter().enumerate() {
        let j = direction_to_texel(out, texel_direction(face, i));
        sum[j] += *t;
        count[j] += 1;
    }
    sum.iter()
        .zip(&count)
        .map(|(s, &c)| *s / c.max(1) as f32)
        .collect()
}

/// Reads and decodes key `k` of view `v` relit at `relight`, box-filtered to
/// [`probe_face`].
fn read_key(reader: &PackReader, v: u32, k: u32, relight: &Relight) -> Option<ProbeCube> {
    let cube = relight.radiance_cube(reader, v, k).ok()?;
    let out = probe_face(cube.face_size);
    Some((out, downsample(cube.face_size, &cube.texels, out)))
}

/// Whether the device lets Bevy apply reflection probes (binding arrays). Without, the
/// probes keep their ambient cubes for the irradiance volume ([`super::volume`]) but get no
/// Bevy light probe (its cubemap would be filtered every frame for nothing).
#[derive(Resource, Debug, Clone, Copy, Default)]
pub struct ReflectionProbes(pub bool);

/// A light probe the plugin keeps at a base view.
#[derive(Component, Debug, Clone)]
pub struct PlenopticProbe {
    /// The pack.
    pub pack: AssetId<RadiancePack>,
    /// The base view it stands at.
    pub view: u32,
    /// Its source cubemap (none where Bevy cannot apply reflection probes:
    /// [`ReflectionProbes`]).
    pub image: Option<Handle<Image>>,
    /// The ambient cube of its radiance (+X, −X, +Y, −Y, +Z, −Z; [`super::volume`]).
    pub ambient: [Vec3; 6],
    built_for: Source,
}

/// The side of the probe box of base view `v` among `positions`: the distance to the nearest
/// other view, or `fallback` without one; at least 0.25 m.
pub fn probe_side(positions: &[Vec3], v: usize, fallback: f32) -> f32 {
    positions
        .iter()
        .enumerate()
        .filter(|&(i, _)| i != v)
        .map(|(_, p)| p.distance(positions[v]))
        .fold(f32::INFINITY, f32::min)
        .min(if fallback > 0.0 {
            fallback
        } else {
            f32::INFINITY
        })
        .clamp(0.25, 1e4)
}

/// Spawns, rewrites and removes the [`PlenopticProbe`]s, and reads the keys they need.
#[expect(clippy::too_many_arguments, reason = "a Bevy system's parameters")]
pub(super) fn update_probes(
    mut commands: Commands,
    settings: Res<PlenopticSettings>,
    mut keys: ResMut<ProbeKeys>,
    support: Option<Res<ReflectionProbes>>,
    packs: Res<Assets<RadiancePack>>,
    cameras: Query<&PlenopticCamera>,
    mut probes: Query<(Entity, &mut PlenopticProbe)>,
    mut images: ResMut<Assets<Image>>,
    mut maps: Local<HashMap<(u32, u32), Vec<usize>>>,
) {
    // The time and light-group weights of each shown pack's first camera.
    let mut times: Vec<(AssetId<RadiancePack>, f32, &LightSettings)> = Vec::new();
    if settings.environment_light {
        for cam in &cameras {
            if !times.iter().any(|(id, ..)| *id == cam.pack.id()) {
                times.push((cam.pack.id(), cam.time, &cam.lights));
            }
        }
    }
    let mut existing: HashMap<(AssetId<RadiancePack>, u32), Entity> = HashMap::new();
    for (entity, probe) in &probes {
        if times.iter().any(|(id, ..)| *id == probe.pack) {
            existing.insert((probe.pack, probe.view), entity);
        } else {
            commands.entity(entity).despawn();
        }
    }
    // Finished reads.
    let keys = &mut *keys;
    keys.tasks.retain(|k, task| match check_ready(task) {
        Some(result) => {
            if let Some(r) = result {
                keys.cubes.insert(k.clone(), Arc::new(r));
            }
            false
        }
        None => true,
    });
    let mut needed: Vec<ProbeKey> = Vec::new();
    for (id, t, lights) in times {
        let Some(pack) = packs.get(id) else { continue };
        let m = pack.reader.manifest();
        let relight = Arc::new(lights.relight(m));
        let bits = weight_bits(&relight.weights);
        let positions: Vec<Vec3> = m.base_views.iter().map(|b| b.position).collect();
        let diagonal = (m.scene_bounds.max - m.scene_bounds.min).length();
        for v in 0..positions.len() {
            if !pack.usable_views.get(v).copied().unwrap_or(false) {
                continue;
            }
            let Some((k0, k1, f)) = bracketing(&m.base_views[v].time_keys, t) else {
                continue;
            };
            let mut wanted = vec![(k0 as u32, 1.0 - f)];
            if k1 != k0 && f > 1e-4 {
                wanted.push((k1 as u32, f));
            }
            wanted.retain(|w| w.1 > 1e-4);
            for &(k, _) in &wanted {
                let key = (id, v as u32, k, bits.clone());
                if !keys.cubes.contains_key(&key) && !keys.tasks.contains_key(&key) {
                    let (reader, relight) = (pack.reader.clone(), relight.clone());
                    let task = IoTaskPool::get()
                        .spawn(async move { read_key(&reader, v as u32, k, &relight) });
                    keys.tasks.insert(key.clone(), task);
                }
                needed.push(key);
            }
            // Both keys read: the probe's cubemap, unless it already shows them (time weights in
            // steps of 1/64 of a key interval: many probes are rewritten per frame while
            // playing).
            let Some(cubes) = wanted
                .iter()
                .map(|&(k, w)| Some((keys.cubes.get(&(id, v as u32, k, bits.clone()))?.clone(), w)))
                .collect::<Option<Vec<_>>>()
            else {
                continue;
            };
            let face = cubes[0].0.0;
            if cubes.iter().any(|c| c.0.0 != face) {
                continue;
            }
            let source: Source = (
                id,
                v as u32,
                wanted
                    .iter()
                    .map(|&(k, w)| (k, (w * 64.0).round() as u32))
                    .collect(),
                bits.clone(),
            );
            let current = existing
                .get(&(id, v as u32))
                .and_then(|&e| probes.get_mut(e).ok());
            if current.as_ref().is_some_and(|(_, p)| p.built_for == source) {
                continue;
            }
            // Blended once: the ambient cube and the cubemap both read this.
            let blended: Vec<Vec3> = (0..cubes[0].0.1.len())
                .map(|i| cubes.iter().map(|(c, w)| c.1[i] * *w).sum())
                .collect();
            let ambient = super::volume::ambient_cube(face, &blended);
            let reflections = support.as_ref().is_some_and(|s| s.0);
            let image = reflections.then(|| {
                let map = maps
                    .entry((face, source_face(face)))
                    .or_insert_with(|| texel_map(face, source_face(face)));
                source_image(face, &[(blended, 1.0)], map)
            });
            match current {
                Some((_, mut probe)) => {
                    if let (Some(image), Some(handle)) = (image, &probe.image) {
                        images.insert(handle, image).ok();
                    }
                    probe.built_for = source;
                    probe.ambient = ambient;
                }
                None => {
                    let side = probe_side(&positions, v, diagonal);
                    let handle = image.map(|i| images.add(i));
                    let mut probe = commands.spawn((
                        Name::new(format!("plenoptic probe {v}")),
                        PlenopticProbe {
                            pack: id,
                            view: v as u32,
                            image: handle.clone(),
                            ambient,
                            built_for: source,
                        },
                        Transform::from_translation(positions[v]).with_scale(Vec3::splat(side)),
                    ));
                    if let Some(handle) = handle {
                        probe.insert((
                            LightProbe::default(),
                            GeneratedEnvironmentMapLight {
                                environment_map: handle,
                                intensity: 1.0,
                                ..default()
                            },
                        ));
                    }
                }
            }
        }
    }
    // Keys no probe needs any more.
    keys.cubes.retain(|k, _| needed.contains(k));
    keys.tasks.retain(|k, _| needed.contains(k));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn probe_faces_and_box_filter() {
        for (face, out) in [(1, 1), (8, 8), (16, 16), (48, 32), (128, 64), (2048, 64)] {
            assert_eq!(probe_face(face), out, "{face}");
        }
        // Texels holding their own direction, filtered to half the face: each output texel
        // is the mean of its four inputs, so it points where the output texel does.
        let input: Vec<Vec3> = (0..6 * 16 * 16).map(|i| texel_direction(16, i)).collect();
        let out = downsample(16, &input, 8);
        assert_eq!(out.len(), 6 * 64);
        for (j, d) in out.iter().enumerate() {
            let angle = d.angle_between(texel_direction(8, j));
            assert!(angle < 0.02, "texel {j}: {angle}");
        }
        // A uniform cube stays uniform.
        let grey = downsample(16, &vec![Vec3::splat(0.5); 6 * 256], 4);
        assert!(
            grey.iter()
                .all(|g| (*g - Vec3::splat(0.5)).abs().max_element() < 1e-6)
        );
    }

    #[test]
    fn probe_boxes_reach_the_nearest_view() {
        let p = [
            Vec3::ZERO,
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(3.0, 0.0, 0.0),
        ];
        assert_eq!(probe_side(&p, 0, 10.0), 1.0);
        assert_eq!(probe_side(&p, 2, 10.0), 2.0);
        // One view: the scene's diagonal; none given: the floor of 0.25 m is not the answer.
        assert_eq!(probe_side(&p[..1], 0, 7.0), 7.0);
        assert_eq!(probe_side(&[Vec3::ZERO, Vec3::ZERO], 0, 7.0), 0.25);
        assert!(probe_side(&p[..1], 0, 0.0).is_finite());
    }
}
