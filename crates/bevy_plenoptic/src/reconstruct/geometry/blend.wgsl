// A camera's key pairs blended once per frame (blend.rs; thesis §8.2.3's time blend): per
// texel of each pair's six faces, the first key's id, distance and normal, or PAIR_CHANGING
// where the two keys differ there, and the two keys' lighting and non-diffuse terms blended
// with their weights, as half floats. The keys and the camera's view buffer are bound as the
// materials bind them (group 1, MATERIAL_BIND_GROUP); the outputs in group 0.
#import plenoptic::cube::rgb9e5_decode
#import plenoptic::fill_entry::pack_pair
#import plenoptic::geometry::bindings::{cam, cubes, shading_cubes, MAX_PAIRS, PAIR_CHANGING}

@group(0) @binding(0) var geometry_out: texture_storage_2d_array<rgba32uint, write>;
@group(0) @binding(1) var terms_out: texture_storage_2d_array<rgba32uint, write>;

@compute @workgroup_size(8, 8, 1)
fn blend_keys(@builtin(global_invocation_id) id: vec3<u32>) {
    let n = cam.face;
    let pair = id.z / 6u;
    if id.x >= n || id.y >= n || pair >= min(cam.pair_count, MAX_PAIRS) {
        return;
    }
    let face = id.z % 6u;
    let k = cam.pairs[pair].xy;
    let l0 = cam.lookups[k.x].first_layer + face;
    let l1 = cam.lookups[k.y].first_layer + face;
    let a = textureLoad(cubes, id.xy, l0, 0);
    let b = textureLoad(cubes, id.xy, l1, 0);
    let sa = textureLoad(shading_cubes, id.xy, l0, 0).xy;
    let sb = textureLoad(shading_cubes, id.xy, l1, 0).xy;
    let w0 = cam.lookups[k.x].weight;
    let w1 = cam.lookups[k.y].weight;
    let s = 1.0 / max(w0 + w1, 1e-9);
    let lighting = (rgb9e5_decode(sa.x) * w0 + rgb9e5_decode(sb.x) * w1) * s;
    let non_diffuse = (rgb9e5_decode(sa.y) * w0 + rgb9e5_decode(sb.y) * w1) * s;
    let same = all(a.yzw == b.yzw);
    let layer = pair * 6u + face;
    textureStore(geometry_out, id.xy, layer, vec4<u32>(0u, a.y, select(PAIR_CHANGING, a.z, same), a.w));
    textureStore(terms_out, id.xy, layer, vec4<u32>(pack_pair(lighting, non_diffuse), 0u));
}
