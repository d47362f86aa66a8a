// The environment where no geometry is: a full-screen triangle at depth 0 (reverse-Z far).
// With a pack environment it shows that environment for each pixel's own viewing direction
// (plenoptic_recon's background module): a uniform colour, the Hosek–Wilkie sky from
// coefficients the CPU computes per view at the camera's time, or the equirectangular image
// (bilinear, as plenoptic_sky's EquirectImage::bilinear). Without one, the heaviest key's
// radiance in the pixel's direction (plenoptic_recon's lookup for pixels without an object),
// or in image mode the image-mode frame. Output is times the camera's exposure.

#import bevy_pbr::mesh_view_bindings::view
#ifdef TONEMAP_IN_SHADER
#import bevy_core_pipeline::tonemapping::tone_mapping
#endif

#import plenoptic::cube::{rgb9e5_decode, cube_texel}
#import plenoptic::environment::{Environment, environment}

@group(#{MATERIAL_BIND_GROUP}) @binding(0) var cubes: texture_2d_array<u32>;
// x: first layer, y: face size, z: 1 if a key is shown, w: 1 to show the image-mode frame.
@group(#{MATERIAL_BIND_GROUP}) @binding(1) var<uniform> key: vec4<f32>;
// The image-mode frame (image.wgsl).
@group(#{MATERIAL_BIND_GROUP}) @binding(2) var image_frame: texture_2d<f32>;
@group(#{MATERIAL_BIND_GROUP}) @binding(3) var<uniform> env: Environment;
// The equirectangular environment image (1 × 1 when there is none), linear RGB.
@group(#{MATERIAL_BIND_GROUP}) @binding(4) var env_image: texture_2d<f32>;

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

fn background(position: vec2<f32>) -> vec3<f32> {
    let uv = (position - view.viewport.xy) / view.viewport.zw;
    if env.kind.x > 0.5 {
        // The pixel's viewing ray, from two points on it.
        let ndc = vec2<f32>(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0);
        let a4 = view.world_from_clip * vec4<f32>(ndc, 1.0, 1.0);
        let b4 = view.world_from_clip * vec4<f32>(ndc, 0.5, 1.0);
        return environment(env, env_image, normalize(b4.xyz / b4.w - a4.xyz / a4.w));
    }
    if key.w == 1.0 {
        let size = textureDimensions(image_frame);
        let p = min(vec2<u32>(uv * vec2<f32>(size)), size - vec2<u32>(1u));
        return textureLoad(image_frame, p, 0).rgb;
    }
    if key.z == 0.0 {
        return vec3<f32>(0.0);
    }
    let ndc = vec2<f32>(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0);
    let a4 = view.world_from_clip * vec4<f32>(ndc, 1.0, 1.0);
    let b4 = view.world_from_clip * vec4<f32>(ndc, 0.5, 1.0);
    let dir = b4.xyz / b4.w - a4.xyz / a4.w;
    let n = u32(key.y);
    let t = cube_texel(dir, n);
    let texel = textureLoad(cubes, vec2<u32>(t.x, t.y), u32(key.x) + t.z, 0);
    return rgb9e5_decode(texel.x);
}

// Times the camera's exposure, as Bevy's own lights, inside f16's range; tonemapped here for
// cameras without an HDR target (geometry.wgsl).
@fragment
fn fragment(in: Out) -> @location(0) vec4<f32> {
    let c = background(in.position.xy) * view.exposure;
    var out = vec4<f32>(min(c, vec3<f32>(65504.0)), 1.0);
#ifdef TONEMAP_IN_SHADER
    out = tone_mapping(out, view.color_grading);
#endif
    return out;
}
