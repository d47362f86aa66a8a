// Geometry-assisted reconstruction (thesis §8.2.3), per fragment of a proxy mesh.
// Same lookups and weights as plenoptic_recon::geometry (nearest or seamless bilinear texel, id + distance test,
// w_view · w_time · ((1 + cos θ)/2)^p), with its volume fallback and hole fill. An object with a
// material in a 2.0 pack is shaded as plenoptic_recon's shading module does it:
// albedo (the material's factors × textures) · lighting + non-diffuse, both looked up
// bilinearly, the runtime sun (and, pack 5, the lamps' diffuse light) through the
// normal-mapped shading normal; on
// mirrors and glossy metals the non-diffuse part is replaced by reflections marched for the
// camera through the lookups' distance cubes (reflect.rs, reflect.wgsl).
// This file is the entry point: the fragment shaders of the proxy material and of a lit app
// mesh (PLENOPTIC_STANDARD), and the output. The rest is in the libraries beside it, in
// plenoptic::geometry: bindings (what the material binds, the fragment's state), material
// (albedo, textures, normal map), lookup (texel lookups, tests, weights, volume fallback),
// fill (hole fill and fallbacks), bsdf, sun (the runtime sun), lamps (the placed lamps) and
// specular (reflections).

#import bevy_pbr::forward_io::VertexOutput
#import bevy_pbr::mesh_view_bindings::view
#ifdef TONEMAP_IN_SHADER
#import bevy_core_pipeline::tonemapping::tone_mapping
#endif
#import bevy_pbr::mesh_functions::get_local_from_world
#ifdef PLENOPTIC_STANDARD
#import bevy_pbr::pbr_fragment::pbr_input_from_standard_material
#import bevy_pbr::pbr_functions::alpha_discard
#else
#import plenoptic::geometry::material::{material_albedo, material_emission, bent_normal}
#endif

#import plenoptic::geometry::bindings::{
    cam, params, lit, pixel_albedo, pixel_base, pixel_metallic, pixel_roughness,
    non_diffuse_weight, pixel_emission, local_from_world, view_has, image_mode, VIEW_SUN,
    VIEW_LAMPS,
    point_slot, point_material,
    glazing, object_has, OBJECT_RUNTIME_EMISSION,
}
#import plenoptic::geometry::fill::{radiance, write_fill_entry, note_fragment}
#import plenoptic::geometry::sun::sun_light
#import plenoptic::geometry::lamps::lamps_diffuse
#import plenoptic::geometry::specular::{marched, see_through, reflection}
#import plenoptic::counters::flush_counters

