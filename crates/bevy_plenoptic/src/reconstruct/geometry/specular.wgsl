// Reflections for the camera in geometry-assisted reconstruction (thesis §8.2.3;
// plenoptic_recon's specular and lamps modules, the same formulas): on mirrors and glossy
// metals the baked non-diffuse radiance is replaced by rays reflected for the camera and
// marched through the lookups' distance cubes (reflect.wgsl), cast against the proxies for
// the environment (rays.wgsl), glossy lobes sampled by roughness, with the placed lamps'
// highlights.
#define_import_path plenoptic::geometry::specular

#import bevy_pbr::forward_io::VertexOutput
#import bevy_pbr::mesh_view_bindings::view
#import plenoptic::environment::environment
#import plenoptic::reflect::{march, fetch, orthonormal_pair}
#import plenoptic::rays::{has_rays, occluded}
#import plenoptic::counters::{tally, C_LOADS_16}
#import plenoptic::geometry::lamps::{towards, visible}
#import plenoptic::geometry::bindings::{
    MAX_LOOKUPS, cam, params, cubes, env_image, pixel_base, pixel_metallic, pixel_roughness,
    view_has, image_mode, VIEW_MARCHED, object_has, OBJECT_SEE_THROUGH,
}
#import plenoptic::geometry::bsdf::{
    fresnel_dielectric, fresnel_schlick, glossy_weight, glossy_bsdf, viewer,
}

// How far off its surface a reflected ray is cast (plenoptic_recon::specular's RAY_OFFSET).
const RAY_OFFSET: f32 = 0.001;

// Whether this fragment's surface is marched: no transmission, an ideal mirror, or glossy
// up to the roughest surface marched.
fn marched() -> bool {
    return view_has(VIEW_MARCHED) && (params.transmission <= 0.0 || see_through())
        && (pixel_roughness < 0.02 || pixel_roughness <= cam.glossy_roughness);
}

// Whether this fragment is see-through transmissive glass (flags.z).
fn see_through() -> bool {
    return object_has(OBJECT_SEE_THROUGH) && !image_mode();
}

// The pack's environment in direction `dir` (an image's 4 bilinear texels counted).
fn environment_towards(dir: vec3<f32>) -> vec3<f32> {
    if cam.env.kind.x == 3.0 {
        tally(C_LOADS_16, 4u);
    }
    return environment(cam.env, env_image, dir);
}

// Radiance arriving at `origin` along unit `dir`, over a cone of half-angle `cone`, from the
// lookups' keys: (radiance, 1), or (0, 0) where no lookup can tell.
fn incoming(origin: vec3<f32>, dir: vec3<f32>, cone: f32) -> vec4<f32> {
    // A ray that meets no proxy has left the scene (plenoptic_recon::specular's escape
    // test, cast off the surface it starts on).
    if has_rays() && !occluded(origin + dir * RAY_OFFSET, dir, cam.march_distance) {
        return vec4<f32>(environment_towards(dir), 1.0);
    }
    let count = min(cam.lookup_count, MAX_LOOKUPS);
    let n = cam.face;
    var sum = vec3<f32>(0.0);
    var total = 0.0;
    var escaped = false;
    for (var k = 0u; k < count; k++) {
        if cam.lookups[k].weight <= 0.0 {
            continue;
        }
        let centre = cam.lookups[k].base;
        let layer0 = cam.lookups[k].first_layer;
        let m = march(cubes, layer0, n, centre, origin, dir, cam.march_distance, cam.depth_tolerance);
        if m.y == 1.0 {
            let to = origin + dir * m.x - centre;
            let d = length(to);
            let cos = dot(to, dir) / max(d, 1e-6);
            let w = cam.lookups[k].weight * pow(max((1.0 + cos) * 0.5, 1e-3), cam.angular_power);
            let angle = min(cone * m.x / max(d, 1e-3), 0.5);
            sum += fetch(cubes, layer0, n, to, angle) * w;
            total += w;
        } else if m.y == 2.0 {
            escaped = true;
        }
    }
    if total > 0.0 {
        return vec4<f32>(sum / total, 1.0);
    }
    if escaped {
        return vec4<f32>(environment_towards(dir), 1.0);
    }
    return vec4<f32>(0.0);
}

