//! The surface seen through each pixel, for the materials' frame ([`crate::shading`]): a
//! raster pass gives each pixel its proxy triangle, from which the point, the normals, the UV
//! (barycentric coordinates of the pixel's point on the placed triangle) and the footprint
//! follow, and the material at that UV with the texture's mip chosen by the footprint
//! ([`crate::material`]).

use std::borrow::Cow;

use glam::{Affine3A, Vec2, Vec3};
use rayon::prelude::*;

use crate::Reconstructor;
use crate::brdf::SurfaceMaterial;
use crate::camera::{Camera, CameraBasis};
use crate::geometry::Layer;
use crate::material::Materials;
use crate::proxy::{ProxyGeometry, TriangleMesh};

/// What the compose stage needs of the surface seen through one pixel.
pub(crate) struct SurfacePixel {
    pub object: u32,
    pub material: SurfaceMaterial,
    /// Whether its specular part is marched for the camera ([`crate::specular::Specular::marches`]).
    pub marched: bool,
    /// Transmissive glass drawn in the see-through layer: only its reflection is shown.
    pub see_through: bool,
    /// Emitted radiance at the pixel's UV where the pack leaves the emission to the runtime
    /// (pack 4) or the specular part is marched (which replaces the baked non-diffuse
    /// radiance, holding the emission before pack 4); else zero.
    pub emission: Vec3,
    /// Where the pixel needs its BSDF (the runtime sun shines, or its reflection is marched):
    /// the point, normals and footprint; `None` elsewhere, which the albedo alone serves.
    pub geometry: Option<PixelGeometry>,
}

/// The geometry of the surface seen through a pixel, for its BSDF.
pub(crate) struct PixelGeometry {
    /// The point on the proxy (world).
    pub position: Vec3,
    /// Geometric normal as the mesh winds it (world, unit).
    pub ng: Vec3,
    /// Shading normal on `ng`'s side: the proxy's vertex normals interpolated, else `ng`,
    /// bent by the normal map.
    pub ns: Vec3,
    /// Unit direction of the pixel's ray.
    pub view: Vec3,
    /// How far the point moves on the surface's plane for a step of one pixel in x and in y
    /// (the footprint the runtime sun's shadow rays spread over; zero without the sun).
    pub footprint: (Vec3, Vec3),
}

/// The raster of the same proxies and pixels made by the lighting pass
/// ([`crate::geometry::PairFrame::triangles`]): [`Surfaces::new`] need not make its own.
pub(crate) struct SharedRaster<'a> {
    pub projected: crate::raster::Projected,
    /// Per pixel: the triangle (index into `projected.sources`), the object and the distance
    /// along the pixel's ray.
    pub prim: Vec<u32>,
    pub object: &'a [u32],
    pub depth: &'a [f32],
}

/// Per pixel, the surface of an object with a material seen there: the raster of the
/// proxies and their triangles prepared once per frame, the pixels computed on demand
/// ([`Surfaces::pixel`]) so that a caller shades each while it is in cache.
pub(crate) struct Surfaces<'a> {
    rec: &'a Reconstructor,
    materials: &'a Materials,
    /// Per pixel of the raster: object, projected triangle and distance along the ray.
    object: Cow<'a, [u32]>,
    prim: Vec<u32>,
    depth: Cow<'a, [f32]>,
    /// Per projected triangle: what its pixels need, `None` without a material.
    triangles: Vec<Option<SurfaceTriangle<'a>>>,
    basis: CameraBasis,
    width: usize,
    /// The angle one pixel subtends at the image centre.
    pixel_angle: f32,
    /// The see-through layer ([`Layer::Only`]), and the glazing in it.
    see_through_layer: bool,
    glazing: Vec<u32>,
    with_footprint: bool,
    /// Whether every pixel needs its geometry (the runtime lamps' diffuse light, the sun).
    with_geometry: bool,
    glossy: bool,
    runtime_emission: bool,
    /// Milliseconds the raster pass took.
    pub raster_ms: f64,
}

