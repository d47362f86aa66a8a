//! Tests of the (x, y, t) Delaunay complex: validity (exact empty-circumsphere check),
//! degenerate inputs, hull coverage, slicing and determinism.

use plenoptic_recon::delaunay3::{
    DelaunayError, SliceTriangle, Tetrahedralization, signed_volume, slice_at, tetrahedralize,
    validate,
};

/// Tiny deterministic PRNG (splitmix64).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn f(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
    fn point(&mut self, size: [f64; 3]) -> [f64; 3] {
        [self.f() * size[0], self.f() * size[1], self.f() * size[2]]
    }
}

fn box_corners(size: [f64; 3]) -> Vec<[f64; 3]> {
    (0..8)
        .map(|i| {
            [
                if i & 1 != 0 { size[0] } else { 0.0 },
                if i & 2 != 0 { size[1] } else { 0.0 },
                if i & 4 != 0 { size[2] } else { 0.0 },
            ]
        })
        .collect()
}

fn volume(tri: &Tetrahedralization, points: &[[f64; 3]]) -> f64 {
    tri.tets.iter().map(|&t| signed_volume(points, t)).sum()
}

fn check(points: &[[f64; 3]]) -> Tetrahedralization {
    let tri = tetrahedralize(points).expect("tetrahedralize");
    if let Err(e) = validate(&tri, points) {
        panic!("invalid tetrahedralization of {} points: {e}", points.len());
    }
    tri
}

#[test]
fn cube_corners_and_centre() {
    let mut points = box_corners([1.0; 3]);
    points.push([0.5; 3]);
    let tri = check(&points);
    // The centre sees the 12 triangles of the cube's faces.
    assert_eq!(tri.tets.len(), 12);
    assert!(tri.tets.iter().all(|t| t.contains(&8)));
    assert!((volume(&tri, &points) - 1.0).abs() < 1e-12);
    assert!(tri.skipped.is_empty());
}

#[test]
fn cube_corners_only_cospherical() {
    let points = box_corners([1.0; 3]);
    let tri = check(&points);
    assert!((volume(&tri, &points) - 1.0).abs() < 1e-12);
}

#[test]
fn random_points_are_delaunay() {
    for (n, seed) in [(200, 1), (700, 2), (2000, 3)] {
        let mut rng = Rng(seed);
        let points: Vec<[f64; 3]> = (0..n).map(|_| rng.point([2.0, 1.0, 0.5])).collect();
        let tri = check(&points);
        assert!(tri.tets.len() > 5 * n);
        for (t, nb) in tri.tets.iter().zip(&tri.neighbours) {
            assert_eq!(nb.len(), t.len());
        }
    }
}

#[test]
fn grid_points_highly_cospherical() {
    let mut points = Vec::new();
    for i in 0..6 {
        for j in 0..5 {
            for k in 0..4 {
                points.push([i as f64, j as f64 * 0.5, k as f64 * 2.0]);
            }
        }
    }
    let tri = check(&points);
    assert!((volume(&tri, &points) - 5.0 * 2.0 * 6.0).abs() < 1e-9);
}

#[test]
fn layered_samples_like_a_temporal_volume() {
    // Samples at discrete times, each layer with the square's corners: hull = unit cube.
    let mut rng = Rng(9);
    let mut points = Vec::new();
    for layer in 0..5 {
        let t = layer as f64 * 0.25;
        points.extend([[0.0, 0.0, t], [1.0, 0.0, t], [0.0, 1.0, t], [1.0, 1.0, t]]);
        for _ in 0..60 {
            points.push([rng.f(), rng.f(), t]);
        }
    }
    let tri = check(&points);
    assert!((volume(&tri, &points) - 1.0).abs() < 1e-9);
    let values: Vec<f64> = points
        .iter()
        .map(|p| p[0] - 2.0 * p[1] + 3.0 * p[2])
        .collect();
    for t in [0.0, 0.25, 0.3, 0.5, 0.999, 1.0] {
        let slice = tri.slice(&points, &values, t).unwrap();
        let area: f64 = slice.iter().map(SliceTriangle::area).sum();
        assert!((area - 1.0).abs() < 1e-9, "t = {t}: area {area}");
        for _ in 0..50 {
            let (x, y) = (rng.f(), rng.f());
            let v = interpolate(&slice, [x, y]).expect("inside the slice");
            assert!((v - (x - 2.0 * y + 3.0 * t)).abs() < 1e-9);
        }
    }
}

#[test]
fn duplicates_are_skipped() {
    let mut rng = Rng(4);
    let mut points: Vec<[f64; 3]> = (0..100).map(|_| rng.point([1.0; 3])).collect();
    points.push(points[3]);
    points.push(points[50]);
    points.push(points[3]);
    points.push([-0.0, 0.5, 0.5]);
    points.push([0.0, 0.5, 0.5]);
    let tri = check(&points);
    assert_eq!(tri.skipped, vec![100, 101, 102, 104]);
    assert_eq!(tri.duplicate_of, vec![3, 50, 3, 103]);
}

