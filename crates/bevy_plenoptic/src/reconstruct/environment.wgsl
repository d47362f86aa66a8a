// The pack's environment (plenoptic_sky; plenoptic_recon's background module), shared by the
// background pass and the reflections of geometry.wgsl: a uniform colour, the Hosek–Wilkie
// sky from coefficients the CPU computes at the camera's time, or an equirectangular image.
#define_import_path plenoptic::environment

const PI: f32 = 3.14159265358979;
const TAU: f32 = 6.28318530717959;

struct Environment {
    // x: kind (0 none, 1 uniform, 2 sky, 3 image), y: unused, z, w: cos and sin of the
    // image's turn about +Y.
    kind: vec4<f32>,
    // Uniform colour (xyz).
    colour: vec4<f32>,
    // The sky's 27 coefficients, A–I of R, then G, then B, four per vector.
    sky: array<vec4<f32>, 7>,
    // Radiance scale per channel (xyz): the sky's, or the image's intensity.
    sky_radiance: vec4<f32>,
    // Unit direction towards the sun (xyz).
    sun: vec4<f32>,
    // The sky's radiance below the horizon, its ground (xyz; zero without one).
    ground: vec4<f32>,
}

fn sky_param(e: Environment, i: u32) -> f32 {
    return e.sky[i / 4u][i % 4u];
}

// Hosek–Wilkie's formula for channel `ch` (plenoptic_sky's sky.rs, eval_channel).
fn sky_channel(e: Environment, ch: u32, cos_theta: f32, gamma: f32, cos_gamma: f32) -> f32 {
    let o = 9u * ch;
    let p8 = sky_param(e, o + 8u);
    let cos_gamma2 = cos_gamma * cos_gamma;
    let exp_m = exp(sky_param(e, o + 4u) * gamma);
    let mie = (1.0 + cos_gamma2) / pow(1.0 + p8 * p8 - 2.0 * p8 * cos_gamma, 1.5);
    let lhs = 1.0 + sky_param(e, o) * exp(sky_param(e, o + 1u) / (cos_theta + 0.01));
    let rhs = sky_param(e, o + 2u) + sky_param(e, o + 3u) * exp_m + sky_param(e, o + 5u) * cos_gamma2
        + sky_param(e, o + 6u) * mie + sky_param(e, o + 7u) * sqrt(cos_theta);
    return e.sky_radiance[ch] * lhs * rhs;
}

fn sky(e: Environment, dir: vec3<f32>) -> vec3<f32> {
    if dir.y <= 0.0 {
        return e.ground.xyz;
    }
    let cos_theta = min(dir.y, 1.0);
    let cos_gamma = clamp(dot(dir, e.sun.xyz), -1.0, 1.0);
    let gamma = acos(cos_gamma);
    let c = vec3<f32>(
        sky_channel(e, 0u, cos_theta, gamma, cos_gamma),
        sky_channel(e, 1u, cos_theta, gamma, cos_gamma),
        sky_channel(e, 2u, cos_theta, gamma, cos_gamma),
    );
    return max(c, vec3<f32>(0.0));
}

fn image_texel(image: texture_2d<f32>, x: i32, y: i32) -> vec3<f32> {
    let size = vec2<i32>(textureDimensions(image));
    let xi = ((x % size.x) + size.x) % size.x;
    let yi = clamp(y, 0, size.y - 1);
    return textureLoad(image, vec2<i32>(xi, yi), 0).rgb;
}

// The image in world direction `d` (plenoptic_sky: turned about +Y, equirect_uv, bilinear).
fn equirect(e: Environment, image: texture_2d<f32>, d: vec3<f32>) -> vec3<f32> {
    let c = e.kind.z;
    let s = e.kind.w;
    let q = vec3<f32>(c * d.x - s * d.z, d.y, s * d.x + c * d.z);
    let u = fract(0.5 + atan2(q.x, -q.z) / TAU);
    let v = acos(clamp(q.y, -1.0, 1.0)) / PI;
    let size = vec2<f32>(textureDimensions(image));
    let x = u * size.x - 0.5;
    let y = v * size.y - 0.5;
    let x0 = floor(x);
    let y0 = floor(y);
    let f = vec2<f32>(x - x0, y - y0);
    let xi = i32(x0);
    let yi = i32(y0);
    let top = mix(image_texel(image, xi, yi), image_texel(image, xi + 1, yi), f.x);
    let bottom = mix(image_texel(image, xi, yi + 1), image_texel(image, xi + 1, yi + 1), f.x);
    return mix(top, bottom, f.y) * e.sky_radiance.xyz;
}

// The environment `e` (its image `image`, 1 × 1 when it has none) in world direction `dir`;
// black for kind 0 (no environment).
fn environment(e: Environment, image: texture_2d<f32>, dir: vec3<f32>) -> vec3<f32> {
    let kind = u32(e.kind.x + 0.5);
    if kind == 0u {
        return vec3<f32>(0.0);
    }
    if kind == 1u {
        return e.colour.rgb;
    }
    if kind == 2u {
        return sky(e, dir);
    }
    return equirect(e, image, dir);
}