impl<'a> Surfaces<'a> {
    /// The surfaces of the proxies of `layer` seen by `camera` at `t`; with their footprint
    /// only `with_footprint` (the runtime sun's shadow rays need it), their geometry also
    /// where the pack leaves its lamps to the runtime, their emission where the
    /// pack leaves it to the runtime or their specular part is marched (`glossy`:
    /// [`crate::specular::glossy_allowed`]); rasterized unless the lighting pass `shared` its
    /// raster of the same proxies.
    #[expect(clippy::too_many_arguments, reason = "one frame's set-up, called once")]
    pub fn new(
        rec: &'a Reconstructor,
        proxy: &'a ProxyGeometry,
        materials: &'a Materials,
        camera: &Camera,
        t: f32,
        layer: Layer<'_>,
        with_footprint: bool,
        glossy: bool,
        shared: Option<SharedRaster<'a>>,
    ) -> Self {
        let start = std::time::Instant::now();
        let runtime_emission = rec.pack().runtime_emission();
        // Glazing (coverage) is composited as such even where its material transmits
        // (crate::glazing); only other transmissive glass shows its reflection alone.
        let glazing: Vec<u32> = match layer {
            Layer::Only(_) => rec
                .pack()
                .manifest()
                .objects
                .iter()
                .filter(|o| o.coverage.is_some())
                .map(|o| o.id)
                .collect(),
            _ => Vec::new(),
        };
        let mut placed = proxy.placed_meshes(t);
        match layer {
            Layer::All => {}
            Layer::Without(ids) => placed.retain(|o| !ids.contains(&o.0)),
            Layer::Only(ids) => placed.retain(|o| ids.contains(&o.0)),
        }
        let (projected, object, prim, depth) = match shared {
            Some(r) => (
                r.projected,
                Cow::Borrowed(r.object),
                r.prim,
                Cow::Borrowed(r.depth),
            ),
            None => {
                let projected = crate::raster::project(camera, &placed);
                let (object, prim, depth) = crate::raster::rasterize_sources(camera, &projected);
                (projected, Cow::Owned(object), prim, Cow::Owned(depth))
            }
        };
        let raster_ms = start.elapsed().as_secs_f64() * 1e3;
        let eye = camera.basis().position;
        // Per projected triangle, once: its placed corners, normals, UVs and UV-per-metre scale.
        let triangles: Vec<Option<SurfaceTriangle<'_>>> = projected
            .sources
            .par_iter()
            .map(|&(oi, ti)| {
                let (id, xf, mesh) = placed.get(oi as usize)?;
                SurfaceTriangle::placed(*id, materials.object(*id)?, mesh, *xf, ti, eye)
            })
            .collect();
        let basis = camera.basis();
        Surfaces {
            rec,
            materials,
            object,
            prim,
            depth,
            triangles,
            width: camera.width as usize,
            pixel_angle: 2.0 * basis.tan_y / basis.height,
            basis,
            see_through_layer: matches!(layer, Layer::Only(_)),
            glazing,
            with_footprint,
            with_geometry: with_footprint || rec.pack().lamps_at_runtime(),
            glossy,
            runtime_emission,
            raster_ms,
        }
    }

