//! Light groups in a pack (format 4.2; docs/pack-format.md, "Light groups"): the light of
//! each declared group stored apart from the total, and the weights with which a reader
//! relights the baked animation.
//!
//! A pack with `D` declared groups keeps its lighting and non-diffuse cubes (kinds 12, 13) and
//! its volume samples' values as the **total**: every emitter at its own intensity, the sum
//! of all groups. Group `g` adds, per range image, a lighting and a non-diffuse cube of its
//! own ([`ChunkKind::GroupLighting`], [`ChunkKind::GroupNonDiffuse`]) and, per volume block,
//! the lighting and non-diffuse values of the block's samples with only `g` on
//! ([`ChunkKind::GroupVolume`]). The default group (emitters no group names) is the total
//! less the declared groups. Light transport is linear in the emitters, so with weight `w_g`
//! per group and `w_0` for the default group
//!
//! ```text
//! L(w) = Σ_g w_g · L_g = w_0 · T + Σ_{g ≥ 1} (w_g − w_0) · L_g
//! ```
//!
//! (`T` the total). When the default group has no emitter, `T` is the sum of the declared
//! groups, so the last declared group's layers are not stored: it takes the default group's
//! place (`L_last = T − Σ_{g < last} L_g`, and `w_0` is its weight). So a pack stores one layer
//! less than it has groups ([`LightGroupsEntry::stored`]), and a reader reads only the layers
//! whose weight differs from the derived group's: at equal weights none, a lamp switched off
//! one. A reader that knows nothing of groups reads the total (the kinds are skipped by a
//! 4.1 reader), which is the pack at every group's own intensity.

use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::bytes::{ByteReader, PutLe, zstd_compress, zstd_decompress_exact};
use crate::cube::{rgb9e5_pack, rgb9e5_unpack};
use crate::error::{PackError, Result};
use crate::range_image::RadianceCube;
use crate::reader::{Chunk, PackReader};
use crate::volume::MAX_BLOCK_SAMPLES;
use crate::{ChunkEntry, ChunkKind};
use std::collections::HashMap;

/// The name that sets the default group's weight (emitters no group names).
pub const DEFAULT_GROUP: &str = "default";

/// Parses a group setting `NAME=I` (an intensity) or `NAME=R,G,B` (a colour × intensity),
/// as `plenoptic render --light` and the tour take it. Values must be finite and
/// non-negative.
pub fn parse_setting(text: &str) -> std::result::Result<(String, Vec3), String> {
    let bad = || {
        format!(
            "light group setting '{text}': expected NAME=I or NAME=R,G,B with finite, non-negative values"
        )
    };
    let (name, value) = text.split_once('=').ok_or_else(bad)?;
    let parts: Vec<f32> = value
        .split(',')
        .map(|p| p.trim().parse::<f32>())
        .collect::<std::result::Result<_, _>>()
        .map_err(|_| bad())?;
    let w = match parts[..] {
        [i] => Vec3::splat(i),
        [r, g, b] => Vec3::new(r, g, b),
        _ => return Err(bad()),
    };
    if name.trim().is_empty() || !w.is_finite() || w.min_element() < 0.0 {
        return Err(bad());
    }
    Ok((name.trim().to_owned(), w))
}

/// Most light groups a pack may declare (directory kind codes leave room for 256).
pub const MAX_LIGHT_GROUPS: usize = 16;

/// The manifest's `light_groups` (4.2): the declared groups and each emitter's group.
/// Indices are into `names`; `None` is the default group.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct LightGroupsEntry {
    /// The declared groups' names; group `g` is stored in the chunks of kind code
    /// `0x100 + g`, `0x200 + g` and `0x300 + g`.
    pub names: Vec<String>,
    /// Per manifest light (same order as `lights`): its group.
    pub lights: Vec<Option<u32>>,
    /// Per manifest object (same order as `objects`): the group of its emission.
    pub objects: Vec<Option<u32>>,
    /// The sun's group (the environment's `direct_sun`).
    pub sun: Option<u32>,
    /// The environment's group (the sky, its ground, an image or a uniform colour).
    pub sky: Option<u32>,
    /// Whether the default group holds any emitter (else its weight does not matter).
    pub default_has_emitters: bool,
}

