// The environment where no geometry is: a full-screen triangle at depth 0 (reverse-Z far),
// showing the heaviest key's radiance in each pixel's viewing direction (plenoptic_recon's
// lookup for pixels without an object).

#import bevy_pbr::mesh_view_bindings::view

#import plenoptic::cube::{rgb9e5_decode, cube_texel}

@group(#{MATERIAL_BIND_GROUP}) @binding(0) var cubes: texture_2d_array<u32>;
// x: first layer, y: face size, z: 1 if a key is shown, w: 1 to show the image-mode frame.
@group(#{MATERIAL_BIND_GROUP}) @binding(1) var<uniform> key: vec4<f32>;
// The image-mode frame (image.wgsl).
@group(#{MATERIAL_BIND_GROUP}) @binding(2) var image_frame: texture_2d<f32>;

struct Out {
    @builtin(position) position: vec4<f32>,
}

// The mesh's positions are the triangle's clip-space corners (x, y); z = 0 puts it at the far
// end of the reverse-Z depth range.
@vertex
fn vertex(@location(0) corner: vec3<f32>) -> Out {
    var out: Out;
    out.position = vec4<f32>(corner.xy, 0.0, 1.0);
    return out;
}

@fragment
fn fragment(in: Out) -> @location(0) vec4<f32> {
    if key.w == 1.0 {
        let size = textureDimensions(image_frame);
        let uv = (in.position.xy - view.viewport.xy) / view.viewport.zw;
        let p = min(vec2<u32>(uv * vec2<f32>(size)), size - vec2<u32>(1u));
        return vec4<f32>(textureLoad(image_frame, p, 0).rgb, 1.0);
    }
    if key.z == 0.0 {
        return vec4<f32>(0.0, 0.0, 0.0, 1.0);
    }
    // The pixel's viewing ray, from two points on it.
    let uv = (in.position.xy - view.viewport.xy) / view.viewport.zw;
    let ndc = vec2<f32>(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0);
    let a4 = view.world_from_clip * vec4<f32>(ndc, 1.0, 1.0);
    let b4 = view.world_from_clip * vec4<f32>(ndc, 0.5, 1.0);
    let dir = b4.xyz / b4.w - a4.xyz / a4.w;
    let n = u32(key.y);
    let t = cube_texel(dir, n);
    let texel = textureLoad(cubes, vec2<u32>(t.x, t.y), u32(key.x) + t.z, 0);
    return vec4<f32>(rgb9e5_decode(texel.x), 1.0);
}