    /// The surface seen through pixel `j`, `None` where there is none with a material.
    ///
    /// The pixel's UV and footprint come from the triangle's projective form
    /// ([`SurfaceTriangle::uv_along`]); the point, normals and normal map only where the
    /// pixel needs its BSDF.
    pub fn pixel(&self, j: usize) -> Option<SurfacePixel> {
        let t = self.triangles.get(self.prim[j] as usize)?.as_ref()?;
        if t.object != self.object[j] {
            return None;
        }
        let (x, y) = ((j % self.width) as f32 + 0.5, (j / self.width) as f32 + 0.5);
        let b = &self.basis;
        let ray = b.ray(x, y);
        let len = ray.length();
        // The pixel's ray met on the triangle's plane: the raster's interpolated depth is
        // off by ~10⁻⁴ of the distance, enough to put the point under the surface for a
        // shadow ray. Edge-on, the raster's depth.
        let (along, uv) = t.uv_along(ray, len).unwrap_or_else(|| {
            (
                self.depth[j],
                t.uv_at(b.position + ray * (self.depth[j] / len)),
            )
        });
        let uv_footprint = if t.uv.is_some() {
            let cos = (t.normal.dot(ray) / len).abs().max(0.05);
            // A pixel off the axis subtends cos³α of the central pixel's solid angle
            // (cos α = 1/|ray|, as forward · ray = 1).
            let c = 1.0 / len;
            t.scale * along * self.pixel_angle * c * c.sqrt() / cos.sqrt()
        } else {
            f32::INFINITY
        };
        let material =
            self.materials
                .surface(self.rec.pack(), &t.material.material, uv, uv_footprint);
        // In the see-through layer, transmissive glass shows its reflection alone: what
        // it lets through is composited from the layer behind (crate::glazing).
        let see_through = self.see_through_layer
            && material.transmission > 0.0
            && !self.glazing.contains(&t.object);
        let reflection_of = SurfaceMaterial {
            transmission: 0.0,
            ..material
        };
        let marched = self.rec.settings.specular.marches(
            if see_through {
                &reflection_of
            } else {
                &material
            },
            self.glossy || see_through,
        );
        let ng = t.normal;
        // A single-sided emitter emits from its front only, as the tracer has it.
        let emits = t.material.material.double_sided || ray.dot(ng) < 0.0;
        let emission = if emits && (marched || self.runtime_emission) {
            self.materials
                .emission(self.rec.pack(), &t.material.material, uv, uv_footprint)
                * self.rec.relight.object(t.object)
        } else {
            Vec3::ZERO
        };
        let geometry = (marched || self.with_geometry).then(|| {
            let view = ray / len;
            let position = b.position + view * along;
            self.geometry(t, position, view, uv, uv_footprint, (x, y), along)
        });
        Some(SurfacePixel {
            object: t.object,
            material,
            marched,
            see_through,
            emission,
            geometry,
        })
    }

    /// The normals and footprint of the point `position` of triangle `t` seen along `view`
    /// from pixel centre `(x, y)` at distance `along`.
    #[expect(clippy::too_many_arguments, reason = "what pixel() computed before")]
    fn geometry(
        &self,
        t: &SurfaceTriangle<'_>,
        position: Vec3,
        view: Vec3,
        uv: Vec2,
        uv_footprint: f32,
        (x, y): (f32, f32),
        along: f32,
    ) -> PixelGeometry {
        let ng = t.normal;
        let ns = t.shading_normal(self.rec, self.materials, position, uv, uv_footprint);
        // The neighbouring pixels' rays met on the triangle's plane; at most 4 pixels'
        // worth of depth away, so that a grazing plane does not smear the footprint.
        let limit = 4.0 * along * self.pixel_angle;
        let step = |d: Vec3| {
            let den = d.dot(ng);
            let s = if den.abs() > 1e-6 {
                (position - self.basis.position).dot(ng) / den
            } else {
                along
            };
            (self.basis.position + d * s - position).clamp_length_max(limit)
        };
        let footprint = if self.with_footprint {
            (
                step(self.basis.direction(x + 1.0, y)),
                step(self.basis.direction(x, y + 1.0)),
            )
        } else {
            (Vec3::ZERO, Vec3::ZERO)
        };
        PixelGeometry {
            position,
            ng,
            ns,
            view,
            footprint,
        }
    }
}

/// The surface a reflected ray meets, shaded as a pixel's ([`surface_at`]).
pub(crate) struct HitSurface {
    pub material: SurfaceMaterial,
    /// Emitted radiance towards the ray where the pack leaves the emission to the runtime
    /// (pack 4; else it is in the non-diffuse cube); zero from a single-sided emitter's back.
    pub emission: Vec3,
    /// Geometric normal as the mesh winds it (world, unit).
    pub ng: Vec3,
    /// Shading normal on `ng`'s side ([`SurfaceTriangle::shading_normal`]).
    pub ns: Vec3,
}

