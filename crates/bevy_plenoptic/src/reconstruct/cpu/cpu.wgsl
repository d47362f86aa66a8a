// The CPU backend's frame, shown through the proxy meshes: each fragment takes the texel of
// its pixel from the frame plenoptic_recon reconstructed (linear radiance, unlit).

#import bevy_pbr::forward_io::VertexOutput
#import bevy_pbr::mesh_view_bindings::view
#ifdef TONEMAP_IN_SHADER
#import bevy_core_pipeline::tonemapping::tone_mapping
#endif

@group(#{MATERIAL_BIND_GROUP}) @binding(0) var frame: texture_2d<f32>;

@fragment
fn fragment(in: VertexOutput) -> @location(0) vec4<f32> {
    let size = textureDimensions(frame);
    let uv = (in.position.xy - view.viewport.xy) / view.viewport.zw;
    let p = min(vec2<u32>(uv * vec2<f32>(size)), size - vec2<u32>(1u));
    // Times the camera's exposure, as Bevy's own lights, tonemapped in the shader for
    // cameras without an HDR target (see geometry.wgsl).
    let c = textureLoad(frame, p, 0).rgb * view.exposure;
    var out = vec4<f32>(min(c, vec3<f32>(65504.0)), 1.0);
#ifdef TONEMAP_IN_SHADER
    out = tone_mapping(out, view.color_grading);
#endif
    return out;
}
