//! Textures and how materials refer to them: the decoded image ([`Texture`]), the glTF
//! sampler's wrap modes ([`WrapMode`]), `KHR_texture_transform` ([`UvTransform`]) and the
//! reference that carries both ([`TextureRef`]), plus the alpha mode of a material
//! ([`AlphaMode`]).
//!
//! The tracer's bilinear lookup lives in `plenoptic_trace`; the coordinate arithmetic that the
//! file format defines (wrapping a texel index, transforming a UV) lives here so that it is
//! tested against the specification once.

use glam::{Vec2, Vec4};

/// A texture, decoded to linear floating point RGBA.
#[derive(Debug, Clone, PartialEq)]
pub struct Texture {
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// Texels row by row from the top, linear (sRGB textures are linearised on import).
    pub texels: Vec<Vec4>,
}

/// How texel coordinates outside the texture map back into it (glTF sampler `wrapS`/`wrapT`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash)]
pub enum WrapMode {
    /// The texture tiles (glTF's default, 10497).
    #[default]
    Repeat,
    /// Coordinates clamp to the edge texels (33071).
    ClampToEdge,
    /// The texture tiles, every other tile mirrored (33648).
    MirroredRepeat,
}

impl WrapMode {
    /// The texel index in `0..n` that integer texel coordinate `i` reads (`n > 0`).
    pub fn wrap(self, i: i64, n: i64) -> usize {
        debug_assert!(n > 0);
        let k = match self {
            Self::Repeat => i.rem_euclid(n),
            Self::ClampToEdge => i.clamp(0, n - 1),
            Self::MirroredRepeat => {
                let m = i.rem_euclid(2 * n);
                if m < n { m } else { 2 * n - 1 - m }
            }
        };
        k as usize
    }
}

/// `KHR_texture_transform`: UVs are scaled, then rotated, then offset:
/// `uv' = offset + R(rotation) · (scale ∘ uv)` with
/// `R(r) = [[cos r, sin r], [−sin r, cos r]]` (rows), which rotates the UVs counter-clockwise
/// in the image's y-down frame, as the specification's example requires: offset (0, 1),
/// rotation π/2 and scale ½ map the unit square onto the lower-left quadrant of the image.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UvTransform {
    /// Offset of the UV origin, in units of the texture's size.
    pub offset: Vec2,
    /// Rotation in radians.
    pub rotation: f32,
    /// Scale of the UV components.
    pub scale: Vec2,
}

impl Default for UvTransform {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl UvTransform {
    /// The transform that leaves UVs unchanged.
    pub const IDENTITY: Self = Self {
        offset: Vec2::ZERO,
        rotation: 0.0,
        scale: Vec2::ONE,
    };

    /// Whether this is (exactly) the identity.
    pub fn is_identity(&self) -> bool {
        *self == Self::IDENTITY
    }

    /// The transformed coordinates of `uv`.
    pub fn apply(&self, uv: Vec2) -> Vec2 {
        if self.is_identity() {
            return uv;
        }
        let s = uv * self.scale;
        let (sin, cos) = self.rotation.sin_cos();
        self.offset + Vec2::new(cos * s.x + sin * s.y, -sin * s.x + cos * s.y)
    }
}

/// A reference from a material to a texture, with the sampling state glTF attaches to it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TextureRef {
    /// Index into [`Scene::textures`](crate::Scene::textures).
    pub texture: usize,
    /// Wrap mode along u (glTF `wrapS`).
    pub wrap_s: WrapMode,
    /// Wrap mode along v (glTF `wrapT`).
    pub wrap_t: WrapMode,
    /// `KHR_texture_transform` of this reference (identity when absent).
    pub transform: UvTransform,
}

impl TextureRef {
    /// A reference to texture `texture` with REPEAT wrapping and no transform.
    pub fn new(texture: usize) -> Self {
        Self {
            texture,
            wrap_s: WrapMode::Repeat,
            wrap_t: WrapMode::Repeat,
            transform: UvTransform::IDENTITY,
        }
    }
}