/// The surface of triangle `ti` of object `id`'s `mesh` (placed by `xf`) at its point `p`,
/// met by a ray along unit `dir` whose footprint is `width` metres across there: the
/// material at the point's UV, with the texture's mip chosen by that footprint on the surface,
/// as [`Surfaces::pixel`] shades a pixel. `None` for an object without a material or a
/// degenerate triangle.
#[expect(clippy::too_many_arguments, reason = "the hit and where its mesh is")]
pub(crate) fn surface_at(
    rec: &Reconstructor,
    materials: &Materials,
    id: u32,
    mesh: &TriangleMesh,
    xf: Affine3A,
    ti: u32,
    p: Vec3,
    dir: Vec3,
    width: f32,
) -> Option<HitSurface> {
    let m = materials.object(id)?;
    let t = SurfaceTriangle::placed(id, m, mesh, xf, ti, p - dir)?;
    let uv = t.uv_at(p);
    let uv_footprint = if t.uv.is_some() {
        t.scale * width / t.normal.dot(dir).abs().max(0.05).sqrt()
    } else {
        f32::INFINITY
    };
    let material = materials.surface(rec.pack(), &m.material, uv, uv_footprint);
    let ng = t.normal;
    let emits = m.material.double_sided || dir.dot(ng) < 0.0;
    let emission = if emits && rec.pack().runtime_emission() {
        materials.emission(rec.pack(), &m.material, uv, uv_footprint) * rec.relight.object(id)
    } else {
        Vec3::ZERO
    };
    Some(HitSurface {
        material,
        emission,
        ng,
        ns: t.shading_normal(rec, materials, p, uv, uv_footprint),
    })
}

/// A placed proxy triangle of an object with a material, ready for per-pixel UVs.
///
/// Its projective form gives a pixel's UV from the pixel's ray `r` (not normalised) with
/// three dot products and a division: the ray meets the plane `n · (p − v₀) = 0` at
/// `λ = k / (r · n)` along `r`, with `k = n · (v₀ − eye)`; the barycentric coordinates
/// `b₁ = (p − v₀) · g₁` and `b₂ = (p − v₀) · g₂` (`g` from the inverse Gram matrix) are then
/// `λ (r · g) − (v₀ − eye) · g`, so each UV coordinate is a constant plus `λ (r · G)` with
/// `G` the UV deltas' combination of `g₁` and `g₂`.
struct SurfaceTriangle<'m> {
    object: u32,
    material: &'m crate::material::ObjectMaterial,
    origin: Vec3,
    e0: Vec3,
    e1: Vec3,
    /// The inverse Gram matrix of (e0, e1): barycentrics from dot products.
    inv: [f32; 3],
    normal: Vec3,
    /// Vertex normals placed in the world, when the proxy has them.
    normals: Option<[Vec3; 3]>,
    /// Vertex tangents placed in the world and the bitangent's sign, when the material has a
    /// normal map and the proxy tangents.
    tangents: Option<([Vec3; 3], f32)>,
    uv: Option<[Vec2; 3]>,
    /// √(UV area / world area).
    scale: f32,
    /// The projective form: `k`, the UV's constant part and its `G` per coordinate.
    k: f32,
    uv_constant: Vec2,
    uv_gradient: [Vec3; 2],
}

