//! Light groups in the bake (docs/pack-format.md, "Light groups"; [`plenoptic_scene::groups`]).
//!
//! A scene with declared groups is rendered once per *layer*: each declared group, and the
//! default group when it holds an emitter, with only its emitters on
//! ([`Scene::group_only`]). The plan (base views, time keys, ambient key times) is the whole
//! scene's and is shared; each layer gets its own scene, acceleration structure and ambient
//! fields at the plan's ambient key times. Every range image and volume sample is rendered per
//! layer with the same random streams; the total the pack stores in its lighting cubes is the
//! layers' sum, and the declared groups' lighting and non-diffuse radiance are stored beside
//! it (all but the last when the default group is empty: that one is the total less the
//! others, [`LightGroupsEntry::stored`]). So the total equals the sum of its groups exactly
//! (up to quantisation) and a reader may scale each. The geometry (distance, id, normal) does not depend on the emitters and is
//! taken from the first layer.
//!
//! Cost: every rendering of the bake is done once per layer; the ambient key times are chosen
//! on the sum of the layers' fields ([`crate::plan::layered_ambient_phase`]), so the whole
//! scene's fields are never gathered. The tour's three groups take 1.85× its ungrouped bake
//! (docs/results/measurements.md, "Light groups on the tour").

use glam::Vec3;
use plenoptic_pack::{
    ChunkKind, CubeImage, GroupWeights, LightGroupsEntry, RangeImage, encode_radiance,
};
use plenoptic_scene::Scene;
use plenoptic_trace::{AmbientField, SceneAccel};

use crate::volume::LayeredVolume;
use crate::work::ItemChunk;

/// The light layers of `scene`: `(group, scene with only that group on)`, declared groups
/// first, then the default group (`None`) when it holds an emitter. Empty for a scene
/// without groups (the bake then renders the scene itself).
pub fn layer_scenes(scene: &Scene) -> Vec<(Option<u32>, Scene)> {
    let groups = &scene.light_groups;
    if groups.is_empty() {
        return Vec::new();
    }
    let mut out: Vec<(Option<u32>, Scene)> = (0..groups.names.len() as u32)
        .map(|g| (Some(g), scene.group_only(Some(g))))
        .collect();
    if groups.default_has_emitters(scene) {
        out.push((None, scene.group_only(None)));
    }
    out
}

/// One light layer as the renderer uses it.
pub struct Layer<'a> {
    /// Its group (`None`: the default group).
    pub group: Option<u32>,
    /// Whether its lighting is stored as a layer of its own (else it is the total less the
    /// stored layers).
    pub stored: bool,
    /// The scene with only the group's emitters on.
    pub accel: &'a SceneAccel<'a>,
    /// Its ambient fields at the plan's ambient key times.
    pub fields: &'a [AmbientField],
}

/// A range image rendered per layer: the total the pack stores in its ordinary chunks, and
/// each declared group's image.
pub struct LayeredImage {
    /// The sum of the layers (or the scene's own image without groups).
    pub total: RangeImage,
    /// `(declared group, its image)`.
    pub groups: Vec<(u32, RangeImage)>,
}

/// The sum of per-layer range images of one view and key: radiance, lighting and non-diffuse
/// radiance add; the geometry is the first image's. `None` for no images.
pub fn sum_images(images: &[&RangeImage]) -> Option<RangeImage> {
    let (first, rest) = images.split_first()?;
    let mut total = (*first).clone();
    let add = |a: &mut CubeImage<Vec3>, b: &CubeImage<Vec3>| {
        for (x, y) in a.texels.iter_mut().zip(&b.texels) {
            *x += *y;
        }
    };
    for image in rest {
        add(&mut total.radiance, &image.radiance);
        add(&mut total.lighting, &image.lighting);
        add(&mut total.non_diffuse, &image.non_diffuse);
    }
    Some(total)
}

/// Whether the pack of `scene` stores `group`'s layers ([`LightGroupsEntry::stored`]).
pub fn is_stored(scene: &Scene, group: Option<u32>) -> bool {
    let entry = manifest_entry(scene);
    group.is_some_and(|g| entry.is_some_and(|e| e.stored().contains(&g)))
}

