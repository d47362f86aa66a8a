//! Cost counters of the GPU reconstruction (`docs/architecture.md`, "Cost counters"): what a
//! frame's shaders do per pixel, counted on the GPU itself, so that the work can be tracked
//! on any adapter, Mesa's software Vulkan driver included, without a GPU timer.
//!
//! With [`PlenopticSettings::cost_counters`] on, the geometry-assisted shaders are compiled
//! with the `PLENOPTIC_COUNTERS` shader def: each fragment counts its lookups, its loads by
//! width, its filtered samples and gathers, its march and ray steps and its entries into each
//! fallback (`counters.wgsl`), and adds them to its 8 × 4-pixel tile, 32 pixels as a GPU
//! runs them in one group, in the camera's [`CounterBuffer`]. The buffer is cleared every
//! frame, read back ([`Readback`]) and reduced into the camera's [`CostReport`]: means per
//! pixel, and the mean over tiles of the tile's largest pixel (what divergence costs: a group
//! runs as long as its slowest lane). Off, the shaders count nothing and the buffer is a
//! placeholder of one header.

use bevy::asset::RenderAssetUsages;
use bevy::prelude::*;
use bevy::render::gpu_readback::{Readback, ReadbackComplete};
use bevy::render::storage::ShaderBuffer;

use crate::camera::PlenopticCamera;
use crate::settings::PlenopticSettings;

/// The per-pixel counters, in the order `counters.wgsl` keeps them.
pub const COUNTER_NAMES: [&str; COUNTERS] = [
    "lookups",
    "loads_16",
    "loads_8",
    "loads_4",
    "samples",
    "gathers",
    "steps",
    "volume",
    "fill",
    "fill_lookups",
    "neighbour",
    "kernel_loads",
];
/// Counters per pixel (`counters.wgsl`'s `COUNTERS`).
pub const COUNTERS: usize = 12;
/// Words per tile (`TILE_WORDS`): the sums, the fragment count, the largest loads and work,
/// the diffuse fragments and their loads.
const TILE_WORDS: usize = 17;
/// Words before the first tile (`HEADER_WORDS`): tiles across and down.
const HEADER_WORDS: usize = 4;
/// Pixels a tile spans across and down.
pub const TILE: UVec2 = UVec2::new(8, 4);

/// A camera's counter buffer (every plenoptic camera has one; the materials bind it).
#[derive(Component, Debug, Clone)]
pub struct CounterBuffer {
    /// The storage buffer.
    pub buffer: Handle<ShaderBuffer>,
    /// Its tiles across and down (zero while counting is off).
    pub tiles: UVec2,
}

/// What a camera's shaders did in the last frame read back, per pixel (see the module doc).
#[derive(Component, Debug, Clone, Default, PartialEq)]
pub struct CostReport {
    /// Fragments shaded.
    pub fragments: u64,
    /// Mean of each counter per fragment ([`COUNTER_NAMES`]).
    pub mean: [f64; COUNTERS],
    /// Mean fetches per fragment: loads of all widths and gathers (each one fetch instruction).
    pub loads: f64,
    /// Mean fetches of the screen-space fill kernel per fragment (its holes' ring searches
    /// and fallbacks, run apart from the fragments).
    pub kernel_loads: f64,
    /// Mean work (fetches, samples and steps) per fragment.
    pub work: f64,
    /// Mean over tiles of the tile's largest fragment loads.
    pub group_max_loads: f64,
    /// Mean over tiles of the tile's largest fragment work.
    pub group_max_work: f64,
    /// Fragments that marched nothing (no reflection steps): the diffuse fragments.
    pub diffuse_fragments: u64,
    /// Mean fetches (loads and gathers) per diffuse fragment.
    pub diffuse_loads: f64,
}