impl<'m> SurfaceTriangle<'m> {
    /// Triangle `ti` of object `id`'s `mesh` placed by `xf`, seen from `eye`: its corners,
    /// UVs, vertex normals, and tangents where the material's normal map needs them.
    fn placed(
        id: u32,
        m: &'m crate::material::ObjectMaterial,
        mesh: &TriangleMesh,
        xf: Affine3A,
        ti: u32,
        eye: Vec3,
    ) -> Option<Self> {
        let tri = mesh.triangles.get(ti as usize)?;
        let v = tri.map(|i| xf.transform_point3(mesh.positions[i as usize]));
        let uv = match tri.map(|i| m.uvs.get(i as usize).copied()) {
            [Some(a), Some(b), Some(c)] => Some([a, b, c]),
            _ => None,
        };
        let normals = (mesh.normals.len() == mesh.positions.len()).then(|| {
            let to_world = xf.matrix3.inverse().transpose();
            tri.map(|i| to_world * mesh.normals[i as usize])
        });
        // Tangents only where a normal map needs them (placed as the tracer places them).
        let tangents = (m.material.normal_texture.is_some()
            && m.tangents.len() == mesh.positions.len())
        .then(|| {
            let t = tri.map(|i| m.tangents[i as usize]);
            // A mirroring placement flips the bitangent's handedness, as in the tracer.
            let sign = t[0].w * xf.matrix3.determinant().signum();
            (t.map(|t| xf.matrix3 * t.truncate()), sign)
        });
        let mut t = SurfaceTriangle::new(id, m, v, uv, eye)?;
        if xf.matrix3.determinant() < 0.0 {
            // The tracer's geometric normal is the object-space one carried by the normal
            // matrix, which a mirroring transform turns against the placed winding.
            t.flip();
        }
        t.normals = normals;
        t.tangents = tangents;
        Some(t)
    }

    /// The triangle `v` (with `uv` at its corners) as seen from `eye`.
    fn new(
        object: u32,
        material: &'m crate::material::ObjectMaterial,
        v: [Vec3; 3],
        uv: Option<[Vec2; 3]>,
        eye: Vec3,
    ) -> Option<Self> {
        let (e0, e1) = (v[1] - v[0], v[2] - v[0]);
        let (d00, d01, d11) = (e0.dot(e0), e0.dot(e1), e1.dot(e1));
        let den = d00 * d11 - d01 * d01;
        if den.is_nan() || den.abs() <= 1e-20 {
            return None;
        }
        let world = e0.cross(e1);
        let scale = uv.map_or(0.0, |[a, b, c]| {
            ((b - a).perp_dot(c - a).abs() / world.length().max(1e-12)).sqrt()
        });
        let inv = [d11 / den, -d01 / den, d00 / den];
        let normal = world.normalize_or_zero();
        let a = v[0] - eye;
        let (g1, g2) = (e0 * inv[0] + e1 * inv[1], e0 * inv[1] + e1 * inv[2]);
        let (uv_constant, uv_gradient) =
            uv.map_or((Vec2::ZERO, [Vec3::ZERO; 2]), |[t0, t1, t2]| {
                let (d1, d2) = (t1 - t0, t2 - t0);
                let (a1, a2) = (a.dot(g1), a.dot(g2));
                (
                    t0 - d1 * a1 - d2 * a2,
                    [g1 * d1.x + g2 * d2.x, g1 * d1.y + g2 * d2.y],
                )
            });
        Some(SurfaceTriangle {
            object,
            material,
            origin: v[0],
            e0,
            e1,
            inv,
            normal,
            normals: None,
            tangents: None,
            uv,
            scale,
            k: a.dot(normal),
            uv_constant,
            uv_gradient,
        })
    }

    /// The shading normal at `p` (UV `uv`, footprint `uv_footprint`) on the geometric
    /// normal's side: the vertex normals interpolated, else the geometric normal, bent by the
    /// material's normal map.
    fn shading_normal(
        &self,
        rec: &Reconstructor,
        materials: &Materials,
        p: Vec3,
        uv: Vec2,
        uv_footprint: f32,
    ) -> Vec3 {
        let b = self.barycentric(p);
        let ng = self.normal;
        let mut ns = self.normals.map_or(ng, |[a, c, d]| {
            (a * b.x + c * b.y + d * b.z).normalize_or(ng)
        });
        if let Some(([ta, tb, tc], sign)) = self.tangents
            && let Some(local) =
                materials.normal(rec.pack(), &self.material.material, uv, uv_footprint)
        {
            let tangent = ta * b.x + tb * b.y + tc * b.z;
            ns = crate::material::bend_normal(ns, tangent, sign, local);
        }
        if ns.dot(ng) < 0.0 { -ns } else { ns }
    }

