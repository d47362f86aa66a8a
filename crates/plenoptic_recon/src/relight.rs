//! Light groups at runtime: the baked animation relit by a colour × intensity per group
//! (docs/pack-format.md, "Light groups"; the blend is [`plenoptic_pack::groups`]'s).
//!
//! What the pack stores is scaled where it is read, once per chunk and set of weights: the
//! lighting and non-diffuse cubes and the volume blocks' values are blended from the total
//! and the layers of the groups whose weight differs ([`GroupWeights::blend`]) when the
//! chunk cache hands them out, and kept until the weights change. A lookup then reads one
//! blended texel as before, so the frame costs what it cost without groups; a change of
//! weights costs one pass over each resident chunk. What the runtime computes itself is
//! scaled where it is computed: the runtime sun by the sun's group, a placed lamp's highlight
//! by its light's group, the emission at a pixel's UV by its object's group, and the
//! environment (background, reflections, glazing) by the sky's group.
//!
//! The radiance (radiance cubes, volume samples' radiance), which glossy reflections answer
//! from and image and volume modes warp, is not split by group: it is scaled per texel and
//! channel by the ratio of the blended lighting + non-diffuse radiance to the stored one
//! ([`relit_radiance`]), and a texel that sees no object by the sky's weight. That is exact
//! where the texel's light is indirect or from one group; the sun's direct light and an
//! emitter's own emission, which the radiance holds and the lighting does not, are scaled by
//! the ratio of the light around them instead of their own group's weight.

use std::collections::HashMap;
use std::sync::Arc;

use glam::Vec3;
use plenoptic_pack::{
    ChunkKind, ChunkRef, CubeImage, GroupWeights, LayerBlend, Manifest, PackError, PackReader,
    VolumeBlock, VolumeSample,
};

use crate::Reconstructor;
use crate::cache::Cached;

/// The light groups' weights and what they give each emitter of a pack: the one definition
/// of every multiplier, which the CPU reconstructor applies and the plugin's GPU passes take
/// as uniforms.
#[derive(Debug, Clone, PartialEq)]
pub struct Relight {
    /// The weights as set.
    pub weights: GroupWeights,
    /// How the stored layers combine at them.
    pub blend: LayerBlend,
    /// The runtime sun's multiplier.
    pub sun: Vec3,
    /// The environment's multiplier.
    pub sky: Vec3,
    /// Per manifest light.
    lights: Vec<Vec3>,
    /// Per object id whose emission is scaled (absent: 1).
    objects: HashMap<u32, Vec3>,
}

impl Default for Relight {
    /// Every emitter as baked, for any pack.
    fn default() -> Self {
        Self {
            weights: GroupWeights::identity(),
            blend: GroupWeights::identity().blend(None),
            sun: Vec3::ONE,
            sky: Vec3::ONE,
            lights: Vec::new(),
            objects: HashMap::new(),
        }
    }
}

impl Relight {
    /// The multipliers of `manifest`'s emitters at `weights`. A pack without groups has one
    /// group, the default, whose weight scales everything.
    pub fn new(manifest: &Manifest, weights: &GroupWeights) -> Self {
        let entry = manifest.light_groups.as_ref();
        let of = |g: Option<u32>| weights.weight(g);
        let lights = (0..manifest.lights.len())
            .map(|i| of(entry.and_then(|e| e.lights.get(i).copied().flatten())))
            .collect();
        let objects = manifest
            .objects
            .iter()
            .enumerate()
            .map(|(i, o)| {
                (
                    o.id,
                    of(entry.and_then(|e| e.objects.get(i).copied().flatten())),
                )
            })
            .filter(|(_, w)| *w != Vec3::ONE)
            .collect();
        Self {
            weights: weights.clone(),
            blend: weights.blend(entry),
            sun: of(entry.and_then(|e| e.sun)),
            sky: of(entry.and_then(|e| e.sky)),
            lights,
            objects,
        }
    }

