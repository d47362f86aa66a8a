//! An irradiance volume over the pack's scene: diffuse light for the app's meshes that
//! varies with their position, on every device.
//!
//! Bevy applies reflection probes only where the device has binding arrays (not on Mesa's
//! lavapipe, WebGPU or WebGL 2), but one irradiance volume everywhere. So for each pack
//! the plugin also keeps one Bevy [`IrradianceVolume`] spanning the scene's bounds: each
//! voxel holds the ambient cube (Valve's six-direction irradiance, Mitchell 2006, the
//! representation Bevy samples) of the base view nearest the voxel's centre, computed from
//! that view's light probe ([`super::probes`]): for each axis direction `a`,
//! `Σ L(ω) max(0, a·ω) Δω / π` over the probe cube's texels (the diffuse light a white
//! surface facing `a` would show at the base view). Voxels are about half the spacing of the
//! base views (at most [`MAX_VOXELS`] a side), so each base view's region of the plan shows
//! its own light; the volume is rebuilt when a probe's cubemap changes. Bevy takes a view's
//! diffuse indirect light from its irradiance volumes alone once one exists, so inside the
//! volume it replaces the camera's environment light's diffuse part (its specular part
//! stays), and a mesh outside the volume's box ([`volume_box`]) gets no diffuse light from
//! the pack.

use std::collections::HashMap;

use bevy::asset::RenderAssetUsages;
use bevy::light::{IrradianceVolume, LightProbe};
use bevy::prelude::*;
use bevy::render::render_resource::{Extent3d, TextureDimension, TextureFormat};
use plenoptic_pack::cube::texel_direction;

use super::probes::PlenopticProbe;
use crate::asset::RadiancePack;

/// Most voxels along one side of the volume.
pub const MAX_VOXELS: u32 = 32;

/// The six axis directions of an ambient cube, in the order +X, −X, +Y, −Y, +Z, −Z.
const AXES: [Vec3; 6] = [
    Vec3::X,
    Vec3::NEG_X,
    Vec3::Y,
    Vec3::NEG_Y,
    Vec3::Z,
    Vec3::NEG_Z,
];

/// The ambient cube of a radiance cube of face `face` (texels in the pack's layout, world
/// directions): per axis direction (+X, −X, +Y, −Y, +Z, −Z) the irradiance over π.
pub fn ambient_cube(face: u32, texels: &[Vec3]) -> [Vec3; 6] {
    let mut out = [Vec3::ZERO; 6];
    for (i, l) in texels.iter().enumerate() {
        let d = texel_direction(face, i);
        // A texel's solid angle: (2/n)² · cos³ of its angle to its face's axis.
        let omega = (2.0 / face as f32).powi(2) * d.abs().max_element().powi(3);
        for (o, a) in out.iter_mut().zip(AXES) {
            *o += *l * (a.dot(d).max(0.0) * omega);
        }
    }
    out.map(|o| o / std::f32::consts::PI)
}

/// The irradiance volume of one pack.
#[derive(Component, Debug, Clone)]
pub struct PlenopticIrradianceVolume {
    /// The pack.
    pub pack: AssetId<RadiancePack>,
    /// Its voxels (`Rgba16Float`, Bevy's layout).
    pub voxels: Handle<Image>,
}

/// The voxel counts along x, y, z of a volume over `size` with voxels of about `spacing`.
pub fn resolution(size: Vec3, spacing: f32) -> UVec3 {
    let n = |s: f32| ((s / spacing.max(1e-3)).ceil() as u32).clamp(1, MAX_VOXELS);
    UVec3::new(n(size.x), n(size.y), n(size.z))
}

/// For each voxel of a volume of `res` voxels over the box `(min, max)` (x fastest, then y,
/// then z), the index of the nearest of `views`.
pub fn nearest_views(min: Vec3, max: Vec3, res: UVec3, views: &[Vec3]) -> Vec<usize> {
    let size = max - min;
    let mut out = Vec::with_capacity((res.x * res.y * res.z) as usize);
    for z in 0..res.z {
        for y in 0..res.y {
            for x in 0..res.x {
                let centre = min + size * (UVec3::new(x, y, z).as_vec3() + 0.5) / res.as_vec3();
                let nearest = (0..views.len())
                    .min_by(|&a, &b| {
                        views[a]
                            .distance(centre)
                            .total_cmp(&views[b].distance(centre))
                    })
                    .unwrap_or(0);
                out.push(nearest);
            }
        }
    }
    out
}

