//! The pack's materials at screen resolution (docs/architecture.md, "Pack v2"; design.md:
//! "albedo(uv, mip chosen by screen-space footprint) × lighting"): per object its glTF
//! material and proxy UVs, and the diffuse albedo at any UV, sampled from the material's
//! mipmapped textures with trilinear filtering.
//!
//! The albedo is the one the bake divided the lighting by ([`plenoptic_pack::RangeImage`]):
//! `(1 − metallic)(1 − transmission) · base colour`, with the base-colour texture in sRGB
//! decoded to linear and metallic multiplied by the metallic-roughness texture's blue channel.
//! UVs pass through the binding's `KHR_texture_transform` and wrap modes first.
//!
//! Normal maps bend the shading normal as the path tracer bends it (tangent frame from the
//! proxy's interpolated tangent, Gram–Schmidt against the interpolated normal, the
//! bitangent's sign from the triangle's first vertex; `normal_scale` on x and y): the runtime
//! sun and reflections use the bent normal at screen resolution, while the stored lighting
//! holds its average over a cube texel (the bake's paths start on the bent normal).
//!
//! Textures are decoded from the pack on first use and kept (their size is bounded by the
//! pack's `MAX_TEXTURE_SIDE`); one that cannot be read is reported once and treated as white.

use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

use crate::brdf::SurfaceMaterial;
use glam::{Vec2, Vec3, Vec4};
use plenoptic_pack::{
    ColourSpace, MaterialEntry, PackReader, TextureBinding, TextureImage, UvTransform, WrapMode,
};

/// One object's material and the UVs and tangents of its proxy vertices (empty: none).
pub(crate) struct ObjectMaterial {
    pub material: MaterialEntry,
    pub uvs: Vec<Vec2>,
    /// Unit xyz, the bitangent's sign in w (glTF's TANGENT).
    pub tangents: Vec<Vec4>,
}

/// The materials of a pack's objects, with their textures decoded on first use.
pub(crate) struct Materials {
    objects: HashMap<u32, ObjectMaterial>,
    textures: Vec<OnceLock<Option<Arc<TextureImage>>>>,
    /// Messages about textures or attributes that could not be read.
    pub missing: Mutex<Vec<String>>,
}

/// sRGB-encoded byte → linear value.
fn srgb_table() -> &'static [f32; 256] {
    static TABLE: OnceLock<[f32; 256]> = OnceLock::new();
    TABLE.get_or_init(|| {
        std::array::from_fn(|i| plenoptic_pack::texture::srgb_to_linear(i as f32 / 255.0))
    })
}

impl Materials {
    /// Reads the material table, each object's material and its proxy's UVs and tangents (whose vertex
    /// count the pack reader checked against the proxy mesh).
    pub fn load(pack: &PackReader) -> Self {
        let mut objects = HashMap::new();
        let mut missing = Vec::new();
        for o in &pack.manifest().objects {
            let Some(material) = pack.object_material(o.id) else {
                continue;
            };
            let (uvs, tangents) = match pack.proxy_attributes(o.id) {
                Ok(a) => a.map(|a| (a.uvs, a.tangents)).unwrap_or_default(),
                Err(e) => {
                    missing.push(format!("UVs of object {}: {e}", o.id));
                    Default::default()
                }
            };
            objects.insert(
                o.id,
                ObjectMaterial {
                    material: material.clone(),
                    uvs,
                    tangents,
                },
            );
        }
        Materials {
            objects,
            textures: (0..pack.textures().len())
                .map(|_| OnceLock::new())
                .collect(),
            missing: Mutex::new(missing),
        }
    }

    /// The material of pack object `id`, if it has one.
    pub fn object(&self, id: u32) -> Option<&ObjectMaterial> {
        self.objects.get(&id)
    }

    /// The messages about what could not be read so far.
    pub fn messages(&self) -> Vec<String> {
        self.missing.lock().map(|m| m.clone()).unwrap_or_default()
    }

    /// Whether no object has a material.
    pub fn is_empty(&self) -> bool {
        self.objects.is_empty()
    }

    fn texture(&self, pack: &PackReader, index: u32) -> Option<&TextureImage> {
        let slot = self.textures.get(index as usize)?;
        slot.get_or_init(|| match pack.texture(index) {
            Ok(t) => Some(Arc::new(t)),
            Err(e) => {
                if let Ok(mut m) = self.missing.lock() {
                    m.push(format!("material texture {index}: {e}"));
                }
                None
            }
        })
        .as_deref()
    }

