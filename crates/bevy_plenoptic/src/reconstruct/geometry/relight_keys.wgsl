// The light-group relight pass (relight.rs; reconstruct/relight.rs): per texel of the six
// faces of each key the camera looks up, its stored key texel and (lighting, non-diffuse)
// relit at the camera's weights, written into the camera's relit keys at the lookup's layers
// (6k + face). The keys and the camera's view buffer are bound as the materials bind them
// (group 1, MATERIAL_BIND_GROUP); the outputs and the pack's group layers in group 0.
#import plenoptic::cube::{rgb9e5_decode, rgb9e5_encode}
#import plenoptic::geometry::bindings::{cam, cubes, shading_cubes, MAX_LOOKUPS}
#import plenoptic::relight::{stored_terms, blend_base, blend_layer, blend_end, relit_radiance}

@group(0) @binding(0) var keys_out: texture_storage_2d_array<rgba32uint, write>;
@group(0) @binding(1) var shading_out: texture_storage_2d_array<rg32uint, write>;
// Per key slot and stored group, six faces of (lighting, non-diffuse) RGB9E5 texels.
@group(0) @binding(2) var<storage, read> group_layers: array<vec2<u32>>;

@compute @workgroup_size(8, 8, 1)
fn relight_keys(@builtin(global_invocation_id) id: vec3<u32>) {
    let n = cam.face;
    let k = id.z / 6u;
    if id.x >= n || id.y >= n || k >= min(cam.lookup_count, MAX_LOOKUPS) {
        return;
    }
    let face = id.z % 6u;
    let source = cam.lookups[k].source_layer;
    let key = textureLoad(cubes, id.xy, source + face, 0);
    let stored = stored_terms(textureLoad(shading_cubes, id.xy, source + face, 0).xy);
    var acc = blend_base(cam.light_base.xyz, stored);
    let texel = (face * n + id.y) * n + id.x;
    let slot = source / 6u;
    for (var l = 0u; l < cam.light_layer_count; l++) {
        let g = slot * cam.light_groups + cam.light_layers[l].group;
        acc = blend_layer(acc, cam.light_layers[l].coefficient, group_layers[g * 6u * n * n + texel]);
    }
    let relit = blend_end(acc);
    // A texel that sees no object shows the sky.
    let fallback = select(cam.light_base.xyz, cam.light_sky.xyz, key.z == 0u);
    let radiance = relit_radiance(rgb9e5_decode(key.x), stored, relit, fallback);
    let layer = 6u * k + face;
    textureStore(keys_out, id.xy, layer, vec4<u32>(rgb9e5_encode(radiance), key.yzw));
    let terms = vec4<u32>(rgb9e5_encode(relit[0]), rgb9e5_encode(relit[1]), 0u, 0u);
    textureStore(shading_out, id.xy, layer, terms);
}