impl LightGroupsEntry {
    /// The groups whose layers the pack stores: every declared group when the default group
    /// has emitters, else all but the last (whose light is the total less the others').
    pub fn stored(&self) -> std::ops::Range<u32> {
        let n = self.names.len() as u32;
        if self.default_has_emitters {
            0..n
        } else {
            0..n.saturating_sub(1)
        }
    }

    /// Checks the entry against the manifest's light and object counts: names unique, not
    /// empty, at most [`MAX_LIGHT_GROUPS`], every index inside.
    pub fn validate(&self, lights: usize, objects: usize) -> std::result::Result<(), String> {
        let n = self.names.len();
        if n == 0 || n > MAX_LIGHT_GROUPS {
            return Err(format!(
                "light_groups declares {n} groups, expected 1 to {MAX_LIGHT_GROUPS}"
            ));
        }
        for (i, name) in self.names.iter().enumerate() {
            if name.is_empty() || self.names[..i].contains(name) {
                return Err(format!(
                    "light group {i} name {name:?} is empty or repeated"
                ));
            }
        }
        if self.lights.len() != lights || self.objects.len() != objects {
            return Err(format!(
                "light_groups lists {} lights and {} objects, the manifest has {lights} and {objects}",
                self.lights.len(),
                self.objects.len()
            ));
        }
        let all = self
            .lights
            .iter()
            .chain(&self.objects)
            .chain([&self.sun, &self.sky]);
        if let Some(g) = all.flatten().find(|&&g| g as usize >= n) {
            return Err(format!("light group index {g} is not below the {n} groups"));
        }
        Ok(())
    }
}

/// A colour × intensity per light group, which a reader may change every frame.
#[derive(Debug, Clone, PartialEq)]
pub struct GroupWeights {
    /// The default group's weight.
    pub default: Vec3,
    /// The declared groups' weights, in the manifest's order (missing entries are 1).
    pub groups: Vec<Vec3>,
}

impl Default for GroupWeights {
    fn default() -> Self {
        Self {
            default: Vec3::ONE,
            groups: Vec::new(),
        }
    }
}

/// How a reader combines a pack's stored layers at some weights: `base · T + Σ c · L_g`.
#[derive(Debug, Clone, PartialEq)]
pub struct LayerBlend {
    /// The weight of the total.
    pub base: Vec3,
    /// `(group, coefficient)` of every layer to add; groups whose coefficient is zero are
    /// left out (they cost no reads).
    pub layers: Vec<(u32, Vec3)>,
}

impl LayerBlend {
    /// Whether the blend is the total as stored.
    pub fn is_identity(&self) -> bool {
        self.base == Vec3::ONE && self.layers.is_empty()
    }

    /// The blended value of one texel or sample: `base · total + Σ_k c_k · layer(k)`, where
    /// `layer(k)` is the value of the `k`-th entry of [`LayerBlend::layers`]; clamped at zero
    /// (quantised layers may overshoot the total by their rounding).
    pub fn apply(&self, total: Vec3, layer: impl Fn(usize) -> Vec3) -> Vec3 {
        let mut v = self.base * total;
        for (k, &(_, c)) in self.layers.iter().enumerate() {
            v += c * layer(k);
        }
        v.max(Vec3::ZERO)
    }
}

impl GroupWeights {
    /// Every group at its own intensity.
    pub fn identity() -> Self {
        Self::default()
    }

    /// The weight of `group` (`None`: the default group).
    pub fn weight(&self, group: Option<u32>) -> Vec3 {
        match group {
            None => self.default,
            Some(g) => self.groups.get(g as usize).copied().unwrap_or(Vec3::ONE),
        }
    }

