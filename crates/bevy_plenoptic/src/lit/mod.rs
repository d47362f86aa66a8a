//! Your own meshes lit by the pack: every plenoptic camera gets an environment light made
//! from the pack's radiance around it at its time, so that a `StandardMaterial` mesh the
//! app adds (a character, a prop the player carries, anything not baked) is lit by the baked
//! scene's light, diffuse and specular, as Bevy lights meshes from a light probe.
//!
//! The light is Bevy's own [`GeneratedEnvironmentMapLight`] on the camera: Bevy filters a
//! source cubemap on the GPU every frame into the diffuse (Lambert-convolved) and specular
//! (GGX, one mip per roughness) maps of an `EnvironmentMapLight`. The source is written here
//! ([`PackEnvironmentLight`]): the radiance cube of the camera's heaviest base view (the
//! largest of `ReconSettings::view_weights`, as the reconstruction weighs them) at the
//! camera's time, its two bracketing keys blended with their linear time weights
//! (`plenoptic_recon::temporal::bracketing`, as geometry-assisted mode blends them), from
//! the keys the streaming cache holds. It is resampled to a power-of-two face (Bevy's
//! filter needs one) and rewritten when the view, the keys or the time weight change.
//!
//! What this is not: the light is the radiance seen from the base view's position, applied
//! to the whole view as if from infinitely far (no parallax correction), so a mesh far from
//! that base view is lit by light arriving where the base view stands. On a pack whose sun is
//! left to the runtime, the sun's direct light reaches the app's meshes through the
//! plugin's sun light ([`crate::reconstruct::geometry::sun`]), and the radiance cube lacks
//! the light the sunlit surfaces would bounce.
//!
//! A camera that already has an `EnvironmentMapLight` or a `GeneratedEnvironmentMapLight`
//! of its own keeps it; [`crate::PlenopticSettings::environment_light`] turns this off.
//!
//! The pack's light is the scene's whole indirect light, so a camera given it also gets an
//! [`AmbientLight`] of zero brightness, unless it has an `AmbientLight` of its own. Bevy's
//! `GlobalAmbientLight` (80 cd/m² by default) otherwise lights every `StandardMaterial` mesh
//! evenly on top of the probes: at the exposure a pack is shown with (about 1 for the tour,
//! [`crate::camera::EV100_UNIT`]) that is hundreds of times the baked interior's light: the
//! `own_scene` example's white sphere would show as a white disc.
//!
//! Meshes near a base view are lit by that view's own cube instead, through a light probe
//! at the base view ([`probes`]; where the device has binding arrays); the camera's light
//! serves the meshes outside every probe. Their diffuse light comes from an irradiance
//! volume over the scene, each voxel taking the ambient cube of its nearest base view
//! ([`volume`]), on every device.

pub mod exclusive;
mod lighting;
pub mod probes;
pub mod scene;
pub mod volume;

use std::collections::HashMap;

use bevy::asset::RenderAssetUsages;
use bevy::light::{AmbientLight, EnvironmentMapLight, GeneratedEnvironmentMapLight};
use bevy::prelude::*;
use bevy::render::render_resource::{
    Extent3d, TextureDimension, TextureFormat, TextureUsages, TextureViewDescriptor,
    TextureViewDimension,
};
use plenoptic_pack::cube::{direction_to_texel, rgb9e5_unpack, texel_direction};
use plenoptic_recon::relight::Relight;
use plenoptic_recon::temporal::bracketing;

use crate::asset::RadiancePack;
use crate::camera::PlenopticCamera;
use crate::reconstruct::relight::weight_bits;
use crate::settings::{PlenopticSettings, PlenopticSystems};
use crate::streaming::{DecodedKey, StreamCache};

/// Smallest and largest face of the source cubemap (it is resampled to a power of two in
/// this range, the nearest above the pack's face).
const FACE_RANGE: (u32, u32) = (16, 256);