impl CostReport {
    /// Reduces a counter buffer's words (the header, then `TILE_WORDS` per tile); `None`
    /// when the words are not a whole buffer.
    pub fn from_words(words: &[u32]) -> Option<Self> {
        let (header, tiles) = words.split_at_checked(HEADER_WORDS)?;
        let count = header[0] as usize * header[1] as usize;
        if tiles.len() < count * TILE_WORDS {
            return None;
        }
        let mut sums = [0u64; COUNTERS];
        let (mut fragments, mut diffuse, mut diffuse_loads) = (0u64, 0u64, 0u64);
        let (mut max_loads, mut max_work, mut groups) = (0u64, 0u64, 0u64);
        for tile in tiles.chunks_exact(TILE_WORDS).take(count) {
            let n = u64::from(tile[COUNTERS]);
            if n == 0 {
                continue;
            }
            for (s, &v) in sums.iter_mut().zip(tile) {
                *s += u64::from(v);
            }
            fragments += n;
            groups += 1;
            max_loads += u64::from(tile[COUNTERS + 1]);
            max_work += u64::from(tile[COUNTERS + 2]);
            diffuse += u64::from(tile[COUNTERS + 3]);
            diffuse_loads += u64::from(tile[COUNTERS + 4]);
        }
        let per = |v: u64, n: u64| if n == 0 { 0.0 } else { v as f64 / n as f64 };
        let mean = sums.map(|s| per(s, fragments));
        let loads = mean[1] + mean[2] + mean[3] + mean[5];
        Some(Self {
            fragments,
            mean,
            loads,
            kernel_loads: mean[11],
            work: loads + mean[4] + mean[6],
            group_max_loads: per(max_loads, groups),
            group_max_work: per(max_work, groups),
            diffuse_fragments: diffuse,
            diffuse_loads: per(diffuse_loads, diffuse),
        })
    }

    /// The mean of counter `name` ([`COUNTER_NAMES`]) per fragment.
    pub fn mean_of(&self, name: &str) -> Option<f64> {
        COUNTER_NAMES
            .iter()
            .position(|n| *n == name)
            .map(|i| self.mean[i])
    }
}

/// The child entity that reads a camera's counter buffer back.
#[derive(Component, Debug, Clone, Copy)]
struct CountersOf(Entity);

/// Adds the counter buffers, their clearing each frame and their read-back.
pub(crate) fn build(app: &mut App) {
    app.add_systems(
        Update,
        prepare_counter_buffers.in_set(super::ReconstructSystems::Resources),
    )
    .add_observer(read_report);
}

/// A cleared buffer for `tiles` (the header set).
fn cleared(tiles: UVec2) -> ShaderBuffer {
    let mut words = vec![0u32; HEADER_WORDS + (tiles.x * tiles.y) as usize * TILE_WORDS];
    words[0] = tiles.x;
    words[1] = tiles.y;
    let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
    ShaderBuffer::new(&bytes, RenderAssetUsages::RENDER_WORLD)
}

/// Gives every plenoptic camera its counter buffer, sized to its viewport and cleared each
/// frame while counting is on, and the child that reads it back.
fn prepare_counter_buffers(
    mut commands: Commands,
    settings: Res<PlenopticSettings>,
    mut cameras: Query<(Entity, &Camera, Option<&mut CounterBuffer>), With<PlenopticCamera>>,
    mut buffers: ResMut<Assets<ShaderBuffer>>,
) {
    for (entity, camera, counters) in &mut cameras {
        let tiles = match (settings.cost_counters, camera.physical_viewport_size()) {
            (true, Some(size)) => UVec2::new(size.x.div_ceil(TILE.x), size.y.div_ceil(TILE.y)),
            _ => UVec2::ZERO,
        };
        match counters {
            None => {
                let buffer = buffers.add(cleared(tiles));
                commands.entity(entity).insert(CounterBuffer {
                    buffer: buffer.clone(),
                    tiles,
                });
                if settings.cost_counters {
                    commands.spawn((
                        Readback::buffer(buffer),
                        CountersOf(entity),
                        ChildOf(entity),
                    ));
                }
            }
            Some(mut c) if c.tiles != tiles => {
                // Another size: a new buffer (the materials bind it again, as they do a new
                // view buffer) and a read-back of it.
                c.buffer = buffers.add(cleared(tiles));
                c.tiles = tiles;
                commands.spawn((
                    Readback::buffer(c.buffer.clone()),
                    CountersOf(entity),
                    ChildOf(entity),
                ));
            }
            Some(c) if settings.cost_counters => {
                // Same size: rewritten in place (Bevy reuses a storage buffer of the same size).
                if let Some(mut b) = buffers.get_mut(&c.buffer) {
                    *b = cleared(c.tiles);
                }
            }
            Some(_) => {}
        }
    }
}