    /// Weights from `settings` (`(group name, colour × intensity)`; `default` names the
    /// default group) over the groups `names`; groups not set are 1. An unknown name is an
    /// error that lists the groups.
    pub fn from_names(
        names: &[String],
        settings: &[(String, Vec3)],
    ) -> std::result::Result<Self, String> {
        let mut out = Self {
            default: Vec3::ONE,
            groups: vec![Vec3::ONE; names.len()],
        };
        for (name, w) in settings {
            if name == DEFAULT_GROUP {
                out.default = *w;
            } else if let Some(g) = names.iter().position(|n| n == name) {
                out.groups[g] = *w;
            } else {
                return Err(format!(
                    "no light group '{name}': the pack's groups are {}{DEFAULT_GROUP}",
                    names.iter().map(|n| format!("{n}, ")).collect::<String>()
                ));
            }
        }
        Ok(out)
    }

    /// How to combine the layers of a pack with `entry`'s groups at these weights (the
    /// module doc's formula). A pack without groups, or weights all 1, gives the total alone.
    pub fn blend(&self, entry: Option<&LightGroupsEntry>) -> LayerBlend {
        let Some(entry) = entry else {
            return LayerBlend {
                base: self.default,
                layers: Vec::new(),
            };
        };
        let stored = entry.stored();
        // The group whose light is the total less the stored layers.
        let base = if entry.default_has_emitters {
            self.default
        } else {
            self.weight(Some(stored.end))
        };
        let layers = stored
            .map(|g| (g, self.weight(Some(g)) - base))
            .filter(|(_, c)| *c != Vec3::ZERO)
            .collect();
        LayerBlend { base, layers }
    }
}

const GROUP_VOLUME_MAGIC: [u8; 4] = *b"PLGV";
/// Bytes of one sample's values: lighting and non-diffuse radiance, RGB9E5 each.
const GROUP_SAMPLE_BYTES: u64 = 8;

/// Encodes one group's values of a volume block's samples (`values[i]` = (lighting,
/// non-diffuse) of input sample `i`) in the block's stored order (`order`, from
/// [`crate::EncodedVolumeBlock::order`]). Returns the chunk bytes and the uncompressed length.
pub fn encode_group_volume(values: &[[Vec3; 2]], order: &[u32]) -> Result<(Vec<u8>, u64)> {
    if values.len() != order.len() || values.len() > MAX_BLOCK_SAMPLES as usize {
        return Err(PackError::input(format!(
            "{} group values for a block of {} samples",
            values.len(),
            order.len()
        )));
    }
    let mut raw = Vec::with_capacity(values.len() * GROUP_SAMPLE_BYTES as usize);
    for &i in order {
        let [l, nd] = values
            .get(i as usize)
            .ok_or_else(|| PackError::input(format!("order names sample {i}")))?;
        raw.put_u32(rgb9e5_pack(*l));
        raw.put_u32(rgb9e5_pack(*nd));
    }
    let mut out = Vec::with_capacity(16 + raw.len() / 4);
    out.extend_from_slice(&GROUP_VOLUME_MAGIC);
    out.put_u32(values.len() as u32);
    out.extend_from_slice(&zstd_compress(&raw)?);
    Ok((out, raw.len() as u64))
}

/// Checks a group-volume header: (sample count, uncompressed length).
pub(crate) fn group_volume_header(bytes: &[u8]) -> Result<(u32, u64)> {
    let mut r = ByteReader::payload(bytes);
    if r.array::<4>()? != GROUP_VOLUME_MAGIC {
        return Err(r.fail("not a light group's volume values (bad magic)"));
    }
    let n = r.u32()?;
    if n > MAX_BLOCK_SAMPLES {
        return Err(PackError::CountTooLarge {
            what: "light group volume samples",
            count: u64::from(n),
            max: u64::from(MAX_BLOCK_SAMPLES),
        });
    }
    Ok((n, u64::from(n) * GROUP_SAMPLE_BYTES))
}