/// Adds the environment light of each plenoptic camera.
#[derive(Debug, Default)]
pub struct PlenopticLitPlugin;

impl Plugin for PlenopticLitPlugin {
    fn build(&self, app: &mut App) {
        app.add_systems(
            Update,
            (
                update_environment_lights,
                probes::update_probes,
                volume::update_volumes,
            )
                .chain()
                .after(PlenopticSystems::Streaming),
        )
        .init_resource::<probes::ProbeKeys>();
        scene::build(app);
        exclusive::build(app);
    }

    fn finish(&self, app: &mut App) {
        // Bevy's own test (bevy_pbr's `binding_arrays_are_usable`, not public): without
        // binding arrays it ignores reflection probes, so the probes' cubemaps would be
        // filtered every frame for nothing.
        let usable = app
            .get_sub_app(bevy::render::RenderApp)
            .and_then(|r| {
                r.world()
                    .get_resource::<bevy::render::renderer::RenderDevice>()
            })
            .is_some_and(|d| {
                use bevy::render::settings::WgpuFeatures;
                d.features().contains(
                    WgpuFeatures::TEXTURE_BINDING_ARRAY
                        | WgpuFeatures::SAMPLED_TEXTURE_AND_STORAGE_BUFFER_ARRAY_NON_UNIFORM_INDEXING,
                ) && d.limits().max_binding_array_elements_per_shader_stage >= 24
                    && d.limits().max_binding_array_sampler_elements_per_shader_stage >= 24
            });
        app.insert_resource(probes::ReflectionProbes(usable));
    }
}

/// The pack's environment light of a camera: the source cubemap the plugin writes and what
/// it was last written from.
#[derive(Component, Debug, Clone)]
pub struct PackEnvironmentLight {
    /// The source cubemap (`Rgba16Float`, six layers, a cube view).
    pub image: Handle<Image>,
    /// (pack, base view, keys and their time weight's bits) of its content.
    built_for: Option<Source>,
}

/// What a source cubemap holds: pack, view, (key, weight bits) of each blended key, and the
/// bits of the light-group weights it is relit at.
pub(crate) type Source = (AssetId<RadiancePack>, u32, Vec<(u32, u32)>, Vec<u32>);

/// `radiance`, key `data`'s radiance, relit at `relight` (`plenoptic_recon::relight`): from
/// its lighting, non-diffuse and group layers as the GPU streams them; as baked where it
/// has none (a key decoded for the CPU backend keeps no group layers).
fn relit(data: &DecodedKey, relight: &Relight, radiance: Vec<Vec3>) -> Vec<Vec3> {
    if relight.is_identity() {
        return radiance;
    }
    let n = radiance.len();
    let words = |b: &[u8]| -> Option<Vec<u32>> {
        (b.len() == 4 * n).then(|| {
            let word = |c: &[u8]| u32::from_le_bytes([c[0], c[1], c[2], c[3]]);
            b.chunks_exact(4).map(word).collect()
        })
    };
    let colours = |b: &[u8]| words(b).map(|w| w.into_iter().map(rgb9e5_unpack).collect());
    let stored: Option<[Vec<Vec3>; 2]> = (|| {
        Some([
            colours(data.lighting.as_deref()?)?,
            colours(data.non_diffuse.as_deref()?)?,
        ])
    })();
    let layers: Option<Vec<[Vec<Vec3>; 2]>> = (data.groups.iter())
        .map(|[l, nd]| Some([colours(l)?, colours(nd)?]))
        .collect();
    let (Some([l, nd]), Some(layers), Some(ids)) = (stored, layers, words(&data.object_id)) else {
        return radiance;
    };
    let layer = |g: u32, c: usize| layers.get(g as usize).map(|x| &x[c][..]);
    let blended = (
        relight.blend_texels(&l, |g| layer(g, 0)),
        relight.blend_texels(&nd, |g| layer(g, 1)),
    );
    let (Some(lw), Some(ndw)) = blended else {
        return radiance;
    };
    relight.relit_texels(&radiance, [&l, &nd], [&lw, &ndw], |i| ids[i] == 0)
}

