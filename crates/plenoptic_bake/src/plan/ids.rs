//! Id-images for the coherence tests: cubes around a point, orthographic views along a
//! directional light (the sun of a sun study follows its track) and along a changing sky's
//! mean direction, and the fitness of a set of id-images (thesis §6.5.2: the fraction of
//! pixels whose object id is the same in every image).

use glam::Vec3;
use plenoptic_scene::{LightKind, ObjectId};
use plenoptic_trace::{CubeCamera, PlacedScene, Ray};
use rayon::prelude::*;

/// Object ids of the six faces of a cube camera at `position`, face after face in KTX2 layer
/// order, `face_size`² pixels each.
pub fn cube_ids(placed: &PlacedScene<'_>, position: Vec3, face_size: u32) -> Vec<ObjectId> {
    let Ok(cube) = CubeCamera::new(position, face_size) else {
        return Vec::new();
    };
    let mut out = Vec::with_capacity(6 * (face_size * face_size) as usize);
    for face in cube.faces() {
        out.extend(placed.id_image(&face).pixels);
    }
    out
}

/// Object ids seen along parallel rays in direction `dir`, from a `size`² grid on a plane
/// covering the sphere (`centre`, `radius`): the id-image of a directional light.
pub fn ortho_ids(
    placed: &PlacedScene<'_>,
    dir: Vec3,
    centre: Vec3,
    radius: f32,
    size: u32,
) -> Vec<ObjectId> {
    let dir = dir.normalize_or(Vec3::NEG_Y);
    let (u, v) = dir.any_orthonormal_pair();
    let origin = centre - dir * (2.0 * radius + 1.0);
    let n = size.max(1);
    (0..n * n)
        .into_par_iter()
        .map(|i| {
            let (x, y) = (i % n, i / n);
            let s = (2.0 * (x as f32 + 0.5) / n as f32 - 1.0) * radius;
            let t = (2.0 * (y as f32 + 0.5) / n as f32 - 1.0) * radius;
            let ray = Ray::new(origin + u * s + v * t, dir);
            placed
                .intersect(&ray)
                .map_or(plenoptic_scene::NO_OBJECT, |h| h.object)
        })
        .collect()
}

/// Largest number of points sampled on emissive surfaces for their id-images.
pub const EMISSIVE_PROBES: usize = 4;

/// The id-images "from every light" at one time: a cube at each point and spot light, an
/// orthographic image along each directional light over the sphere (`centre`, `radius`), and a
/// cube just in front of up to [`EMISSIVE_PROBES`] evenly spread emissive triangles. A
/// runtime sun keeps its image: its direct light is not stored, but the indirect light it
/// gives changes as what it sees does.
pub fn light_ids(
    placed: &PlacedScene<'_>,
    centre: Vec3,
    radius: f32,
    size: u32,
) -> Vec<Vec<ObjectId>> {
    let scene = placed.scene();
    let t = placed.time();
    let mut out = Vec::new();
    for (i, light) in scene.lights.iter().enumerate() {
        let p = scene.placed_light(i, t);
        out.push(match light.kind {
            LightKind::Point | LightKind::Spot { .. } => cube_ids(placed, p.position, size),
            LightKind::Directional => ortho_ids(placed, p.direction, centre, radius, size),
        });
    }
    if scene.environment_is_animated() {
        // A sky that changes (it follows a moving sun) is a light too: its id-image looks
        // along the direction its light arrives from on average.
        let towards = sky_direction(placed);
        if towards != Vec3::ZERO {
            out.push(ortho_ids(placed, -towards, centre, radius, size));
        }
    }
    let emissive = placed.lights().emissive();
    let probes = emissive.len().min(EMISSIVE_PROBES);
    for k in 0..probes {
        let tri = &emissive[k * emissive.len() / probes];
        let c = tri.p0 + (tri.e1 + tri.e2) / 3.0;
        let offset = 1e-3 * (1.0 + c.abs().max_element());
        out.push(cube_ids(placed, c + tri.normal * offset, size));
    }
    out
}

/// The luminance-weighted mean direction towards the environment over the upper hemisphere
/// (zero for a black sky), on a 32 × 8 grid of directions.
pub fn sky_direction(placed: &PlacedScene<'_>) -> Vec3 {
    let env = placed.lights().environment();
    let mut sum = Vec3::ZERO;
    for i in 0..8 {
        let theta = (i as f32 + 0.5) / 8.0 * std::f32::consts::FRAC_PI_2;
        for j in 0..32 {
            let phi = (j as f32 + 0.5) / 32.0 * std::f32::consts::TAU;
            let d = Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            );
            let l = plenoptic_trace::image::luminance(env.radiance(d));
            sum += d * l * theta.sin();
        }
    }
    sum.normalize_or_zero()
}

/// Fraction of pixels whose id is the same in every image (1 for no images or no pixels).
/// Images of different sizes compare over the shortest.
pub fn fitness(images: &[&[ObjectId]]) -> f64 {
    let Some(first) = images.first() else {
        return 1.0;
    };
    let n = images.iter().map(|i| i.len()).min().unwrap_or(0);
    if n == 0 {
        return 1.0;
    }
    let same = (0..n)
        .filter(|&p| images[1..].iter().all(|img| img[p] == first[p]))
        .count();
    same as f64 / n as f64
}

/// The smallest fitness over paired image lists (`a[i]` against `b[i]`): the light test, where
/// every light must agree.
pub fn min_fitness(a: &[Vec<ObjectId>], b: &[Vec<ObjectId>]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| fitness(&[x, y]))
        .fold(1.0, f64::min)
}