    /// The volume block of base view `view` in `bucket` read from `pack` and relit at these
    /// weights (its samples' lighting, non-diffuse and radiance, as the chunk cache hands
    /// blocks out); as stored where the blend is the identity. The error names the chunk.
    pub fn volume_block(
        &self,
        pack: &PackReader,
        view: u32,
        bucket: u32,
    ) -> plenoptic_pack::Result<VolumeBlock> {
        let block = pack.volume_block(view, bucket)?;
        if self.blend.is_identity() {
            return Ok(block);
        }
        let layers = (self.blend.layers.iter())
            .map(|&(g, _)| pack.group_volume(view, bucket, g).map(Arc::new))
            .collect::<plenoptic_pack::Result<Vec<_>>>()?;
        blend_block(self, &block, &layers).ok_or_else(|| {
            let kind = ChunkKind::GroupVolume(self.blend.layers[0].0);
            PackError::LightGroupMismatch {
                chunk: ChunkRef {
                    index: pack.find(kind, view, bucket).unwrap_or(0),
                    kind,
                    base_view: view,
                    key: bucket,
                },
                problem: "its samples are not the volume block's".to_string(),
            }
        })
    }

    /// Whether these weights leave the pack as baked.
    pub fn is_identity(&self) -> bool {
        self.blend.is_identity() && self.sky == Vec3::ONE
    }

    /// The radiance cube of (view, key) read from `pack` and relit at these weights, as the
    /// chunk cache hands it out: as stored at the identity or where the pack has no lighting
    /// cubes. The error names the chunk.
    pub fn radiance_cube(
        &self,
        pack: &PackReader,
        view: u32,
        key: u32,
    ) -> plenoptic_pack::Result<plenoptic_pack::RadianceCube> {
        let radiance = pack.radiance(view, key)?;
        let lit = pack.find(ChunkKind::LightingCube, view, key).is_some()
            && pack.find(ChunkKind::NonDiffuseCube, view, key).is_some();
        if self.is_identity() || !lit {
            return Ok(radiance);
        }
        let (l, nd) = (pack.lighting(view, key)?, pack.non_diffuse(view, key)?);
        let ids = pack.object_id(view, key)?;
        let mut layers = HashMap::new();
        for &(g, _) in &self.blend.layers {
            let lg = pack.group_lighting(view, key, g)?;
            layers.insert(g, (lg, pack.group_non_diffuse(view, key, g)?));
        }
        let pick = |g: u32, nd: bool| {
            let (a, b) = layers.get(&g)?;
            Some(if nd { &b.texels[..] } else { &a.texels[..] })
        };
        let blended = (
            self.blend_texels(&l.texels, |g| pick(g, false)),
            self.blend_texels(&nd.texels, |g| pick(g, true)),
        );
        let n = radiance.texels.len();
        let sizes_agree = [l.texels.len(), nd.texels.len(), ids.texels.len()] == [n; 3];
        let (Some(lw), Some(ndw), true) = (blended.0, blended.1, sizes_agree) else {
            let first = self.blend.layers.first();
            let kind = first.map_or(ChunkKind::LightingCube, |l| ChunkKind::GroupLighting(l.0));
            return Err(PackError::LightGroupMismatch {
                chunk: ChunkRef {
                    index: pack.find(kind, view, key).unwrap_or(0),
                    kind,
                    base_view: view,
                    key,
                },
                problem: "its cubes are not the key's size".to_string(),
            });
        };
        let texels = self.relit_texels(
            &radiance.texels,
            [&l.texels, &nd.texels],
            [&lw, &ndw],
            |i| ids.texels[i] == 0,
        );
        Ok(CubeImage {
            face_size: radiance.face_size,
            texels,
        })
    }

    /// Radiance texels relit (the module doc): `stored` and `relit` are each texel's
    /// (lighting, non-diffuse) before and after the blend, `sees_sky(i)` whether texel `i`
    /// sees no object (scaled by the sky's weight where its stored light is zero).
    pub fn relit_texels(
        &self,
        radiance: &[Vec3],
        stored: [&[Vec3]; 2],
        relit: [&[Vec3]; 2],
        sees_sky: impl Fn(usize) -> bool,
    ) -> Vec<Vec3> {
        (0..radiance.len())
            .map(|i| {
                let fallback = if sees_sky(i) {
                    self.sky
                } else {
                    self.blend.base
                };
                let old = stored[0][i] + stored[1][i];
                relit_radiance(radiance[i], old, relit[0][i] + relit[1][i], fallback)
            })
            .collect()
    }