/// The radiance of key `data` as linear RGB per texel, if its format is one the pack writes.
fn radiance(data: &DecodedKey) -> Option<Vec<Vec3>> {
    let n = data.face_size as usize;
    let texels = 6 * n * n;
    let bytes = &data.radiance;
    // Decoded for the CPU backend: the cube itself.
    if let Some((_, plenoptic_recon::StreamedCube::Colour(c))) = data
        .cpu
        .iter()
        .find(|(k, _)| *k == plenoptic_pack::ChunkKind::RadianceCube)
    {
        return (c.texels.len() == texels).then(|| c.texels.clone());
    }
    if bytes.len() == 4 * texels {
        Some(
            bytes
                .chunks_exact(4)
                .map(|b| rgb9e5_unpack(u32::from_le_bytes([b[0], b[1], b[2], b[3]])))
                .collect(),
        )
    } else if bytes.len() == 8 * texels {
        let h = |b: &[u8], i: usize| half::f16::from_le_bytes([b[i], b[i + 1]]).to_f32();
        Some(
            bytes
                .chunks_exact(8)
                .map(|b| Vec3::new(h(b, 0), h(b, 2), h(b, 4)))
                .collect(),
        )
    } else {
        None
    }
}

/// The face of the source cubemap for a pack face of `face` texels.
pub fn source_face(face: u32) -> u32 {
    face.max(1)
        .next_power_of_two()
        .clamp(FACE_RANGE.0, FACE_RANGE.1)
}

/// For each texel of a Bevy cubemap of face `out`, the pack texel (face `face`) holding the
/// radiance of its direction. Bevy samples cubemaps with z negated (they are left-handed),
/// so texel direction `c` of the cubemap shows world direction `(c.x, c.y, −c.z)`.
pub fn texel_map(face: u32, out: u32) -> Vec<usize> {
    (0..6 * (out as usize).pow(2))
        .map(|i| {
            let c = texel_direction(out, i);
            direction_to_texel(face, Vec3::new(c.x, c.y, -c.z))
        })
        .collect()
}

/// The source cubemap of `keys` (radiance per texel of a pack face `face`, weight), blended.
pub fn source_image(face: u32, keys: &[(Vec<Vec3>, f32)], map: &[usize]) -> Image {
    let out = source_face(face);
    let mut data = Vec::with_capacity(map.len() * 8);
    for &texel in map {
        let c: Vec3 = keys.iter().map(|(r, w)| r[texel] * *w).sum();
        for x in [c.x, c.y, c.z, 1.0] {
            data.extend_from_slice(&half::f16::from_f32(x).to_le_bytes());
        }
    }
    let mut image = Image::new(
        Extent3d {
            width: out,
            height: out,
            depth_or_array_layers: 6,
        },
        TextureDimension::D2,
        data,
        TextureFormat::Rgba16Float,
        RenderAssetUsages::RENDER_WORLD,
    );
    image.texture_descriptor.usage = TextureUsages::TEXTURE_BINDING | TextureUsages::COPY_DST;
    image.texture_view_descriptor = Some(TextureViewDescriptor {
        dimension: Some(TextureViewDimension::Cube),
        ..default()
    });
    image
}

/// Radiance cubes (per texel) with their weights.
pub(crate) type WeightedCubes = Vec<(Vec<Vec3>, f32)>;

