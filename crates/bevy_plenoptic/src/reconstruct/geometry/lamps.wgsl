// The placed lamps' direct light in geometry-assisted reconstruction (packs 4.1 and 5.0;
// thesis ch. 5; plenoptic_recon's lamps module, the same formulas): each lamp's irradiance at
// a point (glTF's spot falloff, nothing beyond its range), shadowed by a ray against the
// proxies that glazing dims (rays.wgsl's transmittance). specular.wgsl lights marched glossy
// surfaces' highlights with it; with VIEW_LAMPS every lit fragment adds the lamps' diffuse
// light, which the pack left out of its lighting.
#define_import_path plenoptic::geometry::lamps

#import bevy_pbr::forward_io::VertexOutput
#import plenoptic::rays::{has_rays, transmittance}
#import plenoptic::geometry::bindings::{cam, Lamp}
#import plenoptic::geometry::bsdf::{diffuse_bsdf, viewer}

// A lamp seen from a point: the unit direction towards it, its distance, and the irradiance
// normal to that direction (zero beyond the range or outside the cone).
struct LampRay {
    wi: vec3<f32>,
    dist: f32,
    irradiance: vec3<f32>,
}

// plenoptic_recon's RuntimeLamp::towards.
fn towards(lamp: Lamp, p: vec3<f32>) -> LampRay {
    let d = lamp.position - p;
    let dist2 = dot(d, d);
    let dist = sqrt(dist2);
    if dist <= 0.0 || (lamp.range > 0.0 && dist > lamp.range) {
        return LampRay(vec3<f32>(0.0, 0.0, 1.0), 0.0, vec3<f32>(0.0));
    }
    let wi = d / dist;
    var value = lamp.radiant / dist2;
    if lamp.cos_outer > -1.5 {
        let att = clamp((dot(lamp.axis, -wi) - lamp.cos_outer) * lamp.cone_scale, 0.0, 1.0);
        value *= att * att;
    }
    return LampRay(wi, dist, value);
}

// What reaches `p` (geometric normal `ng`, either side) from the lamp along `ray`: the
// shadow ray from just off the surface, on the lamp's side, to just short of the lamp.
fn visible(p: vec3<f32>, ng: vec3<f32>, ray: LampRay) -> f32 {
    if !has_rays() {
        return 1.0;
    }
    let eps = 1e-4 * (1.0 + max(max(abs(p.x), abs(p.y)), abs(p.z)));
    let origin = p + select(-ng, ng, dot(ray.wi, ng) >= 0.0) * eps;
    return transmittance(origin, ray.wi, ray.dist - 2.0 * eps);
}

// The lamps' direct diffuse light towards the eye (plenoptic_recon's lamps::diffuse): the
// fragment's Lambertian lobe × each lamp's irradiance × the cosine × its shadow ray.
// `ng_raw`: the triangle's plane from the position's derivatives.
fn lamps_diffuse(in: VertexOutput, ng_raw: vec3<f32>) -> vec3<f32> {
    let v = viewer(in, ng_raw);
    let p = in.world_position.xyz;
    var sum = vec3<f32>(0.0);
    for (var k = 0u; k < cam.lamp_count; k++) {
        let ray = towards(cam.lamps[k], p);
        if all(ray.irradiance == vec3<f32>(0.0)) {
            continue;
        }
        let f = diffuse_bsdf(ray.wi, v.wo, v.n, v.ng, v.eta);
        if all(f == vec3<f32>(0.0)) {
            continue;
        }
        sum += f * ray.irradiance * abs(dot(ray.wi, v.n)) * visible(p, v.ng, ray);
    }
    return sum;
}
