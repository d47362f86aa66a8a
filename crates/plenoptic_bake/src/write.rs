//! Writing the pack (docs/architecture.md Baking step 8): encoding work items into chunks, proxy geometry
//! and animation tracks, the manifest, and the assembly of the pack from the work directory
//! in canonical order.
//!
//! Canonical chunk order: for each base view, its range images by time key (radiance,
//! lighting, non-diffuse, distance, object id, normal), then its volume blocks by bucket; then one proxy mesh per
//! object in id order; then the animation tracks; then the environment image; then (pack 1.2)
//! the proxies' UVs and tangents in object id order and the material textures in table order
//! ([`crate::materials`]).
//!
//! Statistics: the manifest's `stats` holds sample counts and bytes, which are the same for
//! every run. Wall-clock times are not: by default they go to a sidecar file
//! `<output>.timings.json` and `stats.phase_seconds` stays empty, so that the same inputs give
//! a byte-identical pack (resumed, sharded or not). [`AssembleOptions::timings_in_manifest`]
//! puts them in the manifest instead, at the cost of that property.
//!
//! Tracks: each object gets the world transform of its node chain. A static object gets one
//! step key at the start; an animated object's transform is sampled at twice the frame rate
//! (and at the range's ends) into linear tracks, which also flattens node hierarchies and
//! cubic splines into something every runtime can evaluate.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use plenoptic_pack::{
    Aabb, AnimationTracks, BakeSettings, BaseView, ChunkKind, CubeFormats, DirectSun,
    EnvironmentEntry, Interpolation, Manifest, Motion, ObjectEntry, ObjectTracks, PackWriter,
    ProxyMesh, TimeRange, Track, ViewSpace, VolumeSample, decode_volume_block, encode_connectivity,
    encode_distance, encode_normal, encode_object_id, encode_radiance, encode_volume_block,
};
use plenoptic_scene::{Mesh, Scene};
use plenoptic_trace::SceneAccel;

use crate::error::{BakeError, Result};
use crate::groups::LayeredImage;
use crate::plan::{Plan, PlanViewSpace};
use crate::volume::LayeredVolume;
use crate::work::{ItemChunk, WorkDir, WorkItem, work_items};

/// Storage formats of the range images (the pack's defaults: RGB9E5, R32F, R32 uint, RG16
/// snorm).
pub const FORMATS: CubeFormats = CubeFormats {
    radiance: plenoptic_pack::RadianceFormat::Rgb9e5,
    distance: plenoptic_pack::DistanceFormat::R32Float,
    object_id: plenoptic_pack::ObjectIdFormat::R32Uint,
    normal: plenoptic_pack::NormalFormat::Rg16Snorm,
};

/// The six cube chunks of a range image (lighting and non-diffuse radiance in the radiance
/// format), then each light group's lighting and non-diffuse cubes ([`crate::groups`]).
pub fn range_image_chunks(bv: u32, key: u32, layered: &LayeredImage) -> Result<Vec<ItemChunk>> {
    let image = &crate::quantise::coarsen(&layered.total);
    let c = |kind, bytes| ItemChunk {
        kind,
        base_view: bv,
        key,
        uncompressed_length: 0,
        bytes,
    };
    let mut out = vec![
        c(
            ChunkKind::RadianceCube,
            encode_radiance(&image.radiance, FORMATS.radiance)?,
        ),
        c(
            ChunkKind::LightingCube,
            encode_radiance(&image.lighting, FORMATS.radiance)?,
        ),
        c(
            ChunkKind::NonDiffuseCube,
            encode_radiance(&image.non_diffuse, FORMATS.radiance)?,
        ),
        c(
            ChunkKind::DistanceCube,
            encode_distance(&image.distance, FORMATS.distance)?,
        ),
        c(
            ChunkKind::ObjectIdCube,
            encode_object_id(&image.object_id, FORMATS.object_id)?,
        ),
        c(
            ChunkKind::NormalCube,
            encode_normal(&image.normal, FORMATS.normal)?,
        ),
    ];
    out.extend(crate::groups::layer_chunks(bv, key, layered)?);
    Ok(out)
}