/// Reduces a read-back counter buffer into its camera's [`CostReport`]; a read-back of a
/// buffer the camera no longer binds is dropped with its entity.
fn read_report(
    event: On<ReadbackComplete>,
    mut commands: Commands,
    readers: Query<(&CountersOf, &Readback)>,
    cameras: Query<&CounterBuffer>,
) {
    let Ok((of, readback)) = readers.get(event.entity) else {
        return;
    };
    let current = matches!(readback, Readback::Buffer { buffer, .. }
        if cameras.get(of.0).is_ok_and(|c| c.buffer == *buffer));
    if !current {
        commands.entity(event.entity).despawn();
        return;
    }
    let words: Vec<u32> = event
        .data
        .chunks_exact(4)
        .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    if let Some(report) = CostReport::from_words(&words) {
        commands.entity(of.0).try_insert(report);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two tiles across, one down: the first with three fragments, the second empty.
    fn buffer() -> Vec<u32> {
        let mut w = vec![0u32; HEADER_WORDS + 2 * TILE_WORDS];
        w[0] = 2;
        w[1] = 1;
        let t = &mut w[HEADER_WORDS..HEADER_WORDS + TILE_WORDS];
        t[0] = 12; // lookups
        t[1] = 30; // loads_16
        t[2] = 6; // loads_8
        t[5] = 3; // gathers, fetches as loads are
        t[6] = 9; // steps
        t[COUNTERS] = 3; // fragments
        t[COUNTERS + 1] = 20; // largest loads
        t[COUNTERS + 2] = 29; // largest work
        t[COUNTERS + 3] = 2; // diffuse fragments
        t[COUNTERS + 4] = 16; // their loads
        w
    }

    #[test]
    fn means_per_fragment_and_per_group() {
        let r = CostReport::from_words(&buffer()).unwrap();
        assert_eq!(r.fragments, 3);
        assert!((r.mean_of("lookups").unwrap() - 4.0).abs() < 1e-12);
        assert!((r.loads - 13.0).abs() < 1e-12);
        assert!((r.work - 16.0).abs() < 1e-12);
        // The empty tile is no group.
        assert!((r.group_max_loads - 20.0).abs() < 1e-12);
        assert!((r.group_max_work - 29.0).abs() < 1e-12);
        assert_eq!(r.diffuse_fragments, 2);
        assert!((r.diffuse_loads - 8.0).abs() < 1e-12);
    }

    #[test]
    fn a_short_buffer_is_refused() {
        let mut w = buffer();
        w.pop();
        assert_eq!(CostReport::from_words(&w), None);
        assert_eq!(CostReport::from_words(&[1, 1]), None);
    }

    #[test]
    fn the_names_match_the_counters() {
        assert_eq!(COUNTER_NAMES.len(), COUNTERS);
        let wgsl = include_str!("counters.wgsl");
        for (i, name) in COUNTER_NAMES.iter().enumerate() {
            let line = format!("const C_{}: u32 = {i}u;", name.to_uppercase());
            assert!(wgsl.contains(&line), "counters.wgsl lacks `{line}`");
        }
        assert!(wgsl.contains(&format!("const COUNTERS: u32 = {COUNTERS}u;")));
        assert!(wgsl.contains(&format!("const TILE_WORDS: u32 = {TILE_WORDS}u;")));
        assert!(wgsl.contains(&format!("const HEADER_WORDS: u32 = {HEADER_WORDS}u;")));
    }
}