/// The manifest's `light_groups` for `scene` (`None` without groups). Manifest lights and
/// objects are the scene's, in the same order.
pub fn manifest_entry(scene: &Scene) -> Option<LightGroupsEntry> {
    let groups = &scene.light_groups;
    if groups.is_empty() {
        return None;
    }
    Some(LightGroupsEntry {
        names: groups.names.clone(),
        lights: (0..scene.lights.len()).map(|i| groups.light(i)).collect(),
        objects: (0..scene.objects.len()).map(|i| groups.object(i)).collect(),
        sun: groups.sun(scene),
        sky: groups.sky,
        default_has_emitters: groups.default_has_emitters(scene),
    })
}

/// Parses `settings` (`NAME=I` or `NAME=R,G,B`, [`plenoptic_pack::groups::parse_setting`])
/// into weights over the groups `names`.
pub fn weights(names: &[String], settings: &[String]) -> crate::Result<GroupWeights> {
    let parsed = settings
        .iter()
        .map(|s| plenoptic_pack::groups::parse_setting(s))
        .collect::<std::result::Result<Vec<_>, _>>()
        .map_err(crate::BakeError::Invalid)?;
    GroupWeights::from_names(names, &parsed).map_err(crate::BakeError::Invalid)
}

/// `scene` relit with its light groups at `settings` (what `plenoptic reference --light`
/// path-traces).
pub fn relit_scene(scene: &Scene, settings: &[String]) -> crate::Result<Scene> {
    if settings.is_empty() {
        return Ok(scene.clone());
    }
    let w = weights(&scene.light_groups.names, settings)?;
    Ok(scene.relit(|g| w.weight(g)))
}

/// The light groups' chunks of a range image: each stored group's lighting and non-diffuse
/// cubes, rounded against the total ([`crate::quantise::coarsen_group`]).
pub fn layer_chunks(bv: u32, key: u32, layered: &LayeredImage) -> crate::Result<Vec<ItemChunk>> {
    let mut out = Vec::with_capacity(2 * layered.groups.len());
    let format = crate::write::FORMATS.radiance;
    for (g, group) in &layered.groups {
        let group = crate::quantise::coarsen_group(group, &layered.total);
        for (kind, cube) in [
            (ChunkKind::GroupLighting(*g), &group.lighting),
            (ChunkKind::GroupNonDiffuse(*g), &group.non_diffuse),
        ] {
            out.push(ItemChunk {
                kind,
                base_view: bv,
                key,
                uncompressed_length: 0,
                bytes: encode_radiance(cube, format)?,
            });
        }
    }
    Ok(out)
}

/// The light groups' chunks of the volume block of base view `bv` in bucket `bucket`, whose
/// samples are `volume`'s `members` stored in `order`: each stored group's values, rounded
/// against the total's.
pub fn volume_layer_chunks(
    bv: u32,
    bucket: u32,
    volume: &LayeredVolume,
    members: &[usize],
    order: &[u32],
) -> crate::Result<Vec<ItemChunk>> {
    let mut out = Vec::with_capacity(volume.groups.len());
    for (g, values) in &volume.groups {
        let values: Vec<[Vec3; 2]> = members
            .iter()
            .map(|&i| {
                // A sample's group radiance is not kept: its non-diffuse part is rounded
                // against the total's radiance alone.
                let (total, [l, nd]) = (&volume.samples[i], values[i]);
                [
                    crate::quantise::coarsen_layer(l, l, total.lighting),
                    crate::quantise::coarsen_layer(nd, total.radiance, total.radiance),
                ]
            })
            .collect();
        let (bytes, len) = plenoptic_pack::groups::encode_group_volume(&values, order)?;
        out.push(ItemChunk {
            kind: ChunkKind::GroupVolume(*g),
            base_view: bv,
            key: bucket,
            uncompressed_length: len,
            bytes,
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    #[test]
    fn groups_are_as_many_as_the_pack_allows() {
        assert_eq!(
            plenoptic_scene::recipe::MAX_GROUPS,
            plenoptic_pack::MAX_LIGHT_GROUPS
        );
    }
}
