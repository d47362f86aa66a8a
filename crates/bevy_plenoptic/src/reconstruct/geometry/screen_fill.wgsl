// The screen-space hole fill (thesis §8.2.3, plenoptic_recon's geometry::fill ring search),
// a compute pass per view between Bevy's opaque and transparent passes. Each hole pixel the
// proxies' fragments left in the entries (fill_entry.wgsl) takes the nearest ring of pixels
// (radius 1 to `radius`) holding answered pixels of its own object, averages their terms,
// shades them with its own albedo and non-diffuse weight, adds what its fragment added, and
// overwrites its pixel of the view's HDR target. Where no ring has one, the fragment's own
// fallback (the nearby texels, else the background) stays in the target. No pixel's lookups
// are computed again: a ring pixel costs one 16-byte load.
#import plenoptic::fill_entry::{HOLE, HOLE_NON_DIFFUSE, OBJECT_BITS, HALF_MAX, unpack_pair}

struct FillParams {
    // The entries' size (the view's viewport), its offset in the target, the ring radius.
    size: vec2<u32>,
    offset: vec2<u32>,
    radius: u32,
    // Tiles across of the counter buffer (0: not counting).
    tiles_x: u32,
}

@group(0) @binding(0) var<storage, read> entries: array<vec4<u32>>;
@group(0) @binding(1) var target_image: texture_storage_2d<rgba16float, write>;
@group(0) @binding(2) var<uniform> fill: FillParams;

#ifdef PLENOPTIC_COUNTERS
// The camera's counter buffer (counters.wgsl's layout): the kernel's loads are added to its
// pixel's tile, counted as the fragments' own.
@group(0) @binding(3) var<storage, read_write> counters: array<atomic<u32>>;
const C_LOADS_16: u32 = 1u;
const TILE_WORDS: u32 = 16u;
const HEADER_WORDS: u32 = 4u;
#endif

// Adds `n` loads to the tile of pixel `p` (viewport coordinates), as flush_counters does a
// fragment's.
fn count_loads(p: vec2<u32>, n: u32) {
#ifdef PLENOPTIC_COUNTERS
    let tile = (fill.offset + p) / vec2<u32>(8u, 4u);
    if tile.x >= fill.tiles_x || tile.y >= atomicLoad(&counters[1]) {
        return;
    }
    let base = HEADER_WORDS + (tile.y * fill.tiles_x + tile.x) * TILE_WORDS;
    atomicAdd(&counters[base + C_LOADS_16], n);
#endif
}

@compute @workgroup_size(8, 4, 1)
fn fill_holes(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = id.xy;
    if any(p >= fill.size) {
        return;
    }
    let w = fill.size.x;
    let e = entries[p.y * w + p.x];
    if (e.w & HOLE) == 0u {
        return;
    }
    let object = e.w & OBJECT_BITS;
    var loads = 1u;
    let r_max = i32(fill.radius);
    let c = vec2<i32>(p);
    let size = vec2<i32>(fill.size);
    for (var r = 1; r <= r_max; r++) {
        var sum = mat2x3<f32>();
        var n = 0.0;
        for (var dy = -r; dy <= r; dy++) {
            // Whole rows at the ring's top and bottom, the two ends elsewhere.
            let step = select(2 * r, 1, abs(dy) == r);
            for (var dx = -r; dx <= r; dx += step) {
                let q = c + vec2<i32>(dx, dy);
                if any(q < vec2<i32>(0)) || any(q >= size) {
                    continue;
                }
                loads += 1u;
                let o = entries[u32(q.y) * w + u32(q.x)];
                if o.w == object {
                    sum += unpack_pair(o.xyz);
                    n += 1.0;
                }
            }
        }
        if n > 0.0 {
            let mean = sum * (1.0 / n);
            // What the hole's fragment added (x) and the albedo it shades with (y).
            let own = unpack_pair(e.xyz);
            let nd = select(0.0, 1.0, (e.w & HOLE_NON_DIFFUSE) != 0u);
            let colour = own[1] * mean[0] + mean[1] * nd + own[0];
            textureStore(target_image, fill.offset + p, vec4<f32>(min(colour, vec3<f32>(HALF_MAX)), 1.0));
            count_loads(p, loads);
            return;
        }
    }
    count_loads(p, loads);
}
