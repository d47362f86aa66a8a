//! Analytic meshes for the builder: boxes, planes and UV spheres, with normals and UVs.
//!
//! All shapes are centred on the origin, wind counter-clockwise seen from outside (glTF's
//! front faces) and leave tangents empty (the importer computes them where a normal map
//! needs them).

use std::f32::consts::{PI, TAU};

use glam::{Vec2, Vec3};

use crate::model::Mesh;

/// An axis-aligned box of extent `size`: 24 vertices (flat-shaded faces), 12 triangles.
pub fn cuboid(size: Vec3) -> Mesh {
    let half = size * 0.5;
    let faces = [
        (Vec3::X, Vec3::NEG_Z),
        (Vec3::NEG_X, Vec3::Z),
        (Vec3::Y, Vec3::X),
        (Vec3::NEG_Y, Vec3::X),
        (Vec3::Z, Vec3::X),
        (Vec3::NEG_Z, Vec3::NEG_X),
    ];
    let mut mesh = Mesh::default();
    for (n, u) in faces {
        let v = n.cross(u);
        let base = mesh.positions.len() as u32;
        for (a, b) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
            mesh.positions.push((n + u * a + v * b) * half);
            mesh.normals.push(n);
            mesh.uvs.push(Vec2::new((a + 1.0) * 0.5, (1.0 - b) * 0.5));
        }
        mesh.triangles.push([base, base + 1, base + 2]);
        mesh.triangles.push([base, base + 2, base + 3]);
    }
    mesh
}

/// A plane in the x-z plane facing +Y, `size.x` by `size.y` (along z), cut into
/// `subdivisions` × `subdivisions` cells of two triangles (at least one cell).
pub fn plane(size: Vec2, subdivisions: u32) -> Mesh {
    let s = subdivisions.max(1);
    let mut mesh = Mesh::default();
    for j in 0..=s {
        for i in 0..=s {
            let (fu, fv) = (i as f32 / s as f32, j as f32 / s as f32);
            mesh.positions
                .push(Vec3::new((fu - 0.5) * size.x, 0.0, (fv - 0.5) * size.y));
            mesh.normals.push(Vec3::Y);
            mesh.uvs.push(Vec2::new(fu, fv));
        }
    }
    let row = s + 1;
    for j in 0..s {
        for i in 0..s {
            let p00 = j * row + i;
            let (p10, p01, p11) = (p00 + 1, p00 + row, p00 + row + 1);
            mesh.triangles.push([p00, p01, p10]);
            mesh.triangles.push([p10, p01, p11]);
        }
    }
    mesh
}

/// A UV sphere of `radius` with `segments` around the equator (at least 3) and
/// `segments / 2` rings (at least 2): 2·segments·(rings − 1) triangles, so 320 segments give
/// 101,760 triangles.
pub fn uv_sphere(radius: f32, segments: u32) -> Mesh {
    uv_sphere_with_rings(radius, segments, segments / 2)
}

/// A UV sphere of `radius` with `segments` around the equator (at least 3) and `rings` from
/// pole to pole (at least 2): 2·segments·(rings − 1) triangles. Texture `u` runs around from
/// +X towards +Z, `v` from the north (+Y) pole to the south.
pub fn uv_sphere_with_rings(radius: f32, segments: u32, rings: u32) -> Mesh {
    let (segments, rings) = (segments.max(3), rings.max(2));
    let mut mesh = Mesh::default();
    for r in 0..=rings {
        let theta = PI * r as f32 / rings as f32;
        for s in 0..=segments {
            let phi = TAU * s as f32 / segments as f32;
            let n = Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            );
            mesh.positions.push(n * radius);
            mesh.normals.push(n);
            mesh.uvs.push(Vec2::new(
                s as f32 / segments as f32,
                r as f32 / rings as f32,
            ));
        }
    }
    let row = segments + 1;
    for r in 0..rings {
        for s in 0..segments {
            let a = r * row + s;
            let (b, c, d) = (a + 1, a + row, a + row + 1);
            if r != 0 {
                mesh.triangles.push([a, b, c]);
            }
            if r != rings - 1 {
                mesh.triangles.push([b, d, c]);
            }
        }
    }
    mesh
}

#[cfg(test)]
mod tests {
    use super::*;

    fn outward(mesh: &Mesh) {
        for t in &mesh.triangles {
            let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
            let n = (b - a).cross(c - a);
            assert!(n.length() > 0.0, "degenerate triangle");
            let centre = (a + b + c) / 3.0;
            let expect = mesh.normals[t[0] as usize];
            assert!(n.dot(expect) > 0.0 || n.dot(centre) > 0.0);
        }
    }

    #[test]
    fn shapes_wind_outward() {
        outward(&cuboid(Vec3::new(1.0, 2.0, 3.0)));
        outward(&plane(Vec2::new(2.0, 3.0), 4));
        let sphere = uv_sphere(1.0, 16);
        outward(&sphere);
        assert_eq!(sphere.triangles.len(), 2 * 16 * 7);
        assert_eq!(cuboid(Vec3::ONE).triangles.len(), 12);
        assert_eq!(plane(Vec2::ONE, 3).triangles.len(), 18);
    }
}
