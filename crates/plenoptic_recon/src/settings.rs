//! The reconstruction's tunables in one place (docs/architecture.md, "Reconstruction"):
//! [`ReconSettings`], and the choices both backends derive from them and the pack's manifest
//! (the view-space blend of base views, the temporal window tε, the temporal-volume buckets
//! around t). `plenoptic_recon`'s modes and `bevy_plenoptic`'s GPU passes call these; the
//! plugin hands the values to WGSL in uniforms, so no tunable is written twice.

use std::ops::RangeInclusive;

use glam::Vec3;
use plenoptic_pack::Manifest;

use crate::specular::Specular;
use crate::viewspace::ViewWeights;

/// Reconstruction settings; each field's cost/quality trade-off is documented.
#[derive(Clone, Debug, PartialEq)]
pub struct ReconSettings {
    /// Most base views blended per frame (more: smoother transitions, linear cost).
    pub max_views: usize,
    /// Relative distance tolerance of a geometry-assisted lookup (|d_cube − d| < tol·d, where
    /// d_cube is the distance to the plane of the texel's surface along the lookup direction
    /// when normals are available). Too small rejects valid lookups; too large lets occluders
    /// through. Also the relative depth window of blending in image and volume modes.
    pub depth_tolerance: f32,
    /// Exponent of the angular-closeness weight `((1 + cos θ)/2)^p` between a base view's
    /// direction to a point and the camera's (0 disables it).
    pub angular_power: f32,
    /// Half-width tε of the temporal filter window, seconds (`None`: half the bucket span).
    pub time_epsilon: Option<f32>,
    /// Face size of cubes reconstructed from temporal volumes (cost grows with its square).
    pub volume_face_size: u32,
    /// Radius, pixels, of the same-object hole fill search (cost grows with its square in the
    /// worst case; only holes pay it).
    pub hole_fill_radius: u32,
    /// Passes of the background fill in image and volume modes (each extends by a pixel).
    pub background_passes: u32,
    /// Bytes of decoded chunks kept in the cache.
    pub cache_bytes: usize,
    /// How the geometry-assisted mode reads radiance from the cubes.
    pub cube_filter: CubeFilter,
    /// Image and volume modes: relative depth difference under which two splats of warped
    /// texels count as the same surface (the nearer centre wins) rather than one occluding
    /// the other.
    pub same_surface: f32,
    /// Image and volume modes: largest splat edge, pixels (a texel's footprint is capped at
    /// it; larger closes more gaps near the camera and blurs more).
    pub max_splat_px: f32,
    /// What the geometry-assisted mode shows on objects that have a material in the pack.
    pub shading: Shading,
    /// Shadow rays per pixel of the runtime sun ([`crate::sun`]), spread over the pixel's
    /// footprint and the sun's disc. More: smoother shadow edges and penumbrae, linear cost;
    /// 1 gives the pixel centre's hard shadow.
    pub sun_shadow_rays: u32,
    /// Shadow rays for a pixel whose first [`Self::sun_shadow_rays`] disagree (some blocked,
    /// some not: the pixel straddles a shadow edge or lies in a penumbra). Its estimate is
    /// made again with this many, so edges are antialiased as finely as the path tracer's
    /// while lit and shadowed pixels cost only the first rays. At most
    /// [`crate::sun::MAX_SUN_RAYS`]; not above `sun_shadow_rays` turns the refinement off.
    /// For a sun without a disc (hard shadows), refinement finds edge pixels with 5 rays
    /// from the pixel's corners and centre instead, measures their lit fraction along the
    /// edge ([`crate::sun`]), and uses these rays only where no single edge crosses a pixel.
    pub sun_edge_rays: u32,
    /// How the geometry-assisted mode shows the specular part of surfaces with a material:
    /// as the base views saw it, or for the actual camera by marching the reflected ray
    /// through the distance cubes ([`crate::specular`]; the default, for mirrors and glossy
    /// metals). The plugin's GPU path follows the camera's setting.
    pub specular: Specular,
    /// Samples per pixel along each axis (1: the pixel centre). With n > 1 a frame is
    /// reconstructed at n × its size and each pixel is the mean of its n × n samples: the box
    /// filter over the pixel's area that the path tracer's references use, so that edges
    /// against bright windows are not aliased (on the tour, point-sampled edges of windows
    /// are most of the error of some frames; docs/architecture.md, "Measuring"). Cost grows
    /// with n². Depth and object id come from the sample nearest the pixel's centre. The
    /// plugin's GPU path ignores it: there Bevy's `Msaa` antialiases the proxies' edges.
    pub supersampling: u32,
    /// Materials' frames: look the lighting up at a quarter of the pixels (even rows and
    /// columns) and interpolate between them where the lookups agree: same object facing the
    /// same way, same keys answering with whole bilinear footprints, no depth step
    /// (`geometry/sparse.rs`); every other pixel is looked up itself. The lighting is at cube
    /// resolution, so this changes the test room's lighting by 0.04 % on average; the textured
    /// frame of benches/recon.rs takes 0.84× the time at 640 × 360 (`geometry_textured`
    /// against `geometry_textured_dense`). The plugin's lookup kernel follows the same rule
    /// (`bevy_plenoptic`'s `lookup_kernel.rs`); fragments that make their own lookups make
    /// them at every pixel.
    pub sparse_lighting: bool,
    /// With [`Specular::Marched`] on a pack with proxies: a reflected ray that meets a proxy
    /// is answered at that point ([`crate::specular`]), and on a pack with materials the
    /// surface an ideal mirror's ray meets is shaded as a pixel is, its material at the
    /// hit's UV × the baked lighting there + the runtime sun (`reflected.rs`). Off, every ray
    /// is marched through the distance cubes and reads the base views' radiance where it
    /// crosses them. In the `specular` test (320 × 180, 4 × 4 samples) the mirror's error
    /// fell from 2.18× to 1.32× the diffuse pixels' under the sun, and from 2.08× to 1.59×
    /// under a lamp. The plugin's GPU path does not do this yet: it marches as this does
    /// when off.
    pub shaded_reflections: bool,
}