/// Bevy's irradiance-volume texture of `res` voxels: voxel `i` (in [`nearest_views`]'
/// order) takes `cubes[nearest[i]]`, an ambient cube (+X, −X, +Y, −Y, +Z, −Z). Layout (as
/// Bevy's `irradiance_volume.wgsl` samples it): a 3D texture of `(Rx, 2Ry, 3Rz)`, the
/// positive directions in rows `0..Ry` and the negative ones in `Ry..2Ry`, X, Y and Z in
/// slices `0..Rz`, `Rz..2Rz`, `2Rz..3Rz`.
pub fn voxel_image(res: UVec3, nearest: &[usize], cubes: &[[Vec3; 6]]) -> Image {
    let (w, h, d) = (res.x, 2 * res.y, 3 * res.z);
    let mut data = vec![0u8; (w * h * d) as usize * 8];
    let mut voxel = 0;
    for z in 0..res.z {
        for y in 0..res.y {
            for x in 0..res.x {
                let cube = nearest.get(voxel).and_then(|&n| cubes.get(n));
                voxel += 1;
                let Some(cube) = cube else { continue };
                for (side, value) in cube.iter().enumerate() {
                    let (axis, negative) = (side / 2, side % 2 == 1);
                    let t = y + if negative { res.y } else { 0 };
                    let p = z + axis as u32 * res.z;
                    let i = ((p * h + t) * w + x) as usize * 8;
                    for (c, v) in [value.x, value.y, value.z, 1.0].into_iter().enumerate() {
                        data[i + 2 * c..i + 2 * c + 2]
                            .copy_from_slice(&half::f16::from_f32(v).to_le_bytes());
                    }
                }
            }
        }
    }
    Image::new(
        Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: d,
        },
        TextureDimension::D3,
        data,
        TextureFormat::Rgba16Float,
        RenderAssetUsages::RENDER_WORLD,
    )
}

/// The box the volume spans: the scene's bounds, or for a pack without them the base views'
/// box grown by four times the views' spacing (at least 2 m) on every side. Bevy's
/// irradiance volumes replace the environment map's diffuse light in the whole view, also
/// outside every volume (where they give none), so the box must hold every mesh the pack
/// should light.
pub fn volume_box(bounds: (Vec3, Vec3), views: &[Vec3], spacing: f32) -> (Vec3, Vec3) {
    let size = bounds.1 - bounds.0;
    if size.min_element() > 0.0 && size.is_finite() {
        return bounds;
    }
    let grow = Vec3::splat(if spacing.is_finite() {
        (4.0 * spacing).max(2.0)
    } else {
        2.0
    });
    let min = views.iter().fold(Vec3::INFINITY, |a, b| a.min(*b));
    let max = views.iter().fold(Vec3::NEG_INFINITY, |a, b| a.max(*b));
    if !(min.is_finite() && max.is_finite()) {
        return (-grow, grow);
    }
    (min - grow, max + grow)
}

/// A pack's volume layout: its box and resolution (from all its usable base views, so it
/// does not move as probes arrive), and for the probes present (their views, sorted) each
/// voxel's nearest.
pub(super) struct Layout {
    min: Vec3,
    max: Vec3,
    res: UVec3,
    views: Vec<u32>,
    nearest: Vec<usize>,
}

