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

struct Environment {
    // x: kind (0 none, 1 uniform, 2 sky, 3 image), y: image intensity, z, w: cos and sin of
    // the image's turn about +Y.
    kind: vec4<f32>,
    // Uniform colour (xyz).
    colour: vec4<f32>,
    // The sky's 27 coefficients, A–I of R, then G, then B, four per vector.
    sky: array<vec4<f32>, 7>,
    // Radiance scale per channel (xyz).
    sky_radiance: vec4<f32>,
    // Unit direction towards the sun (xyz).
    sun: vec4<f32>,
    // The sky's radiance below the horizon, its ground (xyz; zero without one).
    ground: vec4<f32>,
}

@group(#{MATERIAL_BIND_GROUP}) @binding(0) var cubes: texture_2d_array<u32>;
// x: first layer, y: face size, z: 1 if a key is shown, w: 1 to show the image-mode frame.
@group(#{MATERIAL_BIND_GROUP}) @binding(1) var<uniform> key: vec4<f32>;
// The image-mode frame (image.wgsl).
@group(#{MATERIAL_BIND_GROUP}) @binding(2) var image_frame: texture_2d<f32>;
@group(#{MATERIAL_BIND_GROUP}) @binding(3) var<uniform> env: Environment;
// The equirectangular environment image (1 × 1 when there is none), linear RGB.
@group(#{MATERIAL_BIND_GROUP}) @binding(4) var env_image: texture_2d<f32>;

const PI: f32 = 3.14159265358979;
const TAU: f32 = 6.28318530717959;

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

fn sky_param(i: u32) -> f32 {
    return env.sky[i / 4u][i % 4u];
}

// Hosek–Wilkie's formula for channel `ch` (plenoptic_sky's sky.rs, eval_channel).
fn sky_channel(ch: u32, cos_theta: f32, gamma: f32, cos_gamma: f32) -> f32 {
    let o = 9u * ch;
    let p8 = sky_param(o + 8u);
    let cos_gamma2 = cos_gamma * cos_gamma;
    let exp_m = exp(sky_param(o + 4u) * gamma);
    let mie = (1.0 + cos_gamma2) / pow(1.0 + p8 * p8 - 2.0 * p8 * cos_gamma, 1.5);
    let lhs = 1.0 + sky_param(o) * exp(sky_param(o + 1u) / (cos_theta + 0.01));
    let rhs = sky_param(o + 2u) + sky_param(o + 3u) * exp_m + sky_param(o + 5u) * cos_gamma2
        + sky_param(o + 6u) * mie + sky_param(o + 7u) * sqrt(cos_theta);
    return env.sky_radiance[ch] * lhs * rhs;
}

fn sky(dir: vec3<f32>) -> vec3<f32> {
    if dir.y <= 0.0 {
        return env.ground.xyz;
    }
    let cos_theta = min(dir.y, 1.0);
    let cos_gamma = clamp(dot(dir, env.sun.xyz), -1.0, 1.0);
    let gamma = acos(cos_gamma);
    let c = vec3<f32>(
        sky_channel(0u, cos_theta, gamma, cos_gamma),
        sky_channel(1u, cos_theta, gamma, cos_gamma),
        sky_channel(2u, cos_theta, gamma, cos_gamma),
    );
    return max(c, vec3<f32>(0.0));
}

fn image_texel(x: i32, y: i32) -> vec3<f32> {
    let size = vec2<i32>(textureDimensions(env_image));
    let xi = ((x % size.x) + size.x) % size.x;
    let yi = clamp(y, 0, size.y - 1);
    return textureLoad(env_image, vec2<i32>(xi, yi), 0).rgb;
}

// The image in world direction `d` (plenoptic_sky: turned about +Y, equirect_uv, bilinear).
fn image(d: vec3<f32>) -> vec3<f32> {
    let c = env.kind.z;
    let s = env.kind.w;
    let q = vec3<f32>(c * d.x - s * d.z, d.y, s * d.x + c * d.z);
    let u = fract(0.5 + atan2(q.x, -q.z) / TAU);
    let v = acos(clamp(q.y, -1.0, 1.0)) / PI;
    let size = vec2<f32>(textureDimensions(env_image));
    let x = u * size.x - 0.5;
    let y = v * size.y - 0.5;
    let x0 = floor(x);
    let y0 = floor(y);
    let f = vec2<f32>(x - x0, y - y0);
    let xi = i32(x0);
    let yi = i32(y0);
    let top = mix(image_texel(xi, yi), image_texel(xi + 1, yi), f.x);
    let bottom = mix(image_texel(xi, yi + 1), image_texel(xi + 1, yi + 1), f.x);
    return mix(top, bottom, f.y) * env.kind.y;
}

fn environment(dir: vec3<f32>) -> vec3<f32> {
    let kind = u32(env.kind.x + 0.5);
    if kind == 1u {
        return env.colour.rgb;
    }
    if kind == 2u {
        return sky(dir);
    }
    return image(dir);
}

fn background(position: vec2<f32>) -> vec3<f32> {
    let uv = (position - view.viewport.xy) / view.viewport.zw;
    if env.kind.x > 0.5 {
        // The pixel's viewing ray, from two points on it.
        let ndc = vec2<f32>(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0);
        let a4 = view.world_from_clip * vec4<f32>(ndc, 1.0, 1.0);
        let b4 = view.world_from_clip * vec4<f32>(ndc, 0.5, 1.0);
        return environment(normalize(b4.xyz / b4.w - a4.xyz / a4.w));
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