/// How a material's alpha (base colour factor × texture × `COLOR_0`) is used (glTF
/// `alphaMode`).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum AlphaMode {
    /// Alpha is ignored: the surface is opaque.
    #[default]
    Opaque,
    /// The surface exists where alpha ≥ `cutoff` and rays pass through it elsewhere.
    Mask {
        /// glTF `alphaCutoff` (0.5 when absent).
        cutoff: f32,
    },
    /// Alpha is coverage: a ray meets the surface with probability alpha and passes through
    /// otherwise, so glass exported this way lets 1 − alpha of the light through.
    Blend,
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f32::consts::FRAC_PI_2;

    #[test]
    fn wrap_modes_at_and_beyond_the_edges() {
        let n = 4;
        for (i, repeat, clamp, mirror) in [
            (0, 0, 0, 0),
            (3, 3, 3, 3),
            (4, 0, 3, 3),
            (5, 1, 3, 2),
            (7, 3, 3, 0),
            (8, 0, 3, 0),
            (-1, 3, 0, 0),
            (-2, 2, 0, 1),
            (-5, 3, 0, 3),
            (-8, 0, 0, 0),
            (-9, 3, 0, 0),
        ] {
            assert_eq!(WrapMode::Repeat.wrap(i, n), repeat, "repeat {i}");
            assert_eq!(WrapMode::ClampToEdge.wrap(i, n), clamp, "clamp {i}");
            assert_eq!(WrapMode::MirroredRepeat.wrap(i, n), mirror, "mirror {i}");
        }
    }

    fn close(a: Vec2, b: Vec2) -> bool {
        a.abs_diff_eq(b, 1e-6)
    }

    #[test]
    fn texture_transform_matches_the_specification_example() {
        // KHR_texture_transform's README: offset (0, 1), rotation π/2, scale ½ "utilizes only
        // the lower left quadrant of the source image, rotated clockwise 90°".
        let t = UvTransform {
            offset: Vec2::new(0.0, 1.0),
            rotation: FRAC_PI_2,
            scale: Vec2::splat(0.5),
        };
        assert!(close(t.apply(Vec2::new(0.0, 0.0)), Vec2::new(0.0, 1.0)));
        assert!(close(t.apply(Vec2::new(1.0, 0.0)), Vec2::new(0.0, 0.5)));
        assert!(close(t.apply(Vec2::new(0.0, 1.0)), Vec2::new(0.5, 1.0)));
        assert!(close(t.apply(Vec2::new(1.0, 1.0)), Vec2::new(0.5, 0.5)));
        // "inverts the T axis": offset (0, 1), scale (1, −1).
        let flip = UvTransform {
            offset: Vec2::new(0.0, 1.0),
            rotation: 0.0,
            scale: Vec2::new(1.0, -1.0),
        };
        assert!(close(
            flip.apply(Vec2::new(0.25, 0.1)),
            Vec2::new(0.25, 0.9)
        ));
    }

    #[test]
    fn texture_transform_components() {
        let uv = Vec2::new(0.3, 0.7);
        let offset = UvTransform {
            offset: Vec2::new(0.5, -0.25),
            ..UvTransform::IDENTITY
        };
        assert!(close(offset.apply(uv), Vec2::new(0.8, 0.45)));
        let scale = UvTransform {
            scale: Vec2::new(2.0, 3.0),
            ..UvTransform::IDENTITY
        };
        assert!(close(scale.apply(uv), Vec2::new(0.6, 2.1)));
        // 30°: u' = cos·u + sin·v, v' = −sin·u + cos·v.
        let r = 30f32.to_radians();
        let rot = UvTransform {
            rotation: r,
            ..UvTransform::IDENTITY
        };
        let (s, c) = (0.5f32, 0.75f32.sqrt());
        assert!(close(
            rot.apply(uv),
            Vec2::new(c * 0.3 + s * 0.7, -s * 0.3 + c * 0.7)
        ));
        // Scale first, then rotate, then offset.
        let all = UvTransform {
            offset: Vec2::new(0.1, 0.2),
            rotation: FRAC_PI_2,
            scale: Vec2::new(2.0, 4.0),
        };
        // (0.6, 2.8) rotated by 90°: (2.8, −0.6); plus offset.
        assert!(close(all.apply(uv), Vec2::new(2.9, -0.4)));
        assert_eq!(UvTransform::IDENTITY.apply(uv), uv);
    }
}
