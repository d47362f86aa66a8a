//! The temporal-volume fallback of the GPU reconstruction (`plenoptic_recon`'s
//! `VolumeIndex`): where no time key has an accepted lookup, the fragment blends the volume
//! samples of its object whose cone contains its direction from a base view, whose distance
//! agrees (3× the depth tolerance), whose time is within `t ± tε` (tent filter) and whose
//! normal is within 60° of the point's surface normal in the world (the lookups' face test).
//!
//! Every resident volume block of a pack ([`crate::streaming::BinnedVolume`]: samples sorted
//! by direction bin, and the bins' offsets) is packed into two storage buffers per pack,
//! rebuilt when the set of resident blocks changes; each block's place in them is passed
//! per frame in the camera's view buffer ([`ViewParams::volumes`]).

use std::collections::HashMap;

use bevy::asset::RenderAssetUsages;
use bevy::prelude::*;
use bevy::render::storage::ShaderBuffer;

use super::view::{ViewParams, VolumeParams};
use crate::asset::RadiancePack;
use crate::camera::PlenopticCamera;
use crate::streaming::schedule::BlockRef;
use crate::streaming::{StreamCache, VOLUME_BIN_OFFSETS, VOLUME_SAMPLE_WORDS};

/// Most (base view, bucket) volume blocks a fragment searches.
pub const MAX_VOLUMES: usize = 8;

/// The volume storage buffers of each pack.
#[derive(Resource, Debug, Default)]
pub struct VolumeBuffers(pub HashMap<AssetId<RadiancePack>, PackVolumes>);

/// One pack's volume buffers.
#[derive(Debug, Clone)]
pub struct PackVolumes {
    /// Sample words of every resident block, block after block (`array<vec4<u32>>`, three
    /// per sample).
    pub samples: Handle<ShaderBuffer>,
    /// Bin offsets of every resident block ([`VOLUME_BIN_OFFSETS`] per block).
    pub bins: Handle<ShaderBuffer>,
    /// Per block in the buffers: (first sample, first bin offset).
    pub layout: HashMap<BlockRef, (u32, u32)>,
    /// Counts the repacks: the buffers are new ones after each, which the materials must
    /// bind again ([`super::view::ViewBuffer::bindings`]).
    pub generation: u64,
    /// The first `vec4` of the samples' light-group words in `samples`, after every
    /// block's samples ([`crate::streaming::BinnedVolume::groups`], block after block).
    pub group_base: u32,
}

impl PackVolumes {
    fn new(buffers: &mut Assets<ShaderBuffer>) -> Self {
        // Bindings may not be empty: one zero sample and one zero bin block.
        PackVolumes {
            samples: buffers.add(storage(&[0; VOLUME_SAMPLE_WORDS])),
            bins: buffers.add(storage(&[0; VOLUME_BIN_OFFSETS])),
            layout: HashMap::new(),
            generation: 0,
            group_base: 0,
        }
    }
}

fn storage(words: &[u32]) -> ShaderBuffer {
    let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
    ShaderBuffer::new(&bytes, RenderAssetUsages::RENDER_WORLD)
}

/// Creates each shown pack's volume buffers and repacks them when its set of resident
/// volume blocks changes.
pub(crate) fn upload_volumes(
    mut volumes: ResMut<VolumeBuffers>,
    cache: Res<StreamCache>,
    cameras: Query<&PlenopticCamera>,
    mut buffers: ResMut<Assets<ShaderBuffer>>,
) {
    for cam in &cameras {
        let id = cam.pack.id();
        let pv = volumes
            .0
            .entry(id)
            .or_insert_with(|| PackVolumes::new(&mut buffers));
        let mut resident: Vec<_> = cache
            .volumes
            .iter()
            .filter(|(k, _)| k.0 == id)
            .map(|(k, r)| ((k.1, k.2), r))
            .collect();
        if resident.len() == pv.layout.len()
            && resident.iter().all(|(b, _)| pv.layout.contains_key(b))
        {
            continue;
        }
        resident.sort_by_key(|(b, _)| *b);
        let mut words = Vec::new();
        let mut bins = Vec::new();
        let mut groups = Vec::new();
        let mut layout = HashMap::new();
        for (b, r) in resident {
            layout.insert(
                b,
                (
                    (words.len() / VOLUME_SAMPLE_WORDS) as u32,
                    bins.len() as u32,
                ),
            );
            words.extend_from_slice(&r.data.words);
            bins.extend_from_slice(&r.data.bins);
            groups.extend_from_slice(&r.data.groups);
        }
        words.resize(words.len().max(VOLUME_SAMPLE_WORDS), 0);
        // The group words start at a whole vec4 (three per sample).
        pv.group_base = (words.len() / 4) as u32;
        words.extend_from_slice(&groups);
        words.resize(words.len().next_multiple_of(4), 0);
        bins.resize(bins.len().max(VOLUME_BIN_OFFSETS), 0);
        if let Some(mut s) = buffers.get_mut(&pv.samples) {
            *s = storage(&words);
        }
        if let Some(mut s) = buffers.get_mut(&pv.bins) {
            *s = storage(&bins);
        }
        pv.layout = layout;
        pv.generation += 1;
    }
}

/// Fills the volume entries of `params` for the views `views` (index, normalised weight)
/// at the buckets `buckets`, from the blocks uploaded in `pv`; `eps` is tε.
pub(super) fn fill_params(
    params: &mut ViewParams,
    pv: Option<&PackVolumes>,
    views: &[(usize, f32)],
    positions: &[Vec3],
    buckets: std::ops::RangeInclusive<u32>,
    t: f32,
    eps: f32,
) {
    let Some(pv) = pv else { return };
    let mut n = 0;
    for &(v, w) in views {
        for b in buckets.clone() {
            let Some(&(sample, bin)) = pv.layout.get(&(v as u32, b)) else {
                continue;
            };
            if n == MAX_VOLUMES {
                break;
            }
            params.volumes[n] = VolumeParams {
                base: positions[v],
                weight: w,
                first_sample: sample,
                first_bin: bin,
            };
            n += 1;
        }
    }
    params.volume_count = n as u32;
    params.volume_groups = pv.group_base;
    params.time = t;
    params.time_window = eps;
}
