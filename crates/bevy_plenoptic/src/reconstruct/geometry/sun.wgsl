// The runtime sun of geometry-assisted reconstruction (pack 3; thesis §8.2.3;
// plenoptic_recon's sun and brdf modules, the same formulas): the sun's direct light added per
// lit fragment through its full BSDF, shadowed by Bevy's shadow map of the directional light
// the plugin keeps aimed along the pack's sun (sun.rs) and dimmed by the glazing it crosses
// (rays.wgsl's see_through_pass over the glazing's own BVHs; glazing casts no shadow).
#define_import_path plenoptic::geometry::sun

#import bevy_pbr::forward_io::VertexOutput
#import bevy_pbr::mesh_view_bindings::{view, lights}
#import bevy_pbr::shadows::fetch_directional_shadow
#import plenoptic::geometry::bindings::{cam, params, pixel_base, pixel_metallic, pixel_roughness}
#import plenoptic::counters::{tally, C_SAMPLES}
#import plenoptic::rays::{has_rays, see_through_pass}
#import plenoptic::geometry::bsdf::{fresnel_dielectric, ggx_d, smith_g1, glossy_bsdf, lambert, viewer}

// The BSDF for light from `wi` seen along `wo`, with shading normal `n` and geometric normal
// `ng` (both on wo's side), relative IOR `eta`; the fragment's material.
fn sun_bsdf(wi: vec3<f32>, wo: vec3<f32>, n: vec3<f32>, ng: vec3<f32>, eta: f32) -> vec3<f32> {
    let cos_i = dot(wi, n);
    let reflect = cos_i > 0.0;
    if reflect != (dot(wi, ng) > 0.0) {
        return vec3<f32>(0.0);
    }
    let cos_o = dot(wo, n);
    let m = pixel_metallic;
    let tr = params.transmission;
    let alpha = max(pixel_roughness * pixel_roughness, 1e-4);
    let delta = pixel_roughness < 0.02;
    if reflect {
        let f = lambert(dot(wo, normalize(wo + wi)), eta);
        if delta {
            return f;
        }
        return f + glossy_bsdf(wi, wo, n, ng, alpha, eta);
    }
    if delta || tr <= 0.0 || m >= 1.0 {
        return vec3<f32>(0.0);
    }
    var h = normalize(wo + wi * eta);
    if dot(h, n) < 0.0 {
        h = -h;
    }
    let woh = dot(wo, h);
    let wih = dot(wi, h);
    if woh * wih >= 0.0 {
        return vec3<f32>(0.0);
    }
    let denom = (wih + woh / eta) * (wih + woh / eta);
    let fd = fresnel_dielectric(abs(woh), eta);
    let d = ggx_d(alpha, dot(h, n));
    let g = smith_g1(alpha, cos_o) * smith_g1(alpha, cos_i);
    let ft = d * (1.0 - fd) * g * abs(wih * woh / (cos_i * cos_o * denom)) / (eta * eta);
    return pixel_base * ((1.0 - m) * tr * ft);
}

// The sun's direct light towards the eye: BSDF × illuminance × cosine × the shadow of the
// plugin's sun light (Bevy's cascaded shadow map of the proxies). `ng_raw`: the triangle's
// plane from the position's derivatives.
fn sun_light(in: VertexOutput, ng_raw: vec3<f32>) -> vec3<f32> {
    let v = viewer(in, ng_raw);
    let n = v.n;
    let ng = v.ng;
    let wo = v.wo;
    let eta = v.eta;
    // Surfaces whose every lobe is ideal take no light sample (as the tracer).
    let fd = fresnel_dielectric(clamp(dot(wo, n), 1e-4, 1.0), eta);
    let lum = dot(pixel_base, vec3<f32>(0.2126, 0.7152, 0.0722));
    let diffuse = (1.0 - pixel_metallic) * (1.0 - params.transmission) * (1.0 - fd) * max(lum, 0.0) > 0.0;
    if !diffuse && pixel_roughness < 0.02 {
        return vec3<f32>(0.0);
    }
    let wi = normalize(cam.sun.xyz);
    let f = sun_bsdf(wi, wo, n, ng, eta);
    if all(f == vec3<f32>(0.0)) {
        return vec3<f32>(0.0);
    }
    // The plugin's sun light: the directional light aimed along the same direction.
    var shadow = 1.0;
    for (var i = 0u; i < lights.n_directional_lights; i++) {
        let l = &lights.directional_lights[i];
        if dot((*l).direction_to_light, wi) > 0.99999 {
            let view_z = dot(vec4<f32>(
                view.view_from_world[0].z,
                view.view_from_world[1].z,
                view.view_from_world[2].z,
                view.view_from_world[3].z
            ), in.world_position);
            let towards = select(-ng, ng, dot(wi, ng) >= 0.0);
            // One filtered sample per shadow lookup (Bevy's filter taps are not counted).
            tally(C_SAMPLES, 1u);
            shadow = fetch_directional_shadow(i, in.world_position, towards, view_z, in.position.xy);
            // Glazing is not in the shadow map: it lets 1 − c through at each surface, as
            // plenoptic_recon's shadow rays pass it.
            if shadow > 0.0 && has_rays() {
                let eps = 1e-4 * (1.0 + max(max(abs(in.world_position.x), abs(in.world_position.y)), abs(in.world_position.z)));
                shadow *= see_through_pass(in.world_position.xyz + towards * eps, wi, 1e9);
            }
            break;
        }
    }
    return f * cam.sun_illuminance.xyz * abs(dot(wi, n)) * shadow;
}