// The radiance the glossy lobe (roughness `alpha`, the fragment's material) reflects
// towards `wo` around `n` (geometric normal `ng`, relative IOR `eta`): cam.glossy_rays
// directions reflected about GGX half-vectors, a Hammersley set turned by `turn`, each
// weighted by F · G · (ω_o·h) / ((n·ω_o)(n·h)) (plenoptic_recon's Bsdf::glossy_weight).
fn lobe(origin: vec3<f32>, n: vec3<f32>, ng: vec3<f32>, wo: vec3<f32>, alpha: f32, eta: f32, turn: f32) -> vec4<f32> {
    let pair = orthonormal_pair(n);
    var sum = vec3<f32>(0.0);
    var count = 0.0;
    let rays = cam.glossy_rays;
    for (var k = 0u; k < rays; k++) {
        let u1 = (f32(k) + 0.5) / f32(rays);
        let u2 = fract(f32(reverseBits(k)) / 4294967296.0 + turn);
        let tan2 = alpha * alpha * u1 / (1.0 - u1);
        let cos_h = 1.0 / sqrt(1.0 + tan2);
        let sin_h = sqrt(max(1.0 - cos_h * cos_h, 0.0));
        let phi = 6.28318530717959 * u2;
        let h = n * cos_h + (pair[0] * cos(phi) + pair[1] * sin(phi)) * sin_h;
        let wi = h * (2.0 * dot(wo, h)) - wo;
        let w = glossy_weight(h, wi, wo, n, ng, alpha, eta);
        if all(w == vec3<f32>(0.0)) {
            // Below the surface: no light, but the lobe's share all the same.
            count += 1.0;
            continue;
        }
        let l = incoming(origin, wi, 0.7 * alpha);
        if l.w > 0.0 {
            sum += l.rgb * w;
            count += 1.0;
        }
    }
    if count > 0.0 {
        return vec4<f32>(sum / count, 1.0);
    }
    return vec4<f32>(0.0);
}

// The placed lamps' highlights at `p` (plenoptic_recon's lamps::highlights): the glossy lobe
// × the lamp's irradiance × the cosine × its shadow ray (lamps.wgsl).
fn highlights(p: vec3<f32>, n: vec3<f32>, ng: vec3<f32>, wo: vec3<f32>, alpha: f32, eta: f32) -> vec3<f32> {
    var sum = vec3<f32>(0.0);
    for (var k = 0u; k < cam.lamp_count; k++) {
        let ray = towards(cam.lamps[k], p);
        if all(ray.irradiance == vec3<f32>(0.0)) {
            continue;
        }
        let f = glossy_bsdf(ray.wi, wo, n, ng, alpha, eta);
        if all(f == vec3<f32>(0.0)) {
            continue;
        }
        sum += f * ray.irradiance * abs(dot(ray.wi, n)) * visible(p, ng, ray);
    }
    return sum;
}

// An ideal mirror's reflectance at n·ω_o = `cos_in` (plenoptic_recon's specular::reflectance):
// the exact Fresnel.
fn reflectance(cos_in: f32, eta: f32) -> vec3<f32> {
    let cos_o = clamp(cos_in, 1e-4, 1.0);
    let m = pixel_metallic;
    return vec3<f32>((1.0 - m) * fresnel_dielectric(cos_o, eta))
        + fresnel_schlick(pixel_base, cos_o) * m;
}

// The reflection at this fragment for the camera: (emission-free specular radiance, 1), or
// (0, 0) where no lookup answers.
fn reflection(in: VertexOutput, ng_raw: vec3<f32>) -> vec4<f32> {
    let v = viewer(in, ng_raw);
    let cos_o = dot(v.wo, v.n);
    let origin = in.world_position.xyz;
    var l: vec4<f32>;
    if pixel_roughness < 0.02 {
        let dir = normalize(v.n * (2.0 * cos_o) - v.wo);
        l = incoming(origin, dir, 0.0);
    } else {
        // The pixel's index in the frame, as the CPU's per-pixel turn.
        let px = vec2<u32>(in.position.xy - view.viewport.xy);
        let j = px.y * u32(view.viewport.z) + px.x;
        let turn = fract(f32(j) * 0.618034);
        let alpha = max(pixel_roughness * pixel_roughness, 1e-4);
        l = lobe(origin, v.n, v.ng, v.wo, alpha, v.eta, turn);
        if l.w == 0.0 {
            return l;
        }
        return vec4<f32>(l.rgb + highlights(origin, v.n, v.ng, v.wo, alpha, v.eta), 1.0);
    }
    if l.w == 0.0 {
        return l;
    }
    return vec4<f32>(reflectance(cos_o, v.eta) * l.rgb, 1.0);
}
