//! Texture lookups for the tracers: bilinear filtering with the glTF sampler's wrap modes,
//! after the reference's `KHR_texture_transform`, and `COLOR_0` interpolation.
//!
//! Every texture the tracers sample (base colour and its alpha, metallic-roughness, emissive,
//! normal) goes through [`sample_ref`], so wrap modes and transforms apply everywhere.

use glam::{Vec2, Vec4};
use plenoptic_scene::{Mesh, Scene, Texture, TextureRef, WrapMode};

/// Bilinear lookup with REPEAT wrapping (glTF's default), uv (0, 0) at the top-left corner of
/// the top-left texel.
pub fn sample_texture(tex: &Texture, uv: Vec2) -> Vec4 {
    sample_texture_wrapped(tex, uv, WrapMode::Repeat, WrapMode::Repeat)
}

/// Bilinear lookup with the given wrap modes along u and v: texel centres sit at
/// ((i + ½)/width, (j + ½)/height), and the four texels around uv are wrapped independently,
/// so CLAMP_TO_EDGE holds the edge texel beyond the border and MIRRORED_REPEAT reflects.
/// A texture without texels reads as white.
pub fn sample_texture_wrapped(tex: &Texture, uv: Vec2, wrap_s: WrapMode, wrap_t: WrapMode) -> Vec4 {
    if tex.width == 0 || tex.height == 0 || tex.texels.len() < (tex.width * tex.height) as usize {
        return Vec4::ONE;
    }
    if !uv.is_finite() {
        return Vec4::ONE;
    }
    let (w, h) = (i64::from(tex.width), i64::from(tex.height));
    // Far outside the texture f32 → i64 saturates; the clamp keeps the wrap arithmetic
    // (2·n, i + 1) far from overflow.
    let x = uv.x * w as f32 - 0.5;
    let y = uv.y * h as f32 - 0.5;
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let (x0, y0) = (
        (x0 as i64).clamp(-(1 << 40), 1 << 40),
        (y0 as i64).clamp(-(1 << 40), 1 << 40),
    );
    let at = |xi: i64, yi: i64| {
        let xi = wrap_s.wrap(xi, w);
        let yi = wrap_t.wrap(yi, h);
        tex.texels[yi * tex.width as usize + xi]
    };
    let top = at(x0, y0).lerp(at(x0 + 1, y0), fx);
    let bottom = at(x0, y0 + 1).lerp(at(x0 + 1, y0 + 1), fx);
    top.lerp(bottom, fy)
}

/// The texture of `r` at mesh coordinates `uv`: transformed by the reference's
/// `KHR_texture_transform`, wrapped by its sampler. White when the index is out of range.
pub fn sample_ref(scene: &Scene, r: &TextureRef, uv: Vec2) -> Vec4 {
    match scene.textures.get(r.texture) {
        Some(t) => sample_texture_wrapped(t, r.transform.apply(uv), r.wrap_s, r.wrap_t),
        None => Vec4::ONE,
    }
}

/// The texture of an optional reference, white when there is none.
pub fn sample_opt(scene: &Scene, r: Option<&TextureRef>, uv: Vec2) -> Vec4 {
    r.map_or(Vec4::ONE, |r| sample_ref(scene, r, uv))
}

/// Texture coordinates of `mesh` at barycentrics (b1, b2) of triangle `triangle` (zero without
/// UVs).
pub fn mesh_uv(mesh: &Mesh, triangle: u32, bary: Vec2) -> Vec2 {
    if mesh.uvs.len() != mesh.positions.len() {
        return Vec2::ZERO;
    }
    let Some(t) = mesh.triangles.get(triangle as usize) else {
        return Vec2::ZERO;
    };
    let [i0, i1, i2] = t.map(|i| i as usize);
    mesh.uvs[i0] * (1.0 - bary.x - bary.y) + mesh.uvs[i1] * bary.x + mesh.uvs[i2] * bary.y
}