/// What the geometry-assisted mode shows on objects with a material (the `shading` module;
/// docs/architecture.md, "Pack v2").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Shading {
    /// The material's albedo at each pixel's UV × the baked lighting + the baked non-diffuse
    /// radiance (pack v2): textures at screen resolution. Objects without a material show
    /// their radiance. Three lookup passes instead of one (benches/recon.rs).
    #[default]
    Materials,
    /// The baked radiance, as image and volume modes and version-1 packs show it: textures
    /// at cube resolution, one lookup pass. What the plugin's GPU path shows today.
    Radiance,
}

/// How radiance is read from a base view's cube in the geometry-assisted mode.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum CubeFilter {
    /// The texel the direction falls in (the fastest).
    #[default]
    Nearest,
    /// Seamless bilinear filtering: the four texels around the direction, taken across face
    /// seams from the neighbouring face ([`plenoptic_pack::cube`] convention), restricted to
    /// the texels that show the same object at the same distance (so that edges stay sharp).
    /// The lookup is still accepted or rejected by its nearest texel. Lowers the error against
    /// the path tracer (by about an eighth on the test room) and takes about twice the time
    /// per frame of `Nearest` (benches/recon.rs). `bevy_plenoptic`'s GPU lookups filter the
    /// same way when a camera's settings ask for it.
    Bilinear,
}

impl Default for ReconSettings {
    fn default() -> Self {
        ReconSettings {
            max_views: 4,
            depth_tolerance: 0.03,
            angular_power: 8.0,
            time_epsilon: None,
            volume_face_size: 48,
            hole_fill_radius: 12,
            background_passes: 24,
            cache_bytes: 512 << 20,
            cube_filter: CubeFilter::Nearest,
            same_surface: 0.03,
            max_splat_px: 8.0,
            shading: Shading::Materials,
            sun_shadow_rays: 4,
            sun_edge_rays: 32,
            specular: Specular::default(),
            supersampling: 1,
            sparse_lighting: true,
            shaded_reflections: true,
        }
    }
}

impl ReconSettings {
    /// The half-width tε of the temporal filter window on `manifest`'s pack:
    /// [`ReconSettings::time_epsilon`], or half the bucket span.
    pub fn time_epsilon_on(&self, manifest: &Manifest) -> f32 {
        self.time_epsilon
            .unwrap_or(manifest.bucket_span * 0.5)
            .max(1e-6)
    }

    /// The base views blended for a camera at `position`, with their weights normalised to
    /// sum 1: the pack's view-space weights over the `usable` views
    /// ([`crate::viewspace::ViewWeights`]), heaviest first, at most
    /// [`ReconSettings::max_views`].
    pub fn view_weights(
        &self,
        manifest: &Manifest,
        usable: &[bool],
        position: Vec3,
    ) -> Vec<(usize, f32)> {
        let mut w =
            ViewWeights::new(&manifest.view_space, &manifest.base_views, usable).weights(position);
        w.truncate(self.max_views.max(1));
        let s: f32 = w.iter().map(|x| x.1).sum();
        if s > 0.0 {
            for x in &mut w {
                x.1 /= s;
            }
        }
        w
    }

    /// The temporal-volume buckets whose samples can fall in the filter window t ± tε (at
    /// most 65).
    pub fn volume_buckets(&self, manifest: &Manifest, t: f32) -> RangeInclusive<u32> {
        let eps = self.time_epsilon_on(manifest);
        let b0 = manifest.bucket_of(t - eps);
        let b1 = manifest.bucket_of(t + eps);
        b0..=b1.min(b0.saturating_add(64))
    }
}