    /// The material `m` at `uv` (base colour, metalness and roughness textured), with the
    /// textures' mip chosen from `footprint`: the pixel's size in UV units (before the
    /// binding's transform). Its [`SurfaceMaterial::albedo`] is the diffuse albedo.
    pub fn surface(
        &self,
        pack: &PackReader,
        m: &MaterialEntry,
        uv: Vec2,
        footprint: f32,
    ) -> SurfaceMaterial {
        let mut base = m.base_colour.truncate();
        if let Some(b) = m.base_colour_texture
            && let Some(t) = self.texture(pack, b.texture)
        {
            base *= sample(t, b, uv, footprint).truncate();
        }
        let (mut metallic, mut roughness) = (m.metallic, m.roughness);
        if let Some(b) = m.metallic_roughness_texture
            && let Some(t) = self.texture(pack, b.texture)
        {
            let mr = sample(t, b, uv, footprint);
            metallic *= mr.z;
            roughness *= mr.y;
        }
        SurfaceMaterial {
            base,
            metallic: metallic.clamp(0.0, 1.0),
            roughness: roughness.clamp(0.0, 1.0),
            transmission: m.transmission.clamp(0.0, 1.0),
            ior: if m.ior > 0.0 { m.ior } else { 1.5 },
            thin_walled: m.thickness <= 0.0,
        }
    }

    /// The emitted radiance of material `m` at `uv`: the emissive factor × its sRGB texture,
    /// with the mip chosen from `footprint` as in [`Materials::surface`].
    pub fn emission(&self, pack: &PackReader, m: &MaterialEntry, uv: Vec2, footprint: f32) -> Vec3 {
        let mut e = m.emissive;
        if e != Vec3::ZERO
            && let Some(b) = m.emissive_texture
            && let Some(t) = self.texture(pack, b.texture)
        {
            e *= sample(t, b, uv, footprint).truncate();
        }
        e
    }

    /// The tangent-space normal of material `m`'s normal map at `uv` (x and y scaled by its
    /// `normal_scale`, not normalised), with the mip chosen from `footprint` as in
    /// [`Materials::surface`]; `None` when it has no normal map or it cannot be read.
    pub fn normal(
        &self,
        pack: &PackReader,
        m: &MaterialEntry,
        uv: Vec2,
        footprint: f32,
    ) -> Option<Vec3> {
        let b = m.normal_texture?;
        let t = self.texture(pack, b.texture)?;
        let c = sample(t, b, uv, footprint).truncate() * 2.0 - Vec3::ONE;
        Some(Vec3::new(c.x * m.normal_scale, c.y * m.normal_scale, c.z))
    }
}

/// Shading normal `ns` bent by tangent-space normal `local` in the frame of `tangent` (world,
/// not necessarily unit or orthogonal to `ns`) with bitangent sign `sign`, as the path tracer
/// bends it; `ns` itself where the frame degenerates.
pub(crate) fn bend_normal(ns: Vec3, tangent: Vec3, sign: f32, local: Vec3) -> Vec3 {
    let t = (tangent - ns * ns.dot(tangent)).normalize_or_zero();
    if t == Vec3::ZERO {
        return ns;
    }
    let b = ns.cross(t) * if sign < 0.0 { -1.0 } else { 1.0 };
    (t * local.x + b * local.y + ns * local.z).normalize_or(ns)
}

/// `KHR_texture_transform` applied to `uv`.
#[inline]
fn transform(t: &UvTransform, uv: Vec2) -> Vec2 {
    let s = uv * t.scale;
    if t.rotation == 0.0 {
        return t.offset + s;
    }
    let (sin, cos) = t.rotation.sin_cos();
    t.offset + Vec2::new(cos * s.x + sin * s.y, -sin * s.x + cos * s.y)
}

/// Wraps texel coordinate `i` of a side of `n` texels.
#[inline]
fn wrap(i: i64, n: i64, mode: WrapMode) -> usize {
    let n = n.max(1);
    if (0..n).contains(&i) {
        return i as usize;
    }
    (match mode {
        // One period off (the texel beside an edge of a reduced coordinate): no division.
        WrapMode::Repeat if (-n..0).contains(&i) => i + n,
        WrapMode::Repeat if (n..2 * n).contains(&i) => i - n,
        WrapMode::Repeat => i.rem_euclid(n),
        WrapMode::ClampToEdge => i.clamp(0, n - 1),
        WrapMode::MirroredRepeat => {
            let p = i.rem_euclid(2 * n);
            if p < n { p } else { 2 * n - 1 - p }
        }
    }) as usize
}