    /// A colour cube's texels blended from its total and its groups' layers (`layer(g)`: group
    /// `g`'s texels, for each group the blend reads); `None` where a layer is missing or of
    /// another length.
    pub fn blend_texels<'a>(
        &self,
        total: &[Vec3],
        layer: impl Fn(u32) -> Option<&'a [Vec3]>,
    ) -> Option<Vec<Vec3>> {
        let layers = (self.blend.layers.iter())
            .map(|&(g, _)| layer(g).filter(|l| l.len() == total.len()))
            .collect::<Option<Vec<_>>>()?;
        Some(blend_slice(&self.blend, total, &layers))
    }

    /// Manifest light `i`'s multiplier.
    pub fn light(&self, i: usize) -> Vec3 {
        self.lights.get(i).copied().unwrap_or(Vec3::ONE)
    }

    /// The multiplier of object `id`'s emission.
    pub fn object(&self, id: u32) -> Vec3 {
        self.objects.get(&id).copied().unwrap_or(Vec3::ONE)
    }
}

/// Chunks blended at the current weights, by (kind, view, key); cleared when they change.
#[derive(Default)]
pub(crate) struct Memo {
    map: HashMap<(ChunkKind, u32, u32), Cached>,
    bytes: usize,
}

/// Whether chunks of `kind` hold light that the groups' weights scale.
pub(crate) fn blended(kind: ChunkKind) -> bool {
    matches!(
        kind,
        ChunkKind::RadianceCube
            | ChunkKind::LightingCube
            | ChunkKind::NonDiffuseCube
            | ChunkKind::VolumeBlock
    )
}

/// Stored radiance `radiance` relit by the ratio, per channel, of the relit light `new` to
/// the stored light `old` (each lighting + non-diffuse radiance); `fallback` where the stored
/// light is zero. The plugin's `relight.wgsl` does the same per texel.
pub fn relit_radiance(radiance: Vec3, old: Vec3, new: Vec3, fallback: Vec3) -> Vec3 {
    let ratio = Vec3::select(old.cmpgt(Vec3::splat(1e-12)), new / old, fallback);
    radiance * ratio
}

/// The group layer of `kind` for group `g`.
fn layer_kind(kind: ChunkKind, g: u32) -> ChunkKind {
    match kind {
        ChunkKind::LightingCube => ChunkKind::GroupLighting(g),
        ChunkKind::NonDiffuseCube => ChunkKind::GroupNonDiffuse(g),
        _ => ChunkKind::GroupVolume(g),
    }
}

/// `blend` of texels `total` and their layers (each as long, in the blend's order).
fn blend_slice(blend: &LayerBlend, total: &[Vec3], layers: &[&[Vec3]]) -> Vec<Vec3> {
    (0..total.len())
        .map(|i| blend.apply(total[i], |k| layers[k][i]))
        .collect()
}

/// `blend` of a colour cube's total and its layers (same face size, else `None`).
fn blend_cube(
    blend: &LayerBlend,
    total: &CubeImage<Vec3>,
    layers: &[Arc<CubeImage<Vec3>>],
) -> Option<CubeImage<Vec3>> {
    if layers.iter().any(|l| l.face_size != total.face_size) {
        return None;
    }
    let layers: Vec<&[Vec3]> = layers.iter().map(|l| &l.texels[..]).collect();
    Some(CubeImage {
        face_size: total.face_size,
        texels: blend_slice(blend, &total.texels, &layers),
    })
}

