// Light groups (relight.rs; plenoptic_recon's relight module): a texel's or volume sample's
// stored (lighting, non-diffuse) blended with its groups' layers, base · total + Σ c · layer
// clamped at zero, and its radiance relit by the ratio of the relit light to the stored
// light. Pure functions: each pass reads the layers from its own bindings.
#define_import_path plenoptic::relight

#import plenoptic::cube::rgb9e5_decode

// A layer blended (relight.rs, LightLayerParams): its coefficient and its stored group.
struct LightLayer {
    coefficient: vec3<f32>,
    group: u32,
}

// A stored RGB9E5 (lighting, non-diffuse) pair decoded.
fn stored_terms(pair: vec2<u32>) -> mat2x3<f32> {
    return mat2x3<f32>(rgb9e5_decode(pair.x), rgb9e5_decode(pair.y));
}

// The total's part of the blend: `base` · the stored terms.
fn blend_base(base: vec3<f32>, stored: mat2x3<f32>) -> mat2x3<f32> {
    return mat2x3<f32>(base * stored[0], base * stored[1]);
}

// `acc` with a layer added: coefficient `c` × the group's RGB9E5 (lighting, non-diffuse)
// pair `layer`.
fn blend_layer(acc: mat2x3<f32>, c: vec3<f32>, layer: vec2<u32>) -> mat2x3<f32> {
    return acc + blend_base(c, stored_terms(layer));
}

// The blend clamped at zero (quantised layers may overshoot the total by their rounding).
fn blend_end(acc: mat2x3<f32>) -> mat2x3<f32> {
    return mat2x3<f32>(max(acc[0], vec3<f32>(0.0)), max(acc[1], vec3<f32>(0.0)));
}

// plenoptic_recon::relight::relit_radiance: `radiance` × the relit over the stored light
// (each lighting + non-diffuse) per channel, `fallback` where the stored light is zero.
fn relit_radiance(radiance: vec3<f32>, stored: mat2x3<f32>, relit: mat2x3<f32>, fallback: vec3<f32>) -> vec3<f32> {
    let light = stored[0] + stored[1];
    let some = light > vec3<f32>(1e-12);
    return radiance * select(fallback, (relit[0] + relit[1]) / max(light, vec3<f32>(1e-12)), some);
}
