// The lookups' last fallbacks (plenoptic_recon's neighbour module): a thin object's nearby
// texels in each lookup's key, and the heaviest key's texel in the point's direction. The
// fragment hole fill (fill.wgsl) and the screen-space fill kernel (screen_fill.wgsl) take
// them where neither the lookups nor the hole fill answered.
#define_import_path plenoptic::geometry::fallback

#import plenoptic::cube::cube_texel
#import plenoptic::counters::{tally, C_LOADS_16, C_NEIGHBOUR}
#import plenoptic::geometry::bindings::{MAX_LOOKUPS, cam, cubes, point_slot, point_material}
#import plenoptic::geometry::lookup::{Weighted, lookup_of, object_point, texel_terms}

// plenoptic_recon's NEIGHBOUR_TEXELS and NEIGHBOUR_TOLERANCE.
const NEIGHBOUR_TEXELS: i32 = 8;
const NEIGHBOUR_TOLERANCE: f32 = 0.25;
// Ranks another object's texel behind every texel of the object itself.
const OTHER_OBJECT: i32 = 2 * NEIGHBOUR_TEXELS * NEIGHBOUR_TEXELS + 1;
// Above every score.
const NO_TEXEL: i32 = 1073741824;

// The fallback after the hole fill (plenoptic_recon's neighbour_texel): in each lookup's key,
// the nearest texel at about the distance of `p` within NEIGHBOUR_TEXELS of the lookup's
// texel on its face, `object`'s own first, then any surface's (the first in row order on
// ties). Returns (Σ w·terms, Σ w).
fn neighbour_texels(p: vec3<f32>, object: u32) -> Weighted {
    return nearby_texels(object_point(p), object, f32(point_slot), point_material);
}

// `neighbour_texels` of the point whose `object_point` is `local`, of `object` with motion
// slot `slot`, shaded from its material or not (`material`): the screen-space fill kernel's
// entry, which has no material bound.
fn nearby_texels(local: vec4<f32>, object: u32, slot: f32, material: bool) -> Weighted {
    tally(C_NEIGHBOUR, 1u);
    var sum = mat2x3<f32>();
    var ws = 0.0;
    let count = cam.lookup_count;
    let n = cam.face;
    for (var k = 0u; k < min(count, MAX_LOOKUPS); k++) {
        let l = lookup_of(local, k, n, slot);
        if !l.ok {
            continue;
        }
        let dist = l.dist;
        let t = l.t;
        let layer0 = cam.lookups[k].first_layer;
        var best = NO_TEXEL;
        var best_c = t;
        for (var dj = -NEIGHBOUR_TEXELS; dj <= NEIGHBOUR_TEXELS; dj++) {
            for (var di = -NEIGHBOUR_TEXELS; di <= NEIGHBOUR_TEXELS; di++) {
                let x = i32(t.x) + di;
                let y = i32(t.y) + dj;
                if x < 0 || y < 0 || x >= i32(n) || y >= i32(n) {
                    continue;
                }
                let c = vec3<u32>(u32(x), u32(y), t.z);
                tally(C_LOADS_16, 1u);
                let texel = textureLoad(cubes, c.xy, layer0 + c.z, 0);
                // The object's own texels first, then any surface at the point's distance.
                let score = di * di + dj * dj + select(OTHER_OBJECT, 0, texel.z == object);
                if texel.z != 0u && abs(bitcast<f32>(texel.y) - dist) <= NEIGHBOUR_TOLERANCE * dist
                    && score < best {
                    best = score;
                    best_c = c;
                }
            }
        }
        if best < NO_TEXEL {
            tally(C_LOADS_16, 1u);
            let texel = textureLoad(cubes, best_c.xy, layer0 + best_c.z, 0);
            sum += texel_terms(best_c, layer0, texel, material) * cam.lookups[k].weight;
            ws += cam.lookups[k].weight;
        }
    }
    return Weighted(sum, ws);
}

// The last fallback: the heaviest key's texel in the direction of world point `p`
// ("background"), the terms of an object shaded from its material or not (`material`);
// w = 0 without lookups.
fn heaviest_texel(p: vec3<f32>, material: bool) -> Weighted {
    let h = cam.heaviest;
    if h >= min(cam.lookup_count, MAX_LOOKUPS) {
        return Weighted(mat2x3<f32>(), 0.0);
    }
    let t = cube_texel(p - cam.lookups[h].base, cam.face);
    let layer0 = cam.lookups[h].first_layer;
    tally(C_LOADS_16, 1u);
    let texel = textureLoad(cubes, t.xy, layer0 + t.z, 0);
    return Weighted(texel_terms(t, layer0, texel, material), 1.0);
}
