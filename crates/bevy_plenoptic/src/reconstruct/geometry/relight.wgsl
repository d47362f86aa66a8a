// Light groups (reconstruct/relight.rs; plenoptic_recon's relight module): a texel's or
// volume sample's stored (lighting, non-diffuse) blended with its groups' layers at the
// camera's weights, base · total + Σ c · layer clamped at zero, and its radiance relit by the
// ratio of the relit light to the stored light.
#define_import_path plenoptic::geometry::relight

#import plenoptic::cube::rgb9e5_decode
#import plenoptic::counters::{tally, C_LOADS_16}
#import plenoptic::geometry::bindings::{cam, volume_samples, lit, view_has, VIEW_RELIT}

// The total's part of the blend: base · the stored terms.
fn blend_base(stored: mat2x3<f32>) -> mat2x3<f32> {
    let b = cam.light_base.xyz;
    return mat2x3<f32>(b * stored[0], b * stored[1]);
}

// `acc` with blended layer `k` added: its coefficient × the group's (lighting, non-diffuse)
// RGB9E5 pair `layer`.
fn blend_layer(acc: mat2x3<f32>, k: u32, layer: vec2<u32>) -> mat2x3<f32> {
    let c = cam.light_layers[k].xyz;
    return acc + mat2x3<f32>(c * rgb9e5_decode(layer.x), c * rgb9e5_decode(layer.y));
}

// The blend clamped at zero (quantised layers may overshoot the total by their rounding).
fn blend_end(acc: mat2x3<f32>) -> mat2x3<f32> {
    return mat2x3<f32>(max(acc[0], vec3<f32>(0.0)), max(acc[1], vec3<f32>(0.0)));
}

// plenoptic_recon::relight::relit_radiance: `radiance` × (`light` / `stored`) per channel
// (the relit and the stored lighting + non-diffuse), `fallback` where the stored light is zero.
fn relit_radiance(radiance: vec3<f32>, stored: vec3<f32>, light: vec3<f32>, fallback: vec3<f32>) -> vec3<f32> {
    let some = stored > vec3<f32>(1e-12);
    return radiance * select(fallback, light / max(stored, vec3<f32>(1e-12)), some);
}

// Volume sample `s`'s terms at the camera's light groups: its (lighting, non-diffuse) for an
// object shaded from its material, else (its radiance, 0). `terms` are its stored RGB9E5
// pair; its layers are the group words at `cam.volume_groups` (vec4s of the sample buffer):
// two words per sample and stored group.
fn volume_terms(s: u32, terms: vec2<u32>, radiance: vec3<f32>) -> mat2x3<f32> {
    let stored = mat2x3<f32>(rgb9e5_decode(terms.x), rgb9e5_decode(terms.y));
    if !view_has(VIEW_RELIT) {
        if lit() {
            return stored;
        }
        return mat2x3<f32>(radiance, vec3<f32>(0.0));
    }
    var acc = blend_base(stored);
    for (var k = 0u; k < cam.light_layer_count; k++) {
        let w = 2u * (s * cam.light_groups + u32(cam.light_layers[k].w));
        tally(C_LOADS_16, 1u);
        let v = volume_samples[cam.volume_groups + w / 4u];
        acc = blend_layer(acc, k, select(v.xy, v.zw, (w & 2u) != 0u));
    }
    let relit = blend_end(acc);
    if lit() {
        return relit;
    }
    let light = relit[0] + relit[1];
    let rad = relit_radiance(radiance, stored[0] + stored[1], light, cam.light_base.xyz);
    return mat2x3<f32>(rad, vec3<f32>(0.0));
}