#[test]
fn bad_input_is_an_error() {
    let mut points = box_corners([1.0; 3]);
    points[5][1] = f64::NAN;
    assert!(matches!(
        tetrahedralize(&points),
        Err(DelaunayError::NonFinite { index: 5, .. })
    ));
    points[5][1] = 1.0;
    points[2][2] = f64::INFINITY;
    assert!(matches!(
        tetrahedralize(&points),
        Err(DelaunayError::NonFinite { index: 2, .. })
    ));

    let mut rng = Rng(5);
    let coplanar: Vec<[f64; 3]> = (0..50).map(|_| [rng.f(), rng.f(), 0.25]).collect();
    assert_eq!(tetrahedralize(&coplanar), Err(DelaunayError::Coplanar));
    // A tilted plane, exactly representable: z = x + 2y on dyadic coordinates.
    let tilted: Vec<[f64; 3]> = (0..50)
        .map(|i| {
            let (x, y) = ((i % 7) as f64 * 0.125, (i / 7) as f64 * 0.25);
            [x, y, x + 2.0 * y]
        })
        .collect();
    assert_eq!(tetrahedralize(&tilted), Err(DelaunayError::Coplanar));
    let collinear: Vec<[f64; 3]> = (0..10).map(|i| [i as f64, 2.0 * i as f64, 1.0]).collect();
    assert_eq!(tetrahedralize(&collinear), Err(DelaunayError::Collinear));
    let few = [[0.0; 3], [1.0, 0.0, 0.0], [0.0; 3], [0.0, 1.0, 0.0]];
    assert_eq!(
        tetrahedralize(&few),
        Err(DelaunayError::TooFewPoints { distinct: 3 })
    );
    assert_eq!(
        tetrahedralize(&[]),
        Err(DelaunayError::TooFewPoints { distinct: 0 })
    );

    let tri = tetrahedralize(&box_corners([1.0; 3])).unwrap();
    assert!(matches!(
        slice_at(&box_corners([1.0; 3]), &tri.tets, &[0.0f32; 3], 0.5),
        Err(DelaunayError::ValueCount { .. })
    ));
    assert!(matches!(
        slice_at(&box_corners([1.0; 3])[..4], &tri.tets, &[0.0f32; 8], 0.5),
        Err(DelaunayError::IndexOutOfRange { .. })
    ));
}

#[test]
fn volume_equals_box_volume() {
    let size = [3.0, 1.5, 0.75];
    let mut rng = Rng(6);
    let mut points = box_corners(size);
    points.extend((0..1500).map(|_| rng.point(size)));
    let tri = tetrahedralize(&points).unwrap();
    let v = volume(&tri, &points);
    let expect = size[0] * size[1] * size[2];
    assert!(((v - expect) / expect).abs() < 1e-9, "{v} vs {expect}");
    assert!(tri.tets.iter().all(|&t| signed_volume(&points, t) > 0.0));
}

/// Value of the slice at `xy`, by barycentric interpolation in the triangle containing it.
fn interpolate(slice: &[SliceTriangle<f64>], xy: [f64; 2]) -> Option<f64> {
    for tri in slice {
        let [a, b, c] = tri.xy;
        let d = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
        if d <= 0.0 {
            continue;
        }
        let l1 = ((xy[0] - a[0]) * (c[1] - a[1]) - (xy[1] - a[1]) * (c[0] - a[0])) / d;
        let l2 = ((b[0] - a[0]) * (xy[1] - a[1]) - (b[1] - a[1]) * (xy[0] - a[0])) / d;
        let l0 = 1.0 - l1 - l2;
        if l0 >= -1e-12 && l1 >= -1e-12 && l2 >= -1e-12 {
            return Some(l0 * tri.values[0] + l1 * tri.values[1] + l2 * tri.values[2]);
        }
    }
    None
}

#[test]
fn slices_interpolate_linear_functions_and_tile_the_section() {
    let size = [2.0, 1.0, 1.0];
    let mut rng = Rng(7);
    let mut points = box_corners(size);
    points.extend((0..800).map(|_| rng.point(size)));
    let tri = check(&points);
    let f = |p: [f64; 3]| 0.7 * p[0] - 1.3 * p[1] + 2.1 * p[2] + 0.4;
    let values: Vec<f64> = points.iter().map(|&p| f(p)).collect();
    let vec_values: Vec<[f32; 2]> = values.iter().map(|&v| [v as f32, 1.0]).collect();
    for t in [0.0, 0.1, 0.5, 0.77, points[20][2], 1.0] {
        let slice = slice_at(&points, &tri.tets, &values, t).unwrap();
        let area: f64 = slice.iter().map(SliceTriangle::area).sum();
        assert!((area - 2.0).abs() < 1e-9, "t = {t}: area {area}");
        assert!(slice.iter().all(|s| s.area() >= 0.0));
        for _ in 0..100 {
            let xy = [rng.f() * size[0], rng.f() * size[1]];
            let v = interpolate(&slice, xy).expect("inside the hull");
            assert!((v - f([xy[0], xy[1], t])).abs() < 1e-9, "t = {t}");
        }
        // Array values interpolate too.
        let vs = slice_at(&points, &tri.tets, &vec_values, t).unwrap();
        assert_eq!(vs.len(), slice.len());
        assert!(vs.iter().all(|s| s.values.iter().all(|v| v[1] == 1.0)));
    }
    assert!(
        slice_at(&points, &tri.tets, &values, 1.5)
            .unwrap()
            .is_empty()
    );
    assert!(
        slice_at(&points, &tri.tets, &values, -0.1)
            .unwrap()
            .is_empty()
    );
}