/// A manifest for `plan` used only to bucket times (same rule as the pack's).
fn bucketing(plan: &Plan) -> Manifest {
    Manifest::new(
        TimeRange {
            start: plan.start,
            end: plan.end,
        },
        plan.bucket_span,
    )
}

/// The volume blocks of one base view: samples bucketed by time, empty buckets left out; with
/// light groups, each group's values of each block ([`ChunkKind::GroupVolume`]).
pub fn volume_chunks(plan: &Plan, bv: u32, volume: &LayeredVolume) -> Result<Vec<ItemChunk>> {
    let m = bucketing(plan);
    let mut buckets: BTreeMap<u32, Vec<usize>> = BTreeMap::new();
    for (i, s) in volume.samples.iter().enumerate() {
        buckets.entry(m.bucket_of(s.t)).or_default().push(i);
    }
    let mut out = Vec::new();
    for (b, members) in buckets {
        let (t0, t1) = m.bucket_range(b);
        let list: Vec<VolumeSample> = members
            .iter()
            .map(|&i| crate::quantise::coarsen_sample(&volume.samples[i]))
            .collect();
        let enc = encode_volume_block(t0, t1, &list)?;
        let complex = if plan.volume_complex {
            complex_chunk(&enc.bytes)?
        } else {
            None
        };
        let chunk = |kind, uncompressed_length, bytes| ItemChunk {
            kind,
            base_view: bv,
            key: b,
            uncompressed_length,
            bytes,
        };
        out.push(chunk(
            ChunkKind::VolumeBlock,
            enc.uncompressed_length,
            enc.bytes,
        ));
        if let Some((bytes, len)) = complex {
            out.push(chunk(ChunkKind::VolumeConnectivity, len, bytes));
        }
        out.extend(crate::groups::volume_layer_chunks(
            bv, b, volume, &members, &enc.order,
        )?);
    }
    Ok(out)
}

/// The (x, y, t) Delaunay complex of an encoded volume block (thesis §7.4.2), over its samples
/// as stored (quantized, in stored order): x, y the octahedral coordinates of the direction in
/// [−1, 1]², t the position in the bucket in [0, 1] — [`plenoptic_recon::volume::complex_point`],
/// the mapping reconstruction slices the complex with. `None` when the samples span no volume
/// (fewer than four, or coplanar).
pub fn complex_chunk(block: &[u8]) -> Result<Option<(Vec<u8>, u64)>> {
    let decoded = decode_volume_block(block)?;
    let points: Vec<[f64; 3]> = decoded
        .samples
        .iter()
        .map(|s| {
            plenoptic_recon::volume::complex_point(s.direction, s.t, decoded.t_start, decoded.t_end)
        })
        .collect();
    match crate::delaunay3::tetrahedralize(&points) {
        Ok(complex) => Ok(Some(encode_connectivity(
            decoded.samples.len() as u32,
            &complex.tets,
        )?)),
        Err(_) => Ok(None),
    }
}

/// The coverage of object `index` for the pack (see [`ObjectEntry::coverage`]): for a
/// `BLEND` material, the tracers' expected coverage at each triangle's centroid, weighted by
/// the triangle's area; `None` for opaque and cut-out materials, and where it rounds to 1.
pub fn object_coverage(scene: &Scene, index: usize) -> Option<f32> {
    let object = scene.objects.get(index)?;
    let material = scene.materials.get(object.material)?;
    if material.alpha_mode != plenoptic_scene::AlphaMode::Blend {
        return None;
    }
    let mesh = scene.meshes.get(object.mesh)?;
    let (mut sum, mut area) = (0.0f64, 0.0f64);
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let [Some(a), Some(b), Some(c)] = tri.map(|i| mesh.positions.get(i as usize)) else {
            continue;
        };
        let da = f64::from((*b - *a).cross(*c - *a).length());
        let bary = glam::Vec2::splat(1.0 / 3.0);
        let cov = plenoptic_trace::alpha::coverage(scene, material, mesh, t as u32, bary);
        sum += f64::from(cov) * da;
        area += da;
    }
    let mean = if area > 0.0 { sum / area } else { 1.0 } as f32;
    (mean < 0.999).then_some(mean.max(1e-3))
}

