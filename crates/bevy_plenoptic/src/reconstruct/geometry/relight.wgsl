// Light groups in the geometry-assisted lookups (reconstruct/relight.rs): the temporal-volume
// fallback's samples blended with their group layers at the camera's weights where they are
// read (the keys are relit once per frame by relight_keys.wgsl instead).
#define_import_path plenoptic::geometry::relight

#import plenoptic::relight::{stored_terms, blend_base, blend_layer, blend_end, relit_radiance}
#import plenoptic::counters::{tally, C_LOADS_16}
#import plenoptic::geometry::bindings::{cam, volume_samples, point_material, view_has, VIEW_RELIT}

// Volume sample `s`'s terms at the camera's light groups: its (lighting, non-diffuse) for an
// object shaded from its material, else (its radiance, 0). `terms` are its stored RGB9E5
// pair; its layers are the group words at `cam.volume_groups` (vec4s of the sample buffer):
// two words per sample and stored group.
fn volume_terms(s: u32, terms: vec2<u32>, radiance: vec3<f32>) -> mat2x3<f32> {
    let stored = stored_terms(terms);
    if !view_has(VIEW_RELIT) {
        if point_material {
            return stored;
        }
        return mat2x3<f32>(radiance, vec3<f32>(0.0));
    }
    var acc = blend_base(cam.light_base.xyz, stored);
    for (var k = 0u; k < cam.light_layer_count; k++) {
        let w = 2u * (s * cam.light_groups + cam.light_layers[k].group);
        tally(C_LOADS_16, 1u);
        let v = volume_samples[cam.volume_groups + w / 4u];
        acc = blend_layer(acc, cam.light_layers[k].coefficient, select(v.xy, v.zw, (w & 2u) != 0u));
    }
    let relit = blend_end(acc);
    if point_material {
        return relit;
    }
    let rad = relit_radiance(radiance, stored, relit, cam.light_base.xyz);
    return mat2x3<f32>(rad, vec3<f32>(0.0));
}