/// `blend` of a volume block's samples' lighting and non-diffuse values (each layer as long
/// as the block, else `None`). The radiance stays the total's.
fn blend_block(
    relight: &Relight,
    block: &VolumeBlock,
    layers: &[Arc<Vec<[Vec3; 2]>>],
) -> Option<VolumeBlock> {
    if layers.iter().any(|l| l.len() != block.samples.len()) {
        return None;
    }
    let blend = &relight.blend;
    let samples = (block.samples.iter().enumerate())
        .map(|(i, s)| {
            let lighting = blend.apply(s.lighting, |k| layers[k][i][0]);
            let non_diffuse = blend.apply(s.non_diffuse, |k| layers[k][i][1]);
            let fallback = if s.object_id == 0 {
                relight.sky
            } else {
                blend.base
            };
            let (old, new) = (s.lighting + s.non_diffuse, lighting + non_diffuse);
            VolumeSample {
                radiance: relit_radiance(s.radiance, old, new, fallback),
                lighting,
                non_diffuse,
                ..*s
            }
        })
        .collect();
    Some(VolumeBlock {
        samples,
        ..block.clone()
    })
}

/// The chunks of `blend`'s layers in its order, each `layer(g)` as `pick` takes it; `Err` with
/// the first layer's failure, or `Err(None)` where a layer is absent or of another kind.
fn stored_layers<T>(
    blend: &LayerBlend,
    layer: impl Fn(u32) -> Cached,
    pick: impl Fn(Cached) -> Option<T>,
) -> Result<Vec<T>, Option<Cached>> {
    blend
        .layers
        .iter()
        .map(|&(g, _)| match layer(g) {
            failed @ Cached::Failed(_) => Err(Some(failed)),
            other => pick(other).ok_or(None),
        })
        .collect()
}

impl Reconstructor {
    /// Sets each light group's colour × intensity (a pack without groups has the default group
    /// alone); frames from now on show the pack relit (see the module doc).
    pub fn set_light_weights(&mut self, weights: GroupWeights) {
        let relight = Relight::new(self.pack.manifest(), &weights);
        if relight != *self.relight {
            self.relight = Arc::new(relight);
            *self.relit.lock().unwrap_or_else(|e| e.into_inner()) = Memo::default();
        }
    }

    /// The pack's environment at time `t` (sky, ground, image or colour), scaled by the sky's
    /// group.
    pub fn environment_at(&self, t: f32) -> plenoptic_pack::plenoptic_sky::PlacedEnvironment {
        self.environment().at(t).scaled(self.relight.sky)
    }

    /// The pack's runtime lamps ([`crate::lamps::runtime_lamps`]), each scaled by its light's
    /// group.
    pub fn runtime_lamps(&self) -> Option<Vec<crate::lamps::RuntimeLamp>> {
        let mut lamps = crate::lamps::runtime_lamps(self.pack.manifest())?;
        for lamp in &mut lamps {
            lamp.radiant *= self.relight.light(lamp.light);
        }
        Some(lamps)
    }

    /// The lamps whose direct diffuse light the pack leaves to the runtime
    /// ([`plenoptic_pack::PackReader::lamps_at_runtime`], [`crate::lamps::diffuse`]), each
    /// scaled by its light's group; empty where the lighting holds it.
    pub fn lamps_lit_at_runtime(&self) -> Vec<crate::lamps::RuntimeLamp> {
        if !self.pack.lamps_at_runtime() {
            return Vec::new();
        }
        self.runtime_lamps().unwrap_or_default()
    }

    /// The light groups' weights in use.
    pub fn light_weights(&self) -> &GroupWeights {
        &self.relight.weights
    }