/// Every object with a proxy: its pack object id and its mesh, which has triangles.
pub(crate) fn proxied_objects(scene: &Scene) -> impl Iterator<Item = (u32, &Mesh)> {
    scene.objects.iter().enumerate().filter_map(|(i, o)| {
        let mesh = scene.meshes.get(o.mesh)?;
        let id = crate::render::pack_object_id(i as u32);
        (!mesh.triangles.is_empty()).then_some((id, mesh))
    })
}

/// The proxy mesh of every object with triangles (object-space positions, indices, normals).
pub fn proxy_meshes(scene: &Scene) -> Vec<ProxyMesh> {
    proxied_objects(scene)
        .map(|(object_id, mesh)| ProxyMesh {
            object_id,
            positions: mesh.positions.clone(),
            indices: mesh.triangles.iter().flatten().copied().collect(),
            normals: (mesh.normals.len() == mesh.positions.len()).then(|| mesh.normals.clone()),
        })
        .collect()
}

/// Animation tracks of every object (see the module doc).
pub fn animation_tracks(scene: &Scene, plan: &Plan) -> AnimationTracks {
    let mut times = vec![plan.start];
    if plan.animated {
        let rate = (plan.frame_rate * 2.0).max(1.0);
        let n = ((plan.end - plan.start) * rate).ceil().max(1.0) as usize;
        times = (0..=n)
            .map(|i| (plan.start + i as f32 / rate).min(plan.end))
            .collect();
        times.dedup();
    }
    let objects = (0..scene.objects.len())
        .map(|i| {
            let id = i as u32;
            let ts: Vec<f32> = if scene.object_is_animated(id) {
                times.clone()
            } else {
                vec![plan.start]
            };
            let interpolation = if ts.len() > 1 {
                Interpolation::Linear
            } else {
                Interpolation::Step
            };
            let (mut tr, mut ro, mut sc) = (Vec::new(), Vec::new(), Vec::new());
            for &t in &ts {
                let (s, r, p) = scene
                    .object_transform(id, t)
                    .to_scale_rotation_translation();
                tr.push(p);
                ro.push(r.normalize());
                sc.push(s);
            }
            ObjectTracks {
                object_id: crate::render::pack_object_id(id),
                translation: Some(Track {
                    interpolation,
                    times: ts.clone(),
                    values: tr,
                }),
                rotation: Some(Track {
                    interpolation,
                    times: ts.clone(),
                    values: ro,
                }),
                scale: Some(Track {
                    interpolation,
                    times: ts,
                    values: sc,
                }),
            }
        })
        .collect();
    AnimationTracks { objects }
}

/// Options of [`assemble`].
#[derive(Debug, Clone, Default)]
pub struct AssembleOptions {
    /// Wall-clock seconds per phase, for the manifest when asked (below).
    pub timings: BTreeMap<String, f64>,
    /// Put the timings into the manifest (breaks byte-identical output between runs).
    pub timings_in_manifest: bool,
}