/// Keeps one irradiance volume per pack with probes, rebuilt when one of its probes changes.
pub(super) fn update_volumes(
    mut commands: Commands,
    packs: Res<Assets<RadiancePack>>,
    probes: Query<&PlenopticProbe>,
    changed: Query<&PlenopticProbe, Changed<PlenopticProbe>>,
    volumes: Query<(Entity, &PlenopticIrradianceVolume)>,
    mut images: ResMut<Assets<Image>>,
    mut layouts: Local<HashMap<AssetId<RadiancePack>, Layout>>,
) {
    let mut ids: Vec<AssetId<RadiancePack>> = probes.iter().map(|p| p.pack).collect();
    ids.sort();
    ids.dedup();
    for (entity, volume) in &volumes {
        if !ids.contains(&volume.pack) {
            commands.entity(entity).despawn();
        }
    }
    layouts.retain(|id, _| ids.contains(id));
    for id in ids {
        if !changed.iter().any(|p| p.pack == id) {
            continue;
        }
        let Some(pack) = packs.get(id) else { continue };
        let m = pack.reader.manifest();
        let mut present: Vec<&PlenopticProbe> = probes.iter().filter(|p| p.pack == id).collect();
        present.sort_by_key(|p| p.view);
        let views: Vec<u32> = present.iter().map(|p| p.view).collect();
        let layout = layouts.entry(id).or_insert_with(|| {
            let all: Vec<Vec3> = (0..m.base_views.len())
                .filter(|&v| pack.usable_views.get(v).copied().unwrap_or(false))
                .map(|v| m.base_views[v].position)
                .collect();
            let spacing = (0..all.len())
                .map(|v| super::probes::probe_side(&all, v, 0.0))
                .fold(f32::INFINITY, f32::min);
            let (min, max) = volume_box((m.scene_bounds.min, m.scene_bounds.max), &all, spacing);
            let size = max - min;
            Layout {
                min,
                max,
                res: resolution(size, 0.5 * spacing.min(size.max_element())),
                views: Vec::new(),
                nearest: Vec::new(),
            }
        });
        if layout.views != views {
            let positions: Vec<Vec3> = views
                .iter()
                .map(|&v| m.base_views[v as usize].position)
                .collect();
            layout.nearest = nearest_views(layout.min, layout.max, layout.res, &positions);
            layout.views = views;
        }
        let cubes: Vec<[Vec3; 6]> = present.iter().map(|p| p.ambient).collect();
        let image = voxel_image(layout.res, &layout.nearest, &cubes);
        match volumes.iter().find(|(_, v)| v.pack == id) {
            Some((_, volume)) => {
                images.insert(&volume.voxels, image).ok();
            }
            None => {
                let voxels = images.add(image);
                commands.spawn((
                    Name::new("plenoptic irradiance volume"),
                    PlenopticIrradianceVolume {
                        pack: id,
                        voxels: voxels.clone(),
                    },
                    LightProbe::default(),
                    IrradianceVolume {
                        voxels,
                        intensity: 1.0,
                        ..default()
                    },
                    Transform::from_translation(0.5 * (layout.min + layout.max))
                        .with_scale(layout.max - layout.min),
                ));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ambient_cube_of_a_uniform_and_a_one_sided_sky() {
        let face = 16;
        let uniform = vec![Vec3::splat(2.0); 6 * 256];
        for v in ambient_cube(face, &uniform) {
            assert!((v - Vec3::splat(2.0)).abs().max_element() < 0.01, "{v}");
        }
        // Light from above only (+Y hemisphere, radiance 1): the +Y side sees the cosine
        // integral π / π = 1, the −Y side nothing, a vertical side half of it (π/2 / π).
        let above: Vec<Vec3> = (0..6 * 256)
            .map(|i| Vec3::splat((texel_direction(face, i).y > 0.0) as u8 as f32))
            .collect();
        let c = ambient_cube(face, &above);
        assert!((c[2].x - 1.0).abs() < 0.02, "{:?}", c);
        assert!(c[3].x.abs() < 1e-6, "{:?}", c);
        assert!((c[0].x - 0.5).abs() < 0.02, "{:?}", c);
    }

    #[test]
    fn voxels_take_the_nearest_view_in_bevy_layout() {
        let res = UVec3::new(2, 1, 1);
        let side = |x: f32| [Vec3::splat(x); 6];
        let mut a = side(1.0);
        a[3] = Vec3::splat(0.5); // −Y of the view at x = 0
        let views = [Vec3::new(0.0, 0.0, 0.0), Vec3::new(2.0, 0.0, 0.0)];
        let nearest = nearest_views(Vec3::ZERO, Vec3::new(2.0, 1.0, 1.0), res, &views);
        assert_eq!(nearest, [0, 1]);
        let image = voxel_image(res, &nearest, &[a, side(3.0)]);
        assert_eq!(image.texture_descriptor.size.width, 2);
        assert_eq!(image.texture_descriptor.size.height, 2);
        assert_eq!(image.texture_descriptor.size.depth_or_array_layers, 3);
        let data = image.data.as_ref().unwrap();
        let at = |x: u32, t: u32, p: u32| {
            let i = ((p * 2 + t) * 2 + x) as usize * 8;
            half::f16::from_le_bytes([data[i], data[i + 1]]).to_f32()
        };
        // Voxel 0 (centre x = 0.5) takes view 0, voxel 1 (x = 1.5) view 1.
        assert_eq!(at(0, 0, 0), 1.0);
        assert_eq!(at(1, 0, 0), 3.0);
        // −Y of voxel 0: negative row (t = Ry = 1), Y slice (p = Rz = 1).
        assert_eq!(at(0, 1, 1), 0.5);
        assert_eq!(at(0, 0, 1), 1.0);
    }

    #[test]
    fn the_box_is_the_scene_or_the_views_grown() {
        let scene = (Vec3::ZERO, Vec3::new(4.0, 3.0, 5.0));
        assert_eq!(volume_box(scene, &[Vec3::ONE], 1.0), scene);
        let views = [Vec3::new(-1.0, 1.3, 1.0), Vec3::new(1.0, 1.3, 1.0)];
        // Views 2 m apart: grown by 8 m.
        let (min, max) = volume_box((Vec3::ZERO, Vec3::ZERO), &views, 2.0);
        assert!(
            (min - Vec3::new(-9.0, -6.7, -7.0)).abs().max_element() < 1e-5,
            "{min}"
        );
        assert!(
            (max - Vec3::new(9.0, 9.3, 9.0)).abs().max_element() < 1e-5,
            "{max}"
        );
        let (min, max) = volume_box((Vec3::ZERO, Vec3::ZERO), &[], f32::INFINITY);
        assert_eq!((min, max), (Vec3::splat(-2.0), Vec3::splat(2.0)));
    }

    #[test]
    fn resolution_follows_the_spacing() {
        assert_eq!(
            resolution(Vec3::new(4.0, 2.0, 1.0), 0.5),
            UVec3::new(8, 4, 2)
        );
        assert_eq!(
            resolution(Vec3::splat(100.0), 0.1),
            UVec3::splat(MAX_VOXELS)
        );
        assert_eq!(resolution(Vec3::ONE, 0.0), UVec3::splat(MAX_VOXELS));
    }
}
