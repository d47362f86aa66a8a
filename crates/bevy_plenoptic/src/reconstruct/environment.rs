//! The pack's environment on the GPU (`plenoptic_recon::background`): its uniform at a time
//! ([`EnvironmentUniform`], mirrored by `environment.wgsl`) and its equirectangular image as a
//! texture ([`EnvironmentImages`]). Shared per-view state: the background shows it behind the
//! proxies, and the geometry-assisted lookups give it to rays that leave the scene.

use bevy::asset::RenderAssetUsages;
use bevy::prelude::*;
use bevy::render::render_resource::{Extent3d, ShaderType, TextureDimension, TextureFormat};
use plenoptic_recon::background::{Environment, PlacedEnvironment};

use crate::asset::RadiancePack;

/// The pack's environment at one time, as `environment.wgsl` reads it.
#[derive(ShaderType, Debug, Clone, Default, PartialEq)]
pub struct EnvironmentUniform {
    /// x: kind (0 none: show the key's cube, 1 uniform, 2 sky, 3 image), y: image
    /// intensity, z and w: cosine and sine of the image's turn about +Y.
    pub kind: Vec4,
    /// Uniform colour (xyz).
    pub colour: Vec4,
    /// The sky's 27 Hosek–Wilkie coefficients (A–I of R, G, B), four per vector.
    pub sky: [Vec4; 7],
    /// The sky's radiance scale per channel (xyz).
    pub sky_radiance: Vec4,
    /// Unit direction towards the sun (xyz).
    pub sun: Vec4,
    /// The sky's radiance below the horizon: its ground (xyz; zero without one).
    pub ground: Vec4,
}

impl EnvironmentUniform {
    /// The uniform for `env` (an environment placed at a time).
    pub fn new(env: &PlacedEnvironment) -> Self {
        let mut u = EnvironmentUniform::default();
        match env {
            PlacedEnvironment::None => {}
            PlacedEnvironment::Uniform(c) => {
                u.kind.x = 1.0;
                u.colour = c.extend(0.0);
            }
            PlacedEnvironment::Sky(sky) => {
                let c = sky.coefficients();
                u.kind.x = 2.0;
                for (i, p) in c.params.iter().enumerate() {
                    u.sky[i / 4][i % 4] = *p;
                }
                u.sky_radiance = Vec3::from_array(c.radiances).extend(0.0);
                u.sun = c.sun.extend(0.0);
                u.ground = Vec3::from_array(c.ground).extend(0.0);
            }
            PlacedEnvironment::Image {
                intensity,
                to_image,
                ..
            } => {
                // `to_image` turns about +Y only: its angle, sign from the axis.
                let (axis, angle) = to_image.to_axis_angle();
                let angle = angle * axis.y.signum();
                u.kind = Vec4::new(3.0, 0.0, angle.cos(), angle.sin());
                u.sky_radiance = intensity.extend(0.0);
            }
        }
        u
    }
}

/// The environment image of each pack as a texture (`Rgba32Float`, row 0 at +Y), and the
/// 1 × 1 black texture of packs without one.
#[derive(Resource, Debug, Default)]
pub struct EnvironmentImages {
    images: std::collections::HashMap<AssetId<RadiancePack>, Handle<Image>>,
}

impl EnvironmentImages {
    /// The texture of `pack`'s environment image, made on first use.
    pub(crate) fn get(
        &mut self,
        id: AssetId<RadiancePack>,
        pack: &RadiancePack,
        images: &mut Assets<Image>,
    ) -> Handle<Image> {
        self.images
            .entry(id)
            .or_insert_with(|| {
                let (w, h, texels): (u32, u32, Vec<Vec3>) = match &pack.environment.environment {
                    Environment::Image { image, .. } => {
                        (image.width, image.height, image.texels.clone())
                    }
                    _ => (1, 1, vec![Vec3::ZERO]),
                };
                let data = texels
                    .iter()
                    .flat_map(|t| [t.x, t.y, t.z, 1.0])
                    .flat_map(f32::to_le_bytes)
                    .collect();
                images.add(Image::new(
                    Extent3d {
                        width: w,
                        height: h,
                        depth_or_array_layers: 1,
                    },
                    TextureDimension::D2,
                    data,
                    TextureFormat::Rgba32Float,
                    RenderAssetUsages::RENDER_WORLD,
                ))
            })
            .clone()
    }
}