/// The manifest of a plan's pack, without statistics and materials ([`assemble`] adds both).
pub fn manifest(plan: &Plan, scene: &Scene, accel: &SceneAccel<'_>) -> Manifest {
    let mut m = bucketing(plan);
    m.view_space = match plan.view_space {
        PlanViewSpace::Segment { a, b } => ViewSpace::Segment { a, b },
        PlanViewSpace::Rectangle { min, max, y } => ViewSpace::Rectangle {
            corners: [
                glam::Vec3::new(min[0], y, min[1]),
                glam::Vec3::new(max[0], y, min[1]),
                glam::Vec3::new(max[0], y, max[1]),
                glam::Vec3::new(min[0], y, max[1]),
            ],
        },
        PlanViewSpace::Box { min, max } => ViewSpace::Box { min, max },
    };
    let mut times: Vec<f32> = plan
        .base_views
        .iter()
        .flat_map(|v| v.time_keys.iter().copied())
        .chain([plan.start, plan.end])
        .collect();
    times.sort_by(f32::total_cmp);
    times.dedup();
    let (mut lo, mut hi) = (
        glam::Vec3::splat(f32::INFINITY),
        glam::Vec3::splat(f32::NEG_INFINITY),
    );
    for t in times {
        let (a, b) = accel.at_time(t).bounds();
        lo = lo.min(a);
        hi = hi.max(b);
    }
    if lo.cmple(hi).all() {
        m.scene_bounds = Aabb { min: lo, max: hi };
    }
    m.base_views = plan
        .base_views
        .iter()
        .map(|v| BaseView {
            id: v.id,
            position: v.position,
            time_keys: v.time_keys.clone(),
        })
        .collect();
    m.objects = scene
        .objects
        .iter()
        .enumerate()
        .map(|(i, o)| {
            let id = crate::render::pack_object_id(i as u32);
            let has_mesh = scene
                .meshes
                .get(o.mesh)
                .is_some_and(|m| !m.triangles.is_empty());
            ObjectEntry {
                id,
                name: o.name.clone(),
                node_path: o.node_path.clone(),
                motion: if scene.object_is_animated(i as u32) {
                    Motion::Animated
                } else {
                    Motion::Static
                },
                proxy_mesh: has_mesh.then_some(id),
                material: None,
                coverage: object_coverage(scene, i),
            }
        })
        .collect();
    m.lights = crate::lights::manifest_lights(scene);
    m.lamps_at_runtime = crate::lights::lamps_at_runtime(scene, &plan.quality);
    let mut extra = BTreeMap::new();
    extra.insert("recipe".into(), plan.recipe.clone());
    extra.insert(
        "baker".into(),
        format!("plenoptic_bake {}", env!("CARGO_PKG_VERSION")),
    );
    extra.insert("seed".into(), format!("{:#x}", plan.seed));
    extra.insert(
        "object_ids".into(),
        "scene object i is stored as i + 1; 0 = none".into(),
    );
    m.bake = BakeSettings {
        quality: plan.quality.q,
        cube_face_size: plan.quality.range_image_size,
        samples_per_texel: plan.quality.samples_per_pixel,
        volume_samples_per_view: plan
            .base_views
            .iter()
            .map(|v| u64::from(v.volume_samples))
            .max()
            .unwrap_or(0),
        extra,
    };
    m.environment = environment_entry(plan.start, plan.end, scene, plan.quality.runtime_sun);
    m.light_groups = crate::groups::manifest_entry(scene);
    m
}

/// Sun-track samples the pack stores for a moving sun that has no sun study (the runtime
/// interpolates linearly between them).
pub const SUN_TRACK_SAMPLES: usize = 256;

/// The scene's environment and sun track over `[start, end]` as the pack stores them; a scene
/// with neither declares its environment none, so that the runtime shows black where no
/// proxy is, as the tracer does (an undeclared environment makes the runtime show what a
/// base view saw in the pixel's direction, which may be a wall).
fn environment_entry(
    start: f32,
    end: f32,
    scene: &Scene,
    runtime_sun: bool,
) -> Option<EnvironmentEntry> {
    let sun = scene.sun_track(start, end, SUN_TRACK_SAMPLES);
    // With `quality.runtime_sun` the bake leaves the sun's direct light to the runtime
    // (`RadianceSample::sun`, taken out of the lighting by the denoiser's split).
    let direct_sun = scene
        .sun
        .as_ref()
        .filter(|_| sun.is_some() && runtime_sun)
        .and_then(|s| scene.lights.get(s.light))
        .map(|l| DirectSun {
            angular_radius: l.angular_radius.clamp(0.0, DirectSun::MAX_ANGULAR_RADIUS),
        });
    Some(EnvironmentEntry {
        direct_sun,
        ..EnvironmentEntry::new(&scene.environment, sun)
    })
}