/// Base view `v` of `pack` at time `t` from the resident keys, relit at `relight`: what its
/// blended source would hold (time weights quantised to `1 / steps`), its face and each
/// key's radiance with its weight; `None` when none of its bracketing keys is resident or
/// readable.
pub(crate) fn view_source(
    cache: &StreamCache,
    (id, pack): (AssetId<RadiancePack>, &RadiancePack),
    v: usize,
    t: f32,
    steps: f32,
    relight: &Relight,
) -> Option<(Source, u32, WeightedCubes)> {
    let m = pack.reader.manifest();
    let (k0, k1, f) = bracketing(&m.base_views.get(v)?.time_keys, t)?;
    let mut wanted = vec![(k0, 1.0 - f)];
    if k1 != k0 {
        wanted.push((k1, f));
    }
    // The resident ones, their weights renormalised.
    let resident: Vec<_> = wanted
        .into_iter()
        .filter(|&(_, w)| w > 1e-4)
        .filter_map(|(k, w)| Some((k, w, cache.get(id, (v as u32, k as u32))?.data.clone())))
        .collect();
    let total: f32 = resident.iter().map(|r| r.1).sum();
    if resident.is_empty() || total <= 0.0 {
        return None;
    }
    // Quantised, so that a playing camera rewrites the cubemap `steps` times per key
    // interval at most.
    let source: Source = (
        id,
        v as u32,
        resident
            .iter()
            .map(|r| (r.0 as u32, ((r.1 / total) * steps).round() as u32))
            .collect(),
        weight_bits(&relight.weights),
    );
    let face = resident[0].2.face_size;
    let keys = resident
        .iter()
        .map(|(_, w, data)| {
            (data.face_size == face)
                .then(|| radiance(data))
                .flatten()
                .map(|r| (relit(data, relight, r), w / total))
        })
        .collect::<Option<Vec<_>>>()?;
    Some((source, face, keys))
}

/// A camera and what it has of an environment light.
type LitCamera<'a> = (
    Entity,
    &'a PlenopticCamera,
    &'a GlobalTransform,
    Option<&'a mut PackEnvironmentLight>,
    Has<EnvironmentMapLight>,
    Has<GeneratedEnvironmentMapLight>,
    Has<AmbientLight>,
);

