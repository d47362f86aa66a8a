//! Throughput of the (x, y, t) Delaunay complex (`plenoptic_recon::delaunay3::tetrahedralize`),
//! in points per second: 10k and 50k uniform random points (a temporal volume holds up to ~50k
//! samples), and 10k points on a jittered grid (near-degenerate, like regularly spaced samples).
//! Also slicing a 50k-point complex at one time.
//!
//! `cargo bench --no-default-features --bench delaunay`

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use plenoptic_recon::delaunay3::{slice_at, tetrahedralize};

/// Tiny deterministic PRNG (splitmix64), uniform in [0, 1).
fn uniform(state: &mut u64) -> f64 {
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
}

fn random_points(n: usize, seed: u64) -> Vec<[f64; 3]> {
    let mut s = seed;
    (0..n)
        .map(|_| [uniform(&mut s), uniform(&mut s), uniform(&mut s)])
        .collect()
}

/// A 22 × 22 × 21 grid (10 164 points) with a 1 % jitter.
fn jittered_grid() -> Vec<[f64; 3]> {
    let mut s = 77;
    let mut points = Vec::new();
    for i in 0..22 {
        for j in 0..22 {
            for k in 0..21 {
                let mut c = |v: usize| v as f64 + 0.01 * (uniform(&mut s) - 0.5);
                points.push([c(i), c(j), c(k)]);
            }
        }
    }
    points
}

fn tetrahedralize_bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("tetrahedralize");
    g.sample_size(10);
    let cases = [
        ("random_10k", random_points(10_000, 1)),
        ("random_50k", random_points(50_000, 2)),
        ("jittered_grid_10k", jittered_grid()),
    ];
    for (name, points) in &cases {
        let tri = tetrahedralize(points).expect("tetrahedralize");
        println!(
            "{name}: {} points -> {} tetrahedra",
            points.len(),
            tri.tets.len()
        );
        g.throughput(Throughput::Elements(points.len() as u64));
        g.bench_function(*name, |b| {
            b.iter(|| tetrahedralize(black_box(points)).unwrap())
        });
    }
    g.finish();

    let points = &cases[1].1;
    let tri = tetrahedralize(points).unwrap();
    let values: Vec<[f32; 3]> = points
        .iter()
        .map(|p| [p[0] as f32, p[1] as f32, 1.0])
        .collect();
    let mut g = c.benchmark_group("slice");
    g.throughput(Throughput::Elements(tri.tets.len() as u64));
    g.bench_function("slice_50k", |b| {
        b.iter(|| slice_at(points, &tri.tets, &values, black_box(0.5)).unwrap())
    });
    g.finish();
}

criterion_group!(benches, tetrahedralize_bench);
criterion_main!(benches);