fn stat_name(kind: ChunkKind) -> &'static str {
    match kind {
        ChunkKind::RadianceCube => "radiance",
        ChunkKind::LightingCube => "lighting",
        ChunkKind::NonDiffuseCube => "non_diffuse",
        ChunkKind::DistanceCube => "distance",
        ChunkKind::ObjectIdCube => "object_id",
        ChunkKind::NormalCube => "normal",
        ChunkKind::VolumeBlock => "volume",
        ChunkKind::VolumeConnectivity => "connectivity",
        ChunkKind::ProxyMesh => "proxy",
        ChunkKind::AnimationTracks => "tracks",
        ChunkKind::EnvironmentImage => "environment",
        ChunkKind::MaterialTexture => "textures",
        ChunkKind::ProxyAttributes => "proxy_attributes",
        ChunkKind::GroupLighting(_) => "group_lighting",
        ChunkKind::GroupNonDiffuse(_) => "group_non_diffuse",
        ChunkKind::GroupVolume(_) => "group_volume",
        ChunkKind::Unknown(_) => "other",
    }
}

/// Assembles the pack at `output` from the work directory's item files in canonical order
/// (every item must be there). Returns the manifest written.
pub fn assemble(
    plan: &Plan,
    scene: &Scene,
    accel: &SceneAccel<'_>,
    work: &WorkDir,
    output: &Path,
    options: &AssembleOptions,
) -> Result<Manifest> {
    let items = work_items(plan);
    let missing: Vec<&WorkItem> = items
        .iter()
        .filter(|i| !work.item_path(i).exists())
        .collect();
    if let Some(first) = missing.first() {
        return Err(BakeError::Incomplete {
            path: work.path.clone(),
            missing: missing.len(),
            total: items.len(),
            first: first.name(),
        });
    }
    if let Some(parent) = output.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent).map_err(|e| BakeError::io(parent, e))?;
    }
    let mut manifest = manifest(plan, scene, accel);
    let mut writer = PackWriter::create(output)?;
    let mut bytes: BTreeMap<String, u64> = BTreeMap::new();
    let mut volume_samples = 0u64;
    for item in &items {
        for c in work.read_item(item)? {
            *bytes.entry(stat_name(c.kind).into()).or_default() += c.bytes.len() as u64;
            if c.kind == ChunkKind::VolumeBlock && c.bytes.len() >= 8 {
                volume_samples += u64::from(u32::from_le_bytes([
                    c.bytes[4], c.bytes[5], c.bytes[6], c.bytes[7],
                ]));
            }
            if c.uncompressed_length == 0 {
                writer.add_chunk(c.kind, c.base_view, c.key, &c.bytes)?;
            } else {
                writer.add_raw_chunk(
                    c.kind,
                    c.base_view,
                    c.key,
                    &c.bytes,
                    c.uncompressed_length,
                    None,
                )?;
            }
        }
    }
    for mesh in proxy_meshes(scene) {
        let before = writer.bytes_written();
        writer.add_proxy_mesh(&mesh)?;
        *bytes.entry("proxy".into()).or_default() += writer.bytes_written() - before;
    }
    let before = writer.bytes_written();
    writer.add_tracks(&animation_tracks(scene, plan))?;
    *bytes.entry("tracks".into()).or_default() += writer.bytes_written() - before;
    if let plenoptic_scene::Environment::Image { image, .. } = &scene.environment {
        let before = writer.bytes_written();
        writer.add_environment_image(image)?;
        *bytes.entry("environment".into()).or_default() += writer.bytes_written() - before;
    }

    let materials = crate::materials::pack_materials(scene)?;
    for attributes in crate::materials::proxy_attributes(scene) {
        let before = writer.bytes_written();
        writer.add_proxy_attributes(&attributes)?;
        *bytes.entry("proxy_attributes".into()).or_default() += writer.bytes_written() - before;
    }
    for (i, image) in materials.images.iter().enumerate() {
        let before = writer.bytes_written();
        writer.add_texture(i as u32, image)?;
        *bytes.entry("textures".into()).or_default() += writer.bytes_written() - before;
    }
    for (object, material) in manifest.objects.iter_mut().zip(&materials.object_material) {
        object.material = *material;
    }
    manifest.textures = materials.textures;
    manifest.materials = materials.materials;

    let cost = plan.cost(0.0);
    let s = &mut manifest.stats;
    s.sample_counts
        .insert("range_images".into(), cost.range_images);
    s.sample_counts
        .insert("range_image_texels".into(), cost.range_image_texels);
    s.sample_counts
        .insert("camera_samples".into(), cost.camera_samples);
    s.sample_counts
        .insert("volume_samples".into(), volume_samples);
    s.sample_counts
        .insert("ambient_fields".into(), cost.ambient_fields);
    s.sample_counts
        .insert("base_views".into(), plan.base_views.len() as u64);
    s.bytes = bytes;
    if options.timings_in_manifest {
        s.phase_seconds = options.timings.clone();
    }
    writer.finish(&manifest)?;
    Ok(manifest)
}

