// The proxy material at the fragment's UV (thesis §8.2.3, pack 2.0 shading; plenoptic_recon's
// material module): the diffuse albedo, base colour, metalness and roughness from the
// material's factors × textures (KHR_texture_transform, the mip level of the pixel's
// footprint), its emission and the normal-mapped shading normal. A lit app mesh
// (PLENOPTIC_STANDARD) reads these from its StandardMaterial instead.
#define_import_path plenoptic::geometry::material

#import bevy_pbr::forward_io::VertexOutput
#import bevy_pbr::mesh_view_bindings::view
#import plenoptic::geometry::bindings::{params, object_has, OBJECT_DOUBLE_SIDED}
#import plenoptic::counters::{tally, C_SAMPLES}
#ifndef PLENOPTIC_STANDARD
#import plenoptic::geometry::bindings::{
    base_colour_texture, base_colour_sampler, metallic_roughness_texture,
    metallic_roughness_sampler, normal_texture, normal_sampler, emissive_texture,
    emissive_sampler, pixel_base, pixel_metallic, pixel_roughness,
}
#endif

// KHR_texture_transform: offset + R(rotation) · (scale ∘ uv).
fn uv_transform(uv: vec2<f32>, t: vec4<f32>, rotation: f32) -> vec2<f32> {
    let s = uv * t.zw;
    let c = cos(rotation);
    let n = sin(rotation);
    return t.xy + vec2<f32>(c * s.x + n * s.y, -n * s.x + c * s.y);
}

// The mip level plenoptic_recon's material module picks: log2 of the pixel's footprint in UV
// units (√ of the UV area one pixel covers, `footprint`) × the transform's scale × the side.
fn level(footprint: f32, t: vec4<f32>, side: f32) -> f32 {
    let texels = footprint * max(abs(t.z), abs(t.w)) * side;
    return select(0.0, log2(texels), texels > 1.0);
}

#ifndef PLENOPTIC_STANDARD
// The diffuse albedo at UV `uv`, whose pixel covers `footprint` UV units (√area):
// (1 − metallic · mr.b)(1 − transmission) · base colour · texture.
fn material_albedo(uv: vec2<f32>, footprint: f32) -> vec3<f32> {
    var base = params.albedo.xyz;
    var metallic = params.albedo.w;
    var roughness = params.roughness;
    if params.base_colour_size > 0.0 {
        let st = uv_transform(uv, params.base_uv, params.uv_rotation.x);
        let lod = level(footprint, params.base_uv, params.base_colour_size);
        tally(C_SAMPLES, 1u);
        base *= textureSampleLevel(base_colour_texture, base_colour_sampler, st, lod).rgb;
    }
    if params.metallic_roughness_size > 0.0 {
        let st = uv_transform(uv, params.mr_uv, params.uv_rotation.y);
        let lod = level(footprint, params.mr_uv, params.metallic_roughness_size);
        tally(C_SAMPLES, 1u);
        let mr = textureSampleLevel(metallic_roughness_texture, metallic_roughness_sampler, st, lod);
        metallic *= mr.b;
        roughness *= mr.g;
    }
    pixel_base = base;
    pixel_metallic = clamp(metallic, 0.0, 1.0);
    pixel_roughness = clamp(roughness, 0.0, 1.0);
    return base * ((1.0 - clamp(metallic, 0.0, 1.0)) * (1.0 - params.transmission));
}

// The emission at UV `uv` (footprint as above), as plenoptic_recon's Materials::emission:
// the emissive factor × the sRGB texture; from the front only unless double-sided.
fn material_emission(in: VertexOutput, uv: vec2<f32>, footprint: f32) -> vec3<f32> {
    var e = params.emissive.xyz;
    let front = dot(view.world_position - in.world_position.xyz, in.world_normal) > 0.0;
    if !object_has(OBJECT_DOUBLE_SIDED) && !front {
        return vec3<f32>(0.0);
    }
    if params.emissive_size > 0.0 && any(e != vec3<f32>(0.0)) {
        let st = uv_transform(uv, params.emissive_uv, params.uv_rotation.w);
        let lod = level(footprint, params.emissive_uv, params.emissive_size);
        tally(C_SAMPLES, 1u);
        e *= textureSampleLevel(emissive_texture, emissive_sampler, st, lod).rgb;
    }
    return e;
}

// The shading normal `ns` bent by the normal map at UV `uv` (footprint as above) in the
// frame of `tangent` (xyz, the bitangent's sign in w), as plenoptic_recon's
// material::bend_normal bends it; `ns` without a normal map or where the frame degenerates.
fn bent_normal(ns: vec3<f32>, tangent: vec4<f32>, uv: vec2<f32>, footprint: f32) -> vec3<f32> {
    if params.normal_map_size <= 0.0 {
        return ns;
    }
    let st = uv_transform(uv, params.normal_uv, params.uv_rotation.z);
    let lod = level(footprint, params.normal_uv, params.normal_map_size);
    tally(C_SAMPLES, 1u);
    let c = textureSampleLevel(normal_texture, normal_sampler, st, lod).rgb * 2.0 - 1.0;
    let local = vec3<f32>(c.xy * params.normal_scale, c.z);
    let t = tangent.xyz - ns * dot(ns, tangent.xyz);
    if dot(t, t) <= 1e-20 {
        return ns;
    }
    let tn = normalize(t);
    let b = cross(ns, tn) * select(1.0, -1.0, tangent.w < 0.0);
    let n = tn * local.x + b * local.y + ns * local.z;
    return select(ns, normalize(n), dot(n, n) > 1e-20);
}
#endif
