//! Tests of [`super`]: the branch-free texel addressing and powers against the reference.

use super::*;

#[test]
fn branch_free_texel_matches_the_reference() {
    let mut s = 987654321u32;
    let mut rnd = || {
        s ^= s << 13;
        s ^= s >> 17;
        s ^= s << 5;
        s as f32 / u32::MAX as f32 * 2.0 - 1.0
    };
    let mut dirs: Vec<Vec3> = (0..20000).map(|_| Vec3::new(rnd(), rnd(), rnd())).collect();
    dirs.extend([
        Vec3::ZERO,
        Vec3::X,
        -Vec3::Y,
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(-1.0, 1.0, 1.0),
        Vec3::new(0.0, -1.0, -1.0),
        Vec3::new(f32::NAN, 1.0, 0.0),
        Vec3::new(f32::INFINITY, 1.0, 0.0),
    ]);
    for d in dirs {
        for n in [1u32, 16, 128, 1182, 1183, 2048] {
            let (lanes, taps, fx, fy) = CubeLanes::new(n).texels(
                Vec4::splat(d.x),
                Vec4::splat(d.y),
                Vec4::splat(d.z),
                true,
            );
            assert_eq!(lanes[0] as usize, cube::direction_to_texel(n, d), "{d} {n}");
            // Inside a face, the footprint is the scalar filter's.
            if taps[0] != NO_TEXEL {
                let reference = sample::bilinear_taps(n, d);
                let (fx, fy) = (fx.x, fy.x);
                let i = taps[0] as usize;
                let n = n as usize;
                let weights = [
                    (i, (1.0 - fx) * (1.0 - fy)),
                    (i + 1, fx * (1.0 - fy)),
                    (i + n, (1.0 - fx) * fy),
                    (i + n + 1, fx * fy),
                ];
                for ((a, wa), (b, wb)) in weights.into_iter().zip(reference) {
                    assert!(a == b || wa.abs() < 1e-6, "{d} {n}: {a} {b}");
                    assert!((wa - wb).abs() < 1e-5, "{d} {n}: {wa} {wb}");
                }
            }
        }
    }
    // The Phong lobe's power by repeated squaring equals `powi` up to rounding: `powi` is
    // an LLVM intrinsic whose multiplication order differs between debug and release
    // builds, so the two agree within a few ulp (one rounding per multiplication; the
    // floor covers 1e-3^13, a subnormal), not bit for bit.
    for c in [0.0f32, 1e-3, 0.3, 0.77, 1.0] {
        for k in [1, 2, 3, 8, 13] {
            let (got, want) = (powi4(Vec4::splat(c), k).x, c.powi(k as i32));
            let tolerance = 2.0 * k as f32 * f32::EPSILON * want.abs().max(f32::MIN_POSITIVE);
            assert!(
                (got - want).abs() <= tolerance,
                "{c}^{k}: {got} vs powi {want}"
            );
        }
    }
    assert_eq!(
        powi4(Vec4::splat(0.5), 3).x,
        0.125,
        "exact where no rounding occurs"
    );
}

/// A floor seen at a grazing angle from a base view: the next texel along the floor is the
/// same surface although its distance differs by far more than the tolerance; a texel of
/// the same object 0.5 m behind the floor's plane is not; without normals only the distance
/// counts.
#[test]
fn a_grazing_surface_keeps_its_neighbouring_texels() {
    let face = 32u32;
    let count = 6 * (face * face) as usize;
    // The floor y = −0.3 below a base view at the origin, seen along +z.
    let floor_at = |j: usize| {
        let dir = cube::texel_direction(face, j);
        (dir.y < -1e-3).then(|| -0.3 / dir.y)
    };
    let texels: Vec<Texel> = (0..count)
        .map(|j| Texel {
            radiance: Vec4::ONE,
            id: 1,
            distance: floor_at(j).unwrap_or(100.0),
        })
        .collect();
    let normals = vec![Vec3::Y; count];
    let key = |normal| FastKey {
        base: Vec3::ZERO,
        weight: 1.0,
        face,
        texels: &texels,
        second: None,
        normal,
        motion: &[],
        reuse: Vec::new(),
    };
    let (with, without) = (key(Some(normals.as_slice())), key(None));
    // A point on the floor 6 m ahead: its texel and the next one towards the view.
    let d = Vec3::new(0.0, -0.3, 6.0);
    let t = cube::direction_to_texel(face, d);
    let next = t + face as usize; // one row down on the +z face: nearer along the floor
    let l = d.length();
    let (near, far) = (texels[next].distance, texels[t].distance);
    assert!((near - far).abs() > 0.03 * l, "{near} {far}: not grazing");
    assert!(same_surface(
        &with,
        &texels[next],
        next,
        (1, Vec3::ZERO),
        d,
        l,
        0.03
    ));
    assert!(!same_surface(
        &without,
        &texels[next],
        next,
        (1, Vec3::ZERO),
        d,
        l,
        0.03
    ));
    // Another object, and the same object half a metre below the floor's plane.
    assert!(!same_surface(
        &with,
        &texels[next],
        next,
        (2, Vec3::ZERO),
        d,
        l,
        0.03
    ));
    let behind = Texel {
        distance: near + 0.5 / (cube::texel_direction(face, next).y.abs()),
        ..texels[next]
    };
    assert!(!same_surface(
        &with,
        &behind,
        next,
        (1, Vec3::ZERO),
        d,
        l,
        0.03
    ));
    // The face test: the floor's texel serves a pixel whose surface faces up (the floor),
    // not one facing sideways (a wall's reveal at the floor's distance) or down (the floor's
    // underside, the same triangles seen from below); without the key's normals, or without
    // the pixel's, every face passes.
    let face = |np: Vec3, key: &FastKey<'_>| same_surface(key, &texels[t], t, (1, np), d, l, 0.03);
    assert!(face(Vec3::Y, &with));
    assert!(face(Vec3::new(0.0, 0.8, 0.6), &with));
    assert!(!face(Vec3::X, &with));
    assert!(!face(-Vec3::Y, &with));
    assert!(same_face(&without, t, -Vec3::Y));
    assert!(face(Vec3::ZERO, &with));
    // A single point's lookup (a reflected ray's hit) answers on the floor and not for
    // another object or a point half a metre above it.
    let (c, second) = at_point(&with, d, 1, 0.03).unwrap();
    assert!((c - Vec3::ONE).abs().max_element() < 1e-6 && second.is_none());
    assert!(at_point(&with, d, 2, 0.03).is_none());
    assert!(at_point(&with, d + Vec3::Y * 0.5, 1, 0.03).is_none());
}