/// Writes wall-clock timings to the sidecar [`timings_path`] of `output`.
pub fn write_timings(output: &Path, timings: &BTreeMap<String, f64>) -> Result<()> {
    let sidecar = timings_path(output);
    let json = serde_json::to_string_pretty(timings).unwrap_or_default();
    std::fs::write(&sidecar, json).map_err(|e| BakeError::io(&sidecar, e))
}

/// The timings sidecar of a pack: `<output>.timings.json`.
pub fn timings_path(output: &Path) -> PathBuf {
    let mut name = output.as_os_str().to_owned();
    name.push(".timings.json");
    PathBuf::from(name)
}

#[cfg(test)]
mod environment_tests {
    use super::*;
    use plenoptic_pack::EnvironmentSource;
    use plenoptic_pack::plenoptic_sky::SkyParams;
    use plenoptic_scene::{Environment, Sun, SunTrack, SunTrackSample};

    #[test]
    fn the_manifest_carries_the_scenes_environment_and_sun_track() {
        // A scene without either declares none: black where no proxy is.
        let none = environment_entry(0.0, 1.0, &Scene::default(), true).unwrap();
        assert_eq!(none, EnvironmentEntry::new(&Environment::None, None));
        let track = SunTrack::new(vec![
            SunTrackSample {
                time: 0.0,
                direction: glam::Vec3::X,
                illuminance: glam::Vec3::splat(1e5),
            },
            SunTrackSample {
                time: 1.0,
                direction: glam::Vec3::Y,
                illuminance: glam::Vec3::splat(1e5),
            },
        ])
        .unwrap();
        let scene = Scene {
            environment: Environment::Sky(SkyParams::default()),
            sun: Some(Sun {
                light: 0,
                track: Some(track.clone()),
            }),
            ..Scene::default()
        };
        let entry = environment_entry(0.0, 1.0, &scene, true).unwrap();
        assert_eq!(
            entry.source,
            EnvironmentSource::Sky {
                params: SkyParams::default()
            }
        );
        assert_eq!(entry.sun, Some(track));
        let uniform = Scene {
            environment: Environment::Uniform(glam::Vec3::ONE),
            ..Scene::default()
        };
        let entry = environment_entry(0.0, 1.0, &uniform, true).unwrap();
        assert_eq!(entry.sun, None);
        assert!(matches!(entry.source, EnvironmentSource::Uniform { .. }));
    }
}