// The reconstructed radiance, times the camera's exposure as Bevy's own lights are
// (`view.exposure`, from its `Exposure`), kept inside the f16 HDR target's range; tonemapped
// here for cameras without an HDR target, as Bevy's PBR does (HDR cameras are tonemapped by
// Bevy's post-process pass).
#ifdef PLENOPTIC_STANDARD
// An app mesh: its own StandardMaterial's base colour, metalness, roughness and normal (its
// textures and normal map, as Bevy's PBR reads them) with the pack's lighting at this
// object's points, exactly as a proxy fragment of the same object is shaded.
#ifdef PLENOPTIC_EARLY_DEPTH
@early_depth_test(force)
#endif
@fragment
fn fragment(
    vertex: VertexOutput,
    @builtin(front_facing) is_front: bool,
    @builtin(sample_mask) coverage: u32,
) -> @location(0) vec4<f32> {
    local_from_world = get_local_from_world(vertex.instance_index);
    point_slot = params.motion_slot;
    point_material = lit();
    note_fragment(vertex.position, coverage);
    let ng = cross(dpdx(vertex.world_position.xyz), dpdy(vertex.world_position.xyz));
    var pbr = pbr_input_from_standard_material(vertex, is_front);
    pbr.material.base_color = alpha_discard(pbr.material, pbr.material.base_color);
    pixel_base = pbr.material.base_color.rgb;
    pixel_metallic = clamp(pbr.material.metallic, 0.0, 1.0);
    pixel_roughness = clamp(pbr.material.perceptual_roughness, 0.0, 1.0);
    pixel_albedo = pixel_base * ((1.0 - pixel_metallic) * (1.0 - params.transmission));
    var in = vertex;
    // The shading normal, normal-mapped (viewer() turns it towards the eye where needed).
    in.world_normal = pbr.N;
    return shade(in, ng);
}
#else
// With storage writes (cost counters, fill entries) a fragment shader is run before the depth
// test unless the test is forced first: forced, a fragment the depth prepass hid costs
// nothing and writes nothing.
#ifdef PLENOPTIC_EARLY_DEPTH
@early_depth_test(force)
#endif
@fragment
fn fragment(in: VertexOutput, @builtin(sample_mask) coverage: u32) -> @location(0) vec4<f32> {
    local_from_world = get_local_from_world(in.instance_index);
    point_slot = params.motion_slot;
    point_material = lit();
    note_fragment(in.position, coverage);
    // The triangle's plane, before any non-uniform branch.
    let ng = cross(dpdx(in.world_position.xyz), dpdy(in.world_position.xyz));
    // The material's albedo at the pixel (derivatives are taken before any non-uniform
    // branch). Without UVs the smallest level: the texture's mean, as on the CPU.
    var v = in;
#ifdef VERTEX_UVS_A
    let duv = abs(determinant(mat2x2<f32>(dpdx(in.uv), dpdy(in.uv))));
    pixel_albedo = material_albedo(in.uv, sqrt(duv));
    pixel_emission = material_emission(in, in.uv, sqrt(duv));
#ifdef VERTEX_TANGENTS
    v.world_normal = bent_normal(normalize(in.world_normal), in.world_tangent, in.uv, sqrt(duv));
#endif
#else
    pixel_albedo = material_albedo(vec2<f32>(0.0), 1e9);
    pixel_emission = material_emission(in, vec2<f32>(0.0), 1e9);
#endif
    return shade(v, ng);
}
#endif

// The fragment's output, once the private pixel_* values are set: its reflection, radiance
// and sun light, times the exposure.
fn shade(in: VertexOutput, ng: vec3<f32>) -> vec4<f32> {
    var reflected = vec3<f32>(0.0);
    if lit() && !image_mode() && marched() {
        let r = reflection(in, ng);
        if r.w > 0.0 {
            non_diffuse_weight = 0.0;
            reflected = pixel_emission + r.rgb;
        }
    }
    // Pack 4 leaves the emission to the runtime: where no marched reflection carries it.
    if lit() && !image_mode() && object_has(OBJECT_RUNTIME_EMISSION) && non_diffuse_weight != 0.0
        && !see_through() {
        reflected += pixel_emission;
    }
    var c: vec4<f32>;
    // What is added to the reconstructed radiance: reflection, emission, the sun and the
    // lamps.
    var added = reflected;
    if see_through() {
        // Transmissive glass: its reflection alone (none where no lookup answers; the baked
        // radiance holds what it lets through), what lies behind blended in by the
        // premultiplied alpha below.
        c = vec4<f32>(reflected, 1.0);
    } else {
        c = radiance(in, ng);
        c = vec4<f32>(c.rgb + reflected, c.a);
    }
    if lit() && view_has(VIEW_SUN) && !image_mode() {
        let sun = sun_light(in, ng);
        added += sun;
        c = vec4<f32>(c.rgb + sun, c.a);
    }
    if lit() && view_has(VIEW_LAMPS) && !image_mode() {
        let lamps = lamps_diffuse(in, ng);
        added += lamps;
        c = vec4<f32>(c.rgb + lamps, c.a);
    }
    write_fill_entry(in.position, added);
    // Glazing (fill.w < 1) is blended over what lies behind it with its coverage in
    // geometry-assisted mode; the image-mode frame already holds what is behind.
    var alpha = select(c.a, params.coverage, glazing() && !image_mode());
    if see_through() {
        alpha = 1.0 - params.transmittance;
    }
    flush_counters(in.position.xy);
    var out = vec4<f32>(min(c.rgb * view.exposure, vec3<f32>(65504.0)), alpha);
#ifdef TONEMAP_IN_SHADER
    out = tone_mapping(out, view.color_grading);
#endif
    return out;
}
