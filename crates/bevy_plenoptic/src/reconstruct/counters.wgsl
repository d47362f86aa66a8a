// Cost counters of the geometry-assisted reconstruction (docs/architecture.md, "Cost
// counters"): with PLENOPTIC_COUNTERS each fragment counts its lookups, its texel and buffer
// loads by width, its filtered samples and gathers, its march and ray steps and its entries
// into each fallback, and adds them to its 8 × 4-pixel tile (a 32-lane group) in the
// camera's counter buffer: per tile the sums, the fragment count and the largest fragment's
// loads and work, and apart the pixels that marched nothing ("diffuse"). Without the shader
// def every tally() is empty and the buffer is not declared. counters.rs reads the
// buffer back and reduces it.
#define_import_path plenoptic::counters

// Direct lookups (view × key) tried.
const C_LOOKUPS: u32 = 0u;
// 16-byte loads: key texels (Rgba32Uint), temporal-volume samples, environment texels.
const C_LOADS_16: u32 = 1u;
// 8-byte loads: shading texels (Rg32Uint: lighting, non-diffuse).
const C_LOADS_8: u32 = 2u;
// 4-byte loads: prepass depth, volume bin offsets.
const C_LOADS_4: u32 = 3u;
// Filtered texture samples (material textures, the sun's shadow map).
const C_SAMPLES: u32 = 4u;
// Texture gathers: one fetch of one channel of a 2 × 2 footprint (four 4-byte texels).
const C_GATHERS: u32 = 5u;
// March steps through the distance cubes and node or triangle visits of the ray cast.
const C_STEPS: u32 = 6u;
// Entries into the temporal-volume fallback.
const C_VOLUME: u32 = 7u;
// Entries into the hole fill.
const C_FILL: u32 = 8u;
// Neighbour points the hole fill reconstructs again (a neighbour's lookups recomputed).
const C_FILL_LOOKUPS: u32 = 9u;
// Entries into the neighbour-texel fallback.
const C_NEIGHBOUR: u32 = 10u;
// Fetches of the screen-space fill kernel (screen_fill.wgsl) for the tile's holes.
const C_KERNEL_LOADS: u32 = 11u;
const COUNTERS: u32 = 12u;
// Words per tile: the COUNTERS sums, then the fragment count, the largest loads and work,
// the diffuse fragments and their loads.
const TILE_WORDS: u32 = 17u;
// Words before the first tile: tiles across, tiles down (written on the CPU).
const HEADER_WORDS: u32 = 4u;

var<private> cost: array<u32, 12>;

#ifdef PLENOPTIC_COUNTERS
#ifdef PLENOPTIC_STANDARD
@group(#{MATERIAL_BIND_GROUP}) @binding(114) var<storage, read_write> counters: array<atomic<u32>>;
#else
@group(#{MATERIAL_BIND_GROUP}) @binding(18) var<storage, read_write> counters: array<atomic<u32>>;
#endif
#endif

// Adds `n` to this fragment's counter `i`.
fn tally(i: u32, n: u32) {
#ifdef PLENOPTIC_COUNTERS
    cost[i] += n;
#endif
}

// Adds this fragment's counts to its tile (`frag`: its framebuffer position).
fn flush_counters(frag: vec2<f32>) {
#ifdef PLENOPTIC_COUNTERS
    let base = add_sums(frag);
    if base == 0u {
        return;
    }
    // Fetches: loads of every width and gathers.
    let loads = cost[C_LOADS_16] + cost[C_LOADS_8] + cost[C_LOADS_4] + cost[C_GATHERS];
    let work = loads + cost[C_SAMPLES] + cost[C_STEPS];
    atomicAdd(&counters[base + COUNTERS], 1u);
    atomicMax(&counters[base + COUNTERS + 1u], loads);
    atomicMax(&counters[base + COUNTERS + 2u], work);
    if cost[C_STEPS] == 0u {
        atomicAdd(&counters[base + COUNTERS + 3u], 1u);
        atomicAdd(&counters[base + COUNTERS + 4u], loads);
    }
#endif
}

// Adds the counts of a compute pass's work for pixel `frag` (framebuffer position), whose
// fragment counted itself (screen_fill.wgsl): its fetches as C_KERNEL_LOADS, its entries
// into fallbacks as they are.
fn flush_kernel_counters(frag: vec2<f32>) {
#ifdef PLENOPTIC_COUNTERS
    cost[C_KERNEL_LOADS] = cost[C_LOADS_16] + cost[C_LOADS_8] + cost[C_LOADS_4] + cost[C_GATHERS];
    cost[C_LOADS_16] = 0u;
    cost[C_LOADS_8] = 0u;
    cost[C_LOADS_4] = 0u;
    cost[C_GATHERS] = 0u;
    add_sums(frag);
#endif
}

// Adds this invocation's counts to the sums of the tile of `frag` (framebuffer position) and
// returns the tile's first word, 0 outside the buffer's tiles.
fn add_sums(frag: vec2<f32>) -> u32 {
#ifdef PLENOPTIC_COUNTERS
    let tiles_x = atomicLoad(&counters[0]);
    let tiles_y = atomicLoad(&counters[1]);
    let tile = vec2<u32>(frag) / vec2<u32>(8u, 4u);
    if tile.x >= tiles_x || tile.y >= tiles_y {
        return 0u;
    }
    let base = HEADER_WORDS + (tile.y * tiles_x + tile.x) * TILE_WORDS;
    for (var i = 0u; i < COUNTERS; i++) {
        if cost[i] != 0u {
            atomicAdd(&counters[base + i], cost[i]);
        }
    }
    return base;
#else
    return 0u;
#endif
}