/// Decodes one group's volume values, in the block's stored order.
pub fn decode_group_volume(bytes: &[u8]) -> Result<Vec<[Vec3; 2]>> {
    let (n, len) = group_volume_header(bytes)?;
    let raw = zstd_decompress_exact(&bytes[8..], len as usize, PackError::payload)?;
    let mut r = ByteReader::payload(&raw);
    (0..n)
        .map(|_| Ok([rgb9e5_unpack(r.u32()?), rgb9e5_unpack(r.u32()?)]))
        .collect()
}

/// Checks the light-group chunks against the manifest's groups: every group chunk names a
/// declared group, and every lighting cube and volume block has each declared group's layers.
pub(crate) fn validate_chunks(
    entries: &[ChunkEntry],
    index: &HashMap<(ChunkKind, u32, u32), usize>,
    groups: Option<&crate::LightGroupsEntry>,
) -> Result<()> {
    let declared = groups.map_or(0, |g| g.names.len() as u32);
    let stored = groups.map_or(0..0, |g| g.stored());
    for (i, e) in entries.iter().enumerate() {
        let mismatch = |problem: String| PackError::LightGroupMismatch {
            chunk: e.chunk_ref(i),
            problem,
        };
        if let Some(g) = e.kind.light_group()
            && !stored.contains(&g)
        {
            return Err(mismatch(format!(
                "light group {g}, but the manifest declares {declared} groups of which {} are stored",
                stored.len()
            )));
        }
        let needs: &[fn(u32) -> ChunkKind] = match e.kind {
            ChunkKind::LightingCube => &[ChunkKind::GroupLighting, ChunkKind::GroupNonDiffuse],
            ChunkKind::VolumeBlock => &[ChunkKind::GroupVolume],
            _ => &[],
        };
        for kind in needs {
            if let Some(g) =
                (stored.clone()).find(|&g| !index.contains_key(&(kind(g), e.base_view, e.key)))
            {
                return Err(mismatch(format!(
                    "no {:?} chunk for light group {g} of the {declared} the manifest declares",
                    kind(g)
                )));
            }
        }
    }
    Ok(())
}

impl PackReader {
    /// Light group `group`'s diffuse-lighting cube of `base_view` at time key `key`.
    pub fn group_lighting(&self, base_view: u32, key: u32, group: u32) -> Result<RadianceCube> {
        match self.get(ChunkKind::GroupLighting(group), base_view, key)? {
            Chunk::GroupLighting(c) => Ok(c),
            _ => unreachable!("decoded by kind"),
        }
    }

    /// Light group `group`'s non-diffuse radiance cube of `base_view` at time key `key`.
    pub fn group_non_diffuse(&self, base_view: u32, key: u32, group: u32) -> Result<RadianceCube> {
        match self.get(ChunkKind::GroupNonDiffuse(group), base_view, key)? {
            Chunk::GroupNonDiffuse(c) => Ok(c),
            _ => unreachable!("decoded by kind"),
        }
    }