    /// Flips the geometric normal (a mirroring placement), keeping the projective form.
    fn flip(&mut self) {
        self.normal = -self.normal;
        self.k = -self.k;
    }

    /// The distance along the unit ray and the UV where the ray `ray` (of length `len`, from
    /// the eye) meets the triangle's plane; `None` edge-on.
    #[inline]
    fn uv_along(&self, ray: Vec3, len: f32) -> Option<(f32, Vec2)> {
        let q = ray.dot(self.normal);
        if q.abs() <= 1e-4 * len {
            return None;
        }
        let lambda = self.k / q;
        let [gu, gv] = self.uv_gradient;
        let uv = self.uv_constant + Vec2::new(ray.dot(gu), ray.dot(gv)) * lambda;
        Some((lambda * len, uv))
    }

    /// The UV at `p` (on or near the triangle's plane); zero without UVs.
    fn uv_at(&self, p: Vec3) -> Vec2 {
        let b = self.barycentric(p);
        self.uv
            .map_or(Vec2::ZERO, |uv| uv[0] * b.x + uv[1] * b.y + uv[2] * b.z)
    }

    /// Barycentric coordinates of `p` (on or near the triangle's plane).
    fn barycentric(&self, p: Vec3) -> Vec3 {
        let e2 = p - self.origin;
        let (d20, d21) = (e2.dot(self.e0), e2.dot(self.e1));
        let b1 = self.inv[0] * d20 + self.inv[1] * d21;
        let b2 = self.inv[1] * d20 + self.inv[2] * d21;
        Vec3::new(1.0 - b1 - b2, b1, b2)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn barycentric_coordinates_recover_the_point() {
        let m = crate::material::ObjectMaterial {
            material: Default::default(),
            uvs: Vec::new(),
            tangents: Vec::new(),
        };
        let v = [Vec3::ZERO, Vec3::X * 2.0, Vec3::new(0.0, 3.0, 1.0)];
        let t = SurfaceTriangle::new(1, &m, v, None, Vec3::ONE).unwrap();
        let q = v[0] * 0.2 + v[1] * 0.5 + v[2] * 0.3;
        let b = t.barycentric(q);
        assert!((b - Vec3::new(0.2, 0.5, 0.3)).length() < 1e-5, "{b}");
        assert!(SurfaceTriangle::new(1, &m, [Vec3::ZERO; 3], None, Vec3::ONE).is_none());
    }

    #[test]
    fn the_projective_form_gives_the_barycentric_uv() {
        let m = crate::material::ObjectMaterial {
            material: Default::default(),
            uvs: Vec::new(),
            tangents: Vec::new(),
        };
        let v = [
            Vec3::new(-1.0, 0.0, -3.0),
            Vec3::new(2.0, 0.2, -4.0),
            Vec3::new(0.0, 2.5, -3.5),
        ];
        let uv = [
            Vec2::new(3.0, 1.0),
            Vec2::new(7.5, 1.5),
            Vec2::new(4.0, -2.0),
        ];
        let eye = Vec3::new(0.3, 0.8, 1.0);
        for flipped in [false, true] {
            let mut t = SurfaceTriangle::new(1, &m, v, Some(uv), eye).unwrap();
            if flipped {
                t.flip();
            }
            for b in [[0.2, 0.5, 0.3], [0.9, 0.05, 0.05], [0.1, 0.1, 0.8]] {
                let p = v[0] * b[0] + v[1] * b[1] + v[2] * b[2];
                let want = uv[0] * b[0] + uv[1] * b[1] + uv[2] * b[2];
                // Any length of ray: only its direction matters.
                let ray = (p - eye) * 0.37;
                let (along, got) = t.uv_along(ray, ray.length()).unwrap();
                assert!((got - want).length() < 1e-4, "{got} against {want}");
                assert!((along - (p - eye).length()).abs() < 1e-4, "{along}");
                assert!((t.uv_at(p) - want).length() < 1e-4);
            }
            // Edge-on: no answer.
            let along_plane = (v[1] - v[0]).normalize();
            assert!(t.uv_along(along_plane, 1.0).is_none());
        }
    }
}