    /// The chunk of `kind` (radiance, lighting, non-diffuse or volume block) at the current
    /// weights, blended on first use and kept until the weights change.
    pub(crate) fn relit(&self, kind: ChunkKind, view: u32, key: u32) -> Cached {
        let id = (kind, view, key);
        if let Some(c) = self
            .relit
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .map
            .get(&id)
        {
            return c.clone();
        }
        if kind == ChunkKind::RadianceCube {
            let value = self.relit_radiance_cube(view, key);
            return self.remember(id, value);
        }
        let blend = &self.relight.blend;
        let layer = |g: u32| self.cached_stored(layer_kind(kind, g), view, key);
        let failed = |what: &str| {
            Cached::Failed(format!(
                "light group layers of {kind:?} (base view {view}, key {key}) {what}"
            ))
        };
        let value = match self.cached_stored(kind, view, key) {
            Cached::Radiance(total) => {
                let layers = match stored_layers(blend, layer, |c| match c {
                    Cached::Radiance(c) => Some(c),
                    _ => None,
                }) {
                    Ok(layers) => layers,
                    Err(e) => return e.unwrap_or_else(|| failed("are missing")),
                };
                blend_cube(blend, &total, &layers).map_or_else(
                    || failed("differ in size"),
                    |c| Cached::Radiance(Arc::new(c)),
                )
            }
            Cached::Volume(block) => {
                let layers = match stored_layers(blend, layer, |c| match c {
                    Cached::GroupVolume(v) => Some(v),
                    _ => None,
                }) {
                    Ok(layers) => layers,
                    Err(e) => return e.unwrap_or_else(|| failed("are missing")),
                };
                blend_block(&self.relight, &block, &layers).map_or_else(
                    || failed("differ in length"),
                    |b| Cached::Volume(Arc::new(b)),
                )
            }
            other => return other,
        };
        self.remember(id, value)
    }

    /// Keeps a blended chunk until the weights change (all are dropped when they exceed the
    /// cache budget); returns it.
    fn remember(&self, id: (ChunkKind, u32, u32), value: Cached) -> Cached {
        let mut memo = self.relit.lock().unwrap_or_else(|e| e.into_inner());
        memo.bytes += value.bytes();
        if memo.bytes > self.settings.cache_bytes {
            *memo = Memo::default();
            memo.bytes = value.bytes();
        }
        memo.map.insert(id, value.clone());
        value
    }

    /// The radiance cube of (view, key) relit ([`relit_radiance`], the module doc): its
    /// stored lighting and non-diffuse cubes against their blends, the sky's weight where the
    /// texel sees no object. The stored radiance where either light cube is missing.
    fn relit_radiance_cube(&self, view: u32, key: u32) -> Cached {
        let stored = self.cached_stored(ChunkKind::RadianceCube, view, key);
        let Cached::Radiance(radiance) = &stored else {
            return stored;
        };
        let cube = |c: Cached| match c {
            Cached::Radiance(c) if c.face_size == radiance.face_size => Some(c),
            _ => None,
        };
        let light = (
            cube(self.cached_stored(ChunkKind::LightingCube, view, key)),
            cube(self.cached_stored(ChunkKind::NonDiffuseCube, view, key)),
            cube(self.relit(ChunkKind::LightingCube, view, key)),
            cube(self.relit(ChunkKind::NonDiffuseCube, view, key)),
        );
        let (Some(l), Some(nd), Some(lw), Some(ndw)) = light else {
            return stored;
        };
        let ids = match self.cached_stored(ChunkKind::ObjectIdCube, view, key) {
            Cached::Ids(ids) if ids.face_size == radiance.face_size => Some(ids),
            _ => None,
        };
        let texels = self.relight.relit_texels(
            &radiance.texels,
            [&l.texels, &nd.texels],
            [&lw.texels, &ndw.texels],
            |i| ids.as_ref().is_some_and(|ids| ids.texels[i] == 0),
        );
        Cached::Radiance(Arc::new(CubeImage {
            face_size: radiance.face_size,
            texels,
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cube_blends_its_total_with_the_layers_that_changed() {
        let blend = LayerBlend {
            base: Vec3::ONE,
            layers: vec![(0, Vec3::splat(-1.0))],
        };
        let total = CubeImage::filled(1, Vec3::splat(3.0));
        let lamp = Arc::new(CubeImage::filled(1, Vec3::splat(1.0)));
        let relit = blend_cube(&blend, &total, &[lamp]).unwrap();
        assert!(relit.texels.iter().all(|&t| t == Vec3::splat(2.0)));
        let other = Arc::new(CubeImage::filled(2, Vec3::ONE));
        assert!(blend_cube(&blend, &total, &[other]).is_none());
    }
}