    /// Light group `group`'s values of the volume block of `base_view` in `bucket`, in the
    /// block's stored order.
    pub fn group_volume(
        &self,
        base_view: u32,
        bucket: u32,
        group: u32,
    ) -> Result<Vec<[glam::Vec3; 2]>> {
        match self.get(ChunkKind::GroupVolume(group), base_view, bucket)? {
            Chunk::GroupVolume(v) => Ok(v),
            _ => unreachable!("decoded by kind"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn entry(default_has_emitters: bool) -> LightGroupsEntry {
        LightGroupsEntry {
            names: vec!["lamp".into(), "sun".into(), "sky".into()],
            lights: vec![Some(0)],
            objects: vec![],
            sun: Some(1),
            sky: Some(2),
            default_has_emitters,
        }
    }

    #[test]
    fn equal_weights_read_no_layer_and_a_lamp_off_reads_one() {
        let e = entry(false);
        assert_eq!(
            e.stored(),
            0..2,
            "the sky's light is the total less the others'"
        );
        let w = |g: [f32; 3]| GroupWeights {
            default: Vec3::ONE,
            groups: g.map(Vec3::splat).to_vec(),
        };
        assert!(w([1.0; 3]).blend(Some(&e)).is_identity());
        let half = w([0.5; 3]).blend(Some(&e));
        assert_eq!((half.base, half.layers.len()), (Vec3::splat(0.5), 0));
        let off = w([0.0, 1.0, 1.0]).blend(Some(&e));
        assert_eq!(off.base, Vec3::ONE);
        assert_eq!(off.layers, vec![(0, Vec3::splat(-1.0))]);
        // T = L0 + L1 + L2: the blend is Σ w_g L_g whatever it reads.
        let layers = [
            Vec3::new(1.0, 2.0, 3.0),
            Vec3::splat(4.0),
            Vec3::splat(0.25),
        ];
        let total = layers.iter().sum::<Vec3>();
        for g in [[0.0, 1.0, 1.0], [0.5, 2.0, 0.0], [3.0, 0.0, 0.0]] {
            let b = w(g).blend(Some(&e));
            assert!(
                b.layers.iter().all(|&(g, _)| g < 2),
                "only stored layers are read"
            );
            let expected: Vec3 = (0..3).map(|i| layers[i] * g[i]).sum();
            let got = b.apply(total, |k| layers[b.layers[k].0 as usize]);
            assert!(
                got.abs_diff_eq(expected, 1e-5),
                "{g:?}: {got} vs {expected}"
            );
        }
    }

    #[test]
    fn a_default_group_with_emitters_keeps_its_weight() {
        let e = entry(true);
        let w = GroupWeights {
            default: Vec3::splat(0.0),
            groups: vec![Vec3::ONE; 3],
        };
        let b = w.blend(Some(&e));
        assert_eq!(b.base, Vec3::ZERO);
        assert_eq!(b.layers.len(), 3);
    }

    #[test]
    fn group_volume_values_round_trip_in_stored_order() {
        let values = vec![
            [Vec3::ONE, Vec3::ZERO],
            [Vec3::splat(2.0), Vec3::splat(0.5)],
        ];
        let (bytes, len) = encode_group_volume(&values, &[1, 0]).unwrap();
        assert_eq!(group_volume_header(&bytes).unwrap(), (2, len));
        assert_eq!(
            decode_group_volume(&bytes).unwrap(),
            vec![values[1], values[0]]
        );
        assert!(decode_group_volume(&bytes[..bytes.len() - 1]).is_err());
        assert!(encode_group_volume(&values, &[0]).is_err());
    }

    #[test]
    fn settings_parse_and_name_their_groups() {
        assert_eq!(
            parse_setting("lamp=0.5"),
            Ok(("lamp".into(), Vec3::splat(0.5)))
        );
        assert_eq!(
            parse_setting("sky=1,0.5,0.25"),
            Ok(("sky".into(), Vec3::new(1.0, 0.5, 0.25)))
        );
        for bad in ["lamp", "lamp=-1", "lamp=1,2", "=1", "lamp=nan", "lamp=x"] {
            assert!(parse_setting(bad).is_err(), "{bad}");
        }
        let names = vec!["lamp".to_owned(), "sun".to_owned()];
        let w = GroupWeights::from_names(
            &names,
            &[
                ("sun".into(), Vec3::ZERO),
                ("default".into(), Vec3::splat(2.0)),
            ],
        )
        .unwrap();
        assert_eq!(w.groups, vec![Vec3::ONE, Vec3::ZERO]);
        assert_eq!(w.default, Vec3::splat(2.0));
        let e = GroupWeights::from_names(&names, &[("moon".into(), Vec3::ONE)]).unwrap_err();
        assert!(e.contains("lamp, sun, default"), "{e}");
    }

    #[test]
    fn entries_with_bad_indices_are_refused() {
        let mut e = entry(false);
        assert!(e.validate(1, 0).is_ok());
        assert!(e.validate(2, 0).is_err());
        e.sky = Some(3);
        assert!(e.validate(1, 0).unwrap_err().contains("index 3"));
    }
}
