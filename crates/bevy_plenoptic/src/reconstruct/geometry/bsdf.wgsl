// The fragment's BSDF terms (plenoptic_recon's brdf module and Bsdf, the same formulas), shared
// by the runtime sun (sun.wgsl), the lamps (lamps.wgsl) and the reflections for the camera
// (specular.wgsl) of
// geometry-assisted reconstruction (thesis §8.2.3): the exact dielectric Fresnel and
// Schlick's, GGX with separable Smith masking, the glossy lobe, and the shading frame of a
// fragment seen from the eye. The material is the fragment's (bindings.wgsl's pixel_*).
#define_import_path plenoptic::geometry::bsdf

#import bevy_pbr::forward_io::VertexOutput
#import bevy_pbr::mesh_view_bindings::view
#import plenoptic::geometry::bindings::{params, pixel_base, pixel_metallic}

const PI: f32 = 3.14159265358979;

fn fresnel_dielectric(cos_in: f32, eta: f32) -> f32 {
    let cos_i = clamp(cos_in, 0.0, 1.0);
    let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = sqrt(1.0 - sin2_t);
    let r_par = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    return 0.5 * (r_par * r_par + r_perp * r_perp);
}

fn fresnel_schlick(f0: vec3<f32>, cos: f32) -> vec3<f32> {
    let m = pow(1.0 - clamp(cos, 0.0, 1.0), 5.0);
    return f0 + (vec3<f32>(1.0) - f0) * m;
}

fn ggx_d(alpha: f32, cos_h: f32) -> f32 {
    if cos_h <= 0.0 {
        return 0.0;
    }
    let a2 = alpha * alpha;
    let d = cos_h * cos_h * (a2 - 1.0) + 1.0;
    return a2 / (PI * d * d);
}

fn smith_g1(alpha: f32, cos: f32) -> f32 {
    let c = abs(cos);
    let a2 = alpha * alpha;
    return 2.0 * c / (c + sqrt(a2 + (1.0 - a2) * c * c));
}

// plenoptic_recon's Bsdf::lambert: the Lambertian lobe at ω_o·h, what the dielectric Fresnel
// lets into the surface, scattered uniformly.
fn lambert(voh: f32, eta: f32) -> vec3<f32> {
    let fd = fresnel_dielectric(clamp(voh, 0.0, 1.0), eta);
    return pixel_base * ((1.0 - pixel_metallic) * (1.0 - params.transmission) * (1.0 - fd) / PI);
}

// plenoptic_recon's Bsdf::eval_diffuse: the Lambertian lobe alone, zero below the surface.
fn diffuse_bsdf(wi: vec3<f32>, wo: vec3<f32>, n: vec3<f32>, ng: vec3<f32>, eta: f32) -> vec3<f32> {
    if dot(wi, n) <= 0.0 || dot(wi, ng) <= 0.0 {
        return vec3<f32>(0.0);
    }
    let h = wo + wi;
    if dot(h, h) <= 0.0 {
        return vec3<f32>(0.0);
    }
    return lambert(dot(wo, normalize(h)), eta);
}

// plenoptic_recon's Bsdf::glossy_weight for the fragment's material.
fn glossy_weight(h: vec3<f32>, wi: vec3<f32>, wo: vec3<f32>, n: vec3<f32>, ng: vec3<f32>, alpha: f32, eta: f32) -> vec3<f32> {
    let cos_o = dot(wo, n);
    let cos_i = dot(wi, n);
    let cos_h = dot(h, n);
    if cos_i <= 0.0 || cos_h <= 0.0 || dot(wi, ng) <= 0.0 {
        return vec3<f32>(0.0);
    }
    let voh = clamp(dot(wo, h), 0.0, 1.0);
    let g = smith_g1(alpha, cos_o) * smith_g1(alpha, cos_i);
    return glossy_fresnel(voh, eta) * (g * voh / max(cos_o * cos_h, 1e-8));
}

// The glossy lobe's Fresnel term at ω_o·h (plenoptic_recon's Bsdf::glossy_fresnel): the exact
// dielectric one for the non-metallic part, Schlick's with the base colour for the metallic.
fn glossy_fresnel(voh: f32, eta: f32) -> vec3<f32> {
    let m = pixel_metallic;
    return vec3<f32>((1.0 - m) * fresnel_dielectric(voh, eta)) + fresnel_schlick(pixel_base, voh) * m;
}

// plenoptic_recon's Bsdf::eval_glossy: the GGX reflection lobe alone.
fn glossy_bsdf(wi: vec3<f32>, wo: vec3<f32>, n: vec3<f32>, ng: vec3<f32>, alpha: f32, eta: f32) -> vec3<f32> {
    let cos_i = dot(wi, n);
    if cos_i <= 0.0 || dot(wi, ng) <= 0.0 {
        return vec3<f32>(0.0);
    }
    let h = normalize(wo + wi);
    let voh = clamp(dot(wo, h), 0.0, 1.0);
    let d = ggx_d(alpha, dot(h, n));
    let g = smith_g1(alpha, dot(wo, n)) * smith_g1(alpha, cos_i);
    return glossy_fresnel(voh, eta) * (d * g / max(4.0 * dot(wo, n) * cos_i, 1e-8));
}

// The shading frame of a fragment seen from the eye: the shading normal `n` and geometric
// normal `ng` on the viewer's side (n bent towards the viewer where it faces away, as
// plenoptic_recon's Bsdf::new), the direction `wo` towards the eye and the relative IOR.
struct Viewer {
    n: vec3<f32>,
    ng: vec3<f32>,
    wo: vec3<f32>,
    eta: f32,
}

fn viewer(in: VertexOutput, ng_raw: vec3<f32>) -> Viewer {
    let p = in.world_position.xyz;
    let wo = normalize(view.world_position - p);
    var ns = normalize(in.world_normal);
    var ng = ns;
    if dot(ng_raw, ng_raw) > 1e-20 {
        ng = normalize(ng_raw);
        // The winding's side: the vertex normals follow it.
        if dot(ng, ns) < 0.0 {
            ng = -ng;
        }
    }
    let front = dot(wo, ng) > 0.0;
    let side = select(-1.0, 1.0, dot(wo, ng) >= 0.0);
    ng = ng * side;
    var n = ns * side;
    if dot(n, wo) < 1e-4 {
        n = n - wo * (dot(n, wo) - 1e-4);
        n = select(ng, normalize(n), dot(n, n) > 0.0);
    }
    let ior = select(1.5, params.ior, params.ior > 0.0);
    return Viewer(n, ng, wo, select(1.0 / ior, ior, front));
}