/// The `COLOR_0` of `mesh` at barycentrics (b1, b2) of triangle `triangle` (white without
/// vertex colours).
pub fn mesh_color(mesh: &Mesh, triangle: u32, bary: Vec2) -> Vec4 {
    if mesh.colors.len() != mesh.positions.len() {
        return Vec4::ONE;
    }
    let Some(t) = mesh.triangles.get(triangle as usize) else {
        return Vec4::ONE;
    };
    let [i0, i1, i2] = t.map(|i| i as usize);
    mesh.colors[i0] * (1.0 - bary.x - bary.y) + mesh.colors[i1] * bary.x + mesh.colors[i2] * bary.y
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec4;

    /// A 2×1 texture: texel 0 is black, texel 1 white (red channel carries the value).
    fn two() -> Texture {
        Texture {
            width: 2,
            height: 1,
            texels: vec![Vec4::new(0.0, 0.0, 0.0, 1.0), Vec4::new(1.0, 0.0, 0.0, 1.0)],
        }
    }

    fn red(uv_x: f32, wrap: WrapMode) -> f32 {
        sample_texture_wrapped(&two(), Vec2::new(uv_x, 0.5), wrap, WrapMode::ClampToEdge).x
    }

    fn close(a: f32, b: f32) -> bool {
        (a - b).abs() < 1e-5
    }

    #[test]
    fn repeat_wraps_around() {
        let w = WrapMode::Repeat;
        // Texel centres at u = 0.25 and 0.75.
        assert!(close(red(0.25, w), 0.0));
        assert!(close(red(0.75, w), 1.0));
        // At u = 1 (and 0) the filter blends the last texel with the first.
        assert!(close(red(1.0, w), 0.5));
        assert!(close(red(0.0, w), 0.5));
        assert!(close(red(1.25, w), 0.0));
        assert!(close(red(-0.25, w), 1.0));
        assert!(close(red(7.75, w), 1.0));
    }

    #[test]
    fn clamp_holds_the_edge_texels() {
        let w = WrapMode::ClampToEdge;
        assert!(close(red(0.0, w), 0.0));
        assert!(close(red(1.0, w), 1.0));
        assert!(close(red(1.3, w), 1.0));
        assert!(close(red(25.0, w), 1.0));
        assert!(close(red(-0.5, w), 0.0));
        assert!(close(red(-1e9, w), 0.0));
        assert!(close(red(0.5, w), 0.5));
    }

    #[test]
    fn mirror_reflects_at_each_edge() {
        let w = WrapMode::MirroredRepeat;
        assert!(close(red(1.0, w), 1.0)); // texel 2 mirrors to texel 1
        assert!(close(red(0.0, w), 0.0)); // texel −1 mirrors to texel 0
        assert!(close(red(1.25, w), 1.0)); // = 0.75
        assert!(close(red(1.75, w), 0.0)); // = 0.25
        assert!(close(red(-0.25, w), 0.0)); // = 0.25
        assert!(close(red(-0.75, w), 1.0)); // = 0.75
        assert!(close(red(2.25, w), 0.0)); // period 2
        assert!(close(red(1.5, w), 0.5));
    }

    #[test]
    fn transform_and_wrap_apply_together() {
        let scene = Scene {
            textures: vec![two()],
            ..Scene::default()
        };
        let mut r = TextureRef::new(0);
        r.transform.offset = Vec2::new(0.5, 0.0);
        // u 0.25 + 0.5 = 0.75: the white texel.
        assert!(close(sample_ref(&scene, &r, Vec2::new(0.25, 0.5)).x, 1.0));
        r.transform.scale = Vec2::new(2.0, 1.0);
        r.wrap_s = WrapMode::ClampToEdge;
        // 0.6·2 + 0.5 = 1.7: beyond the edge, clamped to white.
        assert!(close(sample_ref(&scene, &r, Vec2::new(0.6, 0.5)).x, 1.0));
        r.wrap_s = WrapMode::MirroredRepeat;
        // 0.625·2 + 0.5 = 1.75 mirrors to 0.25: black.
        assert!(close(sample_ref(&scene, &r, Vec2::new(0.625, 0.5)).x, 0.0));
    }
}