/// Trilinear sample of `texture` through binding `b` at `uv`, linear RGBA. `footprint` is
/// the pixel's size in UV units; the level is `log₂(footprint · size)` (the transform's scale
/// included).
pub(crate) fn sample(texture: &TextureImage, b: TextureBinding, uv: Vec2, footprint: f32) -> Vec4 {
    let Some(top) = texture.levels.first() else {
        return Vec4::ONE;
    };
    let (uv, scale) = match &b.transform {
        Some(t) => (transform(t, uv), t.scale.abs().max_element()),
        None => (uv, 1.0),
    };
    let texels = footprint * scale * top.width.max(top.height) as f32;
    let lod = if texels > 1.0 { log2(texels) } else { 0.0 };
    let last = texture.levels.len() - 1;
    let l0 = (floor(lod) as usize).min(last);
    let l1 = (l0 + 1).min(last);
    let f = (lod - l0 as f32).clamp(0.0, 1.0);
    let a = bilinear(texture, l0, b, uv);
    // Below one 8-bit step of the blend the second level cannot change the result.
    if l1 == l0 || f < 1.0 / 512.0 {
        return a;
    }
    a.lerp(bilinear(texture, l1, b, uv), f)
}

/// `x.log2()` within 2·10⁻⁵ for finite x ≥ 1 (∞ stays ∞): the exponent, and the mantissa
/// m ∈ [1, 2) through log₂ m = (2/ln 2)·atanh((m − 1)/(m + 1)) to its t⁷ term. A level of
/// detail needs far less; libm's `log2f` was 3 % of a materials frame.
#[inline]
fn log2(x: f32) -> f32 {
    if !x.is_finite() {
        return x;
    }
    let bits = x.to_bits();
    let exponent = ((bits >> 23) & 0xff) as i32 - 127;
    let m = f32::from_bits((bits & 0x007f_ffff) | 0x3f80_0000);
    let t = (m - 1.0) / (m + 1.0);
    let t2 = t * t;
    let series = t * (1.0 + t2 * (1.0 / 3.0 + t2 * (1.0 / 5.0 + t2 * (1.0 / 7.0))));
    exponent as f32 + series * (2.0 / std::f32::consts::LN_2)
}

/// `x.floor()` without a call into libm (the baseline x86-64 target has no rounding
/// instruction, and the texture lookups are hot): exact for every finite `x`.
#[inline]
fn floor(x: f32) -> f32 {
    // From 2²³ up every f32 is an integer.
    if x.abs() >= 8_388_608.0 {
        return x;
    }
    let t = x as i32 as f32;
    if t > x { t - 1.0 } else { t }
}

/// `uv` reduced to [0, 1) where the wrap mode repeats (the same texels, without an integer
/// division per texel to wrap them).
#[inline]
fn reduce(uv: f32, mode: WrapMode) -> f32 {
    if mode == WrapMode::Repeat && !(0.0..1.0).contains(&uv) {
        uv - floor(uv)
    } else {
        uv
    }
}