/// Writes each camera's source cubemap when its heaviest view, keys or time weight change,
/// and gives a camera without an environment light of its own the generated one (and no
/// ambient light, unless it has one of its own).
fn update_environment_lights(
    mut commands: Commands,
    settings: Res<PlenopticSettings>,
    cache: Res<StreamCache>,
    packs: Res<Assets<RadiancePack>>,
    mut cameras: Query<LitCamera>,
    mut images: ResMut<Assets<Image>>,
    mut maps: Local<HashMap<(u32, u32), Vec<usize>>>,
) {
    if !settings.environment_light {
        return;
    }
    for (entity, cam, transform, ours, has_map, has_generated, has_ambient) in &mut cameras {
        if ours.is_none() && (has_map || has_generated) {
            // The app's own environment light.
            continue;
        }
        let id = cam.pack.id();
        let Some(pack) = packs.get(id) else {
            continue;
        };
        let m = pack.reader.manifest();
        let views = cam
            .settings
            .view_weights(m, &pack.usable_views, transform.translation());
        let Some(&(v, _)) = views.first() else {
            continue;
        };
        let relight = cam.lights.relight(m);
        let Some((source, face, keys)) =
            view_source(&cache, (id, pack), v, cam.time, 256.0, &relight)
        else {
            continue;
        };
        if ours.as_ref().and_then(|o| o.built_for.as_ref()) == Some(&source) {
            continue;
        }
        let map = maps
            .entry((face, source_face(face)))
            .or_insert_with(|| texel_map(face, source_face(face)));
        let image = source_image(face, &keys, map);
        match ours {
            Some(mut light) => {
                images.insert(&light.image, image).ok();
                light.built_for = Some(source);
            }
            None => {
                let handle = images.add(image);
                commands.entity(entity).insert((
                    PackEnvironmentLight {
                        image: handle.clone(),
                        built_for: Some(source),
                    },
                    GeneratedEnvironmentMapLight {
                        environment_map: handle,
                        // The pack's radiance as stored; the camera's exposure applies, as to
                        // the reconstructed frame.
                        intensity: 1.0,
                        ..default()
                    },
                ));
                if !has_ambient {
                    // The pack's light replaces Bevy's uniform stand-in for indirect light.
                    commands.entity(entity).insert(AmbientLight {
                        brightness: 0.0,
                        ..default()
                    });
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The source cubemap shows each world direction's radiance: a pack cube whose texels
    /// hold their own world direction (as colour, shifted positive) is read back from the
    /// Bevy cubemap at the direction Bevy samples, (x, y, −z).
    #[test]
    fn texel_map_turns_bevy_cubemap_directions_into_pack_texels() {
        let (face, out) = (8, source_face(8));
        assert_eq!(out, 16);
        let pack: Vec<Vec3> = (0..6 * 64)
            .map(|i| texel_direction(face, i) + Vec3::ONE)
            .collect();
        let map = texel_map(face, out);
        let mut worst = 0.0f32;
        for (i, &t) in map.iter().enumerate() {
            let c = texel_direction(out, i);
            let world = Vec3::new(c.x, c.y, -c.z);
            let shown = pack[t] - Vec3::ONE;
            worst = worst.max(shown.angle_between(world));
        }
        // Half a pack texel's diagonal at most (8-texel faces: about 0.18 rad at the centre).
        assert!(worst < 0.2, "{worst}");
    }

    #[test]
    fn source_faces_are_powers_of_two_in_range() {
        for (face, out) in [
            (1, 16),
            (8, 16),
            (48, 64),
            (128, 128),
            (130, 256),
            (2048, 256),
        ] {
            assert_eq!(source_face(face), out, "{face}");
        }
    }

    #[test]
    fn blended_keys_and_formats() {
        let texel = |c: Vec3| rgb9e5_pack(c).to_le_bytes();
        use plenoptic_pack::cube::rgb9e5_pack;
        let key = |c: Vec3| DecodedKey {
            face_size: 1,
            radiance: (0..6).flat_map(|_| texel(c)).collect(),
            distance: vec![],
            object_id: vec![],
            normal: None,
            lighting: None,
            non_diffuse: None,
            groups: Vec::new(),
            cpu: Vec::new(),
        };
        let a = radiance(&key(Vec3::new(1.0, 0.5, 0.25))).unwrap();
        let b = radiance(&key(Vec3::new(3.0, 0.5, 0.0))).unwrap();
        assert!((a[0] - Vec3::new(1.0, 0.5, 0.25)).abs().max_element() < 1e-3);
        let map = texel_map(1, source_face(1));
        let image = source_image(1, &[(a, 0.75), (b, 0.25)], &map);
        let data = image.data.as_ref().unwrap();
        let h = |i: usize| half::f16::from_le_bytes([data[i], data[i + 1]]).to_f32();
        // 0.75 · 1 + 0.25 · 3 = 1.5, 0.5, 0.1875.
        let got = Vec3::new(h(0), h(2), h(4));
        assert!(
            (got - Vec3::new(1.5, 0.5, 0.1875)).abs().max_element() < 2e-3,
            "{got}"
        );
        let broken = DecodedKey {
            radiance: vec![0; 5],
            ..key(Vec3::ONE)
        };
        assert!(radiance(&broken).is_none());
        // A key decoded for the CPU backend: its radiance cube itself.
        let cube = plenoptic_pack::CubeImage::filled(1, Vec3::new(0.25, 0.5, 2.0));
        let cpu = DecodedKey {
            radiance: Vec::new(),
            cpu: vec![(
                plenoptic_pack::ChunkKind::RadianceCube,
                plenoptic_recon::StreamedCube::Colour(std::sync::Arc::new(cube.clone())),
            )],
            ..key(Vec3::ONE)
        };
        assert_eq!(radiance(&cpu), Some(cube.texels));
    }
}