#[test]
fn deterministic() {
    let mut rng = Rng(8);
    let points: Vec<[f64; 3]> = (0..3000).map(|_| rng.point([1.0, 1.0, 1.0])).collect();
    let a = tetrahedralize(&points).unwrap();
    let b = tetrahedralize(&points).unwrap();
    assert_eq!(a, b);
}

#[test]
fn larger_input_is_consistent() {
    // 20k points: too many for the O(n·m) check, so check hull volume and adjacency only.
    let mut rng = Rng(10);
    let mut points = box_corners([1.0; 3]);
    points.extend((0..20_000).map(|_| rng.point([1.0; 3])));
    let tri = tetrahedralize(&points).unwrap();
    assert!((volume(&tri, &points) - 1.0).abs() < 1e-9);
    for (t, nb) in tri.neighbours.iter().enumerate() {
        for (i, &n) in nb.iter().enumerate() {
            if n != u32::MAX {
                let back = tri.neighbours[n as usize];
                assert!(back.contains(&(t as u32)));
                assert!(!tri.tets[n as usize].contains(&tri.tets[t][i]));
            }
        }
    }
}

#[test]
fn all_points_exactly_cospherical() {
    // Every integer point with x² + y² + z² = 50, plus the centre: maximal degeneracy.
    let mut points = Vec::new();
    for x in -7i32..=7 {
        for y in -7i32..=7 {
            for z in -7i32..=7 {
                if x * x + y * y + z * z == 50 {
                    points.push([x as f64, y as f64, z as f64]);
                }
            }
        }
    }
    assert!(points.len() > 50);
    check(&points);
    points.push([0.0; 3]);
    check(&points);
}

#[test]
fn far_from_origin_and_nearly_degenerate() {
    // Tiny extents far from the origin: only exact predicates get this right.
    let mut rng = Rng(13);
    let points: Vec<[f64; 3]> = (0..400)
        .map(|_| {
            let p = rng.point([1e-3; 3]);
            [1e6 + p[0], -3e5 + p[1], 7e4 + p[2]]
        })
        .collect();
    check(&points);
    // A grid jittered by a few ulps.
    let mut points = Vec::new();
    for i in 0..7 {
        for j in 0..7 {
            for k in 0..7 {
                let mut c = |v: i32| v as f64 + (rng.f() - 0.5) * 1e-14;
                points.push([c(i), c(j), c(k)]);
            }
        }
    }
    check(&points);
}

#[test]
fn validate_rejects_broken_complexes() {
    let mut rng = Rng(14);
    let mut points = box_corners([1.0; 3]);
    points.extend((0..60).map(|_| rng.point([1.0; 3])));
    let good = check(&points);

    let mut flipped = good.clone();
    flipped.tets[3].swap(0, 1);
    assert!(validate(&flipped, &points).is_err());

    let mut missing = good.clone();
    missing.tets.pop();
    missing.neighbours.clear();
    assert!(validate(&missing, &points).is_err());

    let mut bad_neighbours = good.clone();
    bad_neighbours.neighbours[0] = bad_neighbours.neighbours[1];
    assert!(validate(&bad_neighbours, &points).is_err());

    // A valid but non-Delaunay complex: a flat bipyramid as two tets sharing the big face
    // (the Delaunay one is three tets around the short apex edge).
    let bipyramid = [
        [10.0, 0.0, 0.0],
        [-5.0, 8.0, 0.0],
        [-5.0, -8.0, 0.0],
        [0.0, 0.0, 1.0],
        [0.0, 0.0, -1.0],
    ];
    let orient = |mut t: [u32; 4]| {
        if signed_volume(&bipyramid, t) < 0.0 {
            t.swap(0, 1);
        }
        t
    };
    let two = Tetrahedralization {
        tets: vec![orient([0, 1, 2, 3]), orient([0, 1, 2, 4])],
        ..Default::default()
    };
    let err = validate(&two, &bipyramid).unwrap_err();
    assert!(err.contains("circumsphere"), "{err}");
    assert_eq!(check(&bipyramid).tets.len(), 3);
}