fn bilinear(texture: &TextureImage, level: usize, b: TextureBinding, uv: Vec2) -> Vec4 {
    let l = &texture.levels[level];
    let (w, h) = (l.width as i64, l.height as i64);
    let x = reduce(uv.x, b.wrap_s) * w as f32 - 0.5;
    let y = reduce(uv.y, b.wrap_t) * h as f32 - 0.5;
    if !(x.is_finite() && y.is_finite()) || l.texels.len() < 4 * (w * h) as usize {
        return Vec4::ONE;
    }
    let (x0, y0) = (floor(x), floor(y));
    let (fx, fy) = (x - x0, y - y0);
    let (x0, y0) = (x0 as i64, y0 as i64);
    // The two columns and rows of the footprint, wrapped once each.
    let (i0, i1) = (wrap(x0, w, b.wrap_s), wrap(x0 + 1, w, b.wrap_s));
    let (j0, j1) = (wrap(y0, h, b.wrap_t), wrap(y0 + 1, h, b.wrap_t));
    let srgb = texture.colour_space == ColourSpace::Srgb;
    let table = srgb_table();
    let row = w as usize;
    let texel = |i: usize, j: usize| {
        let k = 4 * (j * row + i);
        let p = &l.texels[k..k + 4];
        if srgb {
            Vec4::new(
                table[p[0] as usize],
                table[p[1] as usize],
                table[p[2] as usize],
                p[3] as f32 / 255.0,
            )
        } else {
            Vec4::new(p[0] as f32, p[1] as f32, p[2] as f32, p[3] as f32) / 255.0
        }
    };
    let top = texel(i0, j0).lerp(texel(i1, j0), fx);
    let bottom = texel(i0, j1).lerp(texel(i1, j1), fx);
    top.lerp(bottom, fy)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 4×4 linear texture: a black and white checker of 2×2 blocks.
    fn checker() -> TextureImage {
        let mut texels = Vec::new();
        for j in 0..4 {
            for i in 0..4 {
                let v = if (i / 2 + j / 2) % 2 == 0 { 255 } else { 0 };
                texels.extend_from_slice(&[v, v, v, 255]);
            }
        }
        TextureImage::with_mips(ColourSpace::Linear, 4, 4, texels).unwrap()
    }

    #[test]
    fn the_fast_log2_agrees_with_libm() {
        let mut x = 1.0f32;
        while x < 1e6 {
            assert!(
                (log2(x) - x.log2()).abs() < 2e-5,
                "{x}: {} {}",
                log2(x),
                x.log2()
            );
            x *= 1.0137;
        }
        assert_eq!(log2(f32::INFINITY), f32::INFINITY);
        assert_eq!(log2(1.0), 0.0);
        assert_eq!(log2(1024.0), 10.0);
    }

    fn binding() -> TextureBinding {
        TextureBinding {
            texture: 0,
            wrap_s: WrapMode::Repeat,
            wrap_t: WrapMode::Repeat,
            transform: None,
        }
    }

    #[test]
    fn texel_centres_are_exact_and_far_pixels_average_the_checker() {
        let t = checker();
        let at = |u: f32, v: f32, fp: f32| sample(&t, binding(), Vec2::new(u, v), fp).x;
        assert!((at(0.125, 0.125, 0.0) - 1.0).abs() < 1e-6);
        assert!(at(0.625, 0.125, 0.0).abs() < 1e-6);
        // A pixel covering the whole texture reads the 1×1 level: the mean (to 8 bits).
        assert!((at(0.3, 0.7, 1.0) - 0.5).abs() < 3e-3);
        // Repeat wraps; the transform's scale tiles.
        assert!((at(1.125, -0.875, 0.0) - 1.0).abs() < 1e-6);
        let scaled = TextureBinding {
            transform: Some(UvTransform {
                offset: Vec2::ZERO,
                rotation: 0.0,
                scale: Vec2::splat(2.0),
            }),
            ..binding()
        };
        assert!(sample(&t, scaled, Vec2::new(0.3125, 0.0625), 0.0).x.abs() < 1e-6);
    }

    #[test]
    fn normal_maps_bend_along_the_tangent_frame() {
        let up = Vec3::Y;
        // The flat normal map's (0.5, 0.5, 1) leaves the normal alone.
        assert!((bend_normal(up, Vec3::X, 1.0, Vec3::Z) - up).length() < 1e-6);
        // Tilted towards +tangent; a tangent not orthogonal to the normal is made so.
        let tilted = Vec3::new(0.6, 0.0, 0.8);
        let n = bend_normal(up, Vec3::new(2.0, 0.5, 0.0), 1.0, tilted);
        assert!((n - Vec3::new(0.6, 0.8, 0.0)).length() < 1e-5, "{n}");
        // The bitangent is n × t, flipped by a negative sign.
        let along_b = Vec3::new(0.0, 0.6, 0.8);
        assert!(
            (bend_normal(up, Vec3::X, 1.0, along_b) - Vec3::new(0.0, 0.8, -0.6)).length() < 1e-5
        );
        assert!(
            (bend_normal(up, Vec3::X, -1.0, along_b) - Vec3::new(0.0, 0.8, 0.6)).length() < 1e-5
        );
        // A tangent along the normal has no frame.
        assert_eq!(bend_normal(up, Vec3::Y, 1.0, tilted), up);
    }

    #[test]
    fn floor_is_libm_floor() {
        for x in [
            0.0f32,
            -0.0,
            0.5,
            -0.5,
            1.0,
            -1.0,
            2.999_999_8,
            -2.999_999_8,
            1e-30,
            -1e-30,
            8_388_607.5,
            -8_388_607.5,
            3e9,
            -3e9,
            123.0,
            -123.0,
        ] {
            assert_eq!(floor(x), x.floor(), "{x}");
        }
        // Repeating coordinates reduce to the same texel coordinates as wrapping them.
        for u in [-3.25f32, -1.0, -0.001, 0.0, 0.4, 1.0, 7.75] {
            let r = reduce(u, WrapMode::Repeat);
            assert!(
                (0.0..1.0).contains(&r) && (r - u - (r - u).round()).abs() < 1e-6,
                "{u}"
            );
            assert_eq!(reduce(u, WrapMode::ClampToEdge), u);
        }
    }

    #[test]
    fn wrap_modes() {
        assert_eq!(wrap(-1, 4, WrapMode::Repeat), 3);
        assert_eq!(wrap(-1, 4, WrapMode::ClampToEdge), 0);
        assert_eq!(wrap(5, 4, WrapMode::ClampToEdge), 3);
        assert_eq!(wrap(4, 4, WrapMode::MirroredRepeat), 3);
        assert_eq!(wrap(-1, 4, WrapMode::MirroredRepeat), 0);
    }
}
