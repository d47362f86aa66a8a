//! Pack write and read+decode throughput, in MB/s of *uncompressed* payload, on a synthetic but
//! realistic pack: a procedural room (walls, floor, ceiling, a table in front, a bright window,
//! smooth light falloff) seen from 4 base views × 3 time keys at face size 128, plus 4 temporal
//! volume blocks of 20 000 samples with connectivity. Prints the compression ratio once.
//!
//! `pack_io/zstd_decode_level_{9,15}`: zstd alone decoding the fixture's radiance, lighting
//! and distance texels with 5 % noise, rounded as the baker stores them
//! (`plenoptic_bake::quantise`), compressed at the writer's level (15) and at level 9, a
//! faster one, measured in the same run; prints the sizes' ratio. With `PLENOPTIC_BENCH_PACK`
//! naming a baked pack, every fifth of its radiance, lighting, non-diffuse and distance cubes
//! instead (the texels as that bake stored them).
//!
//! `cargo bench --no-default-features --bench pack_io`

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use plenoptic_pack::glam::Vec3;
use plenoptic_pack::*;

const FACE: u32 = 128;
const VIEWS: u32 = 4;
const KEYS: u32 = 3;
const BLOCK_SAMPLES: usize = 20_000;

fn room(view: Vec3, phase: f32) -> RangeImage {
    let half = Vec3::new(3.0, 1.4, 4.0);
    let n = FACE;
    let count = 6 * (n as usize).pow(2);
    let mut img = RangeImage::new(n);
    for i in 0..count {
        let d = cube::texel_direction(n, i);
        // Box room around the origin, seen from `view`.
        let lo = (-half - view) / d;
        let hi = (half - view) / d;
        let exit = lo.max(hi);
        let t = exit.min_element();
        let axis = if exit.x == t {
            0
        } else if exit.y == t {
            1
        } else {
            2
        };
        let mut normal = Vec3::ZERO;
        normal[axis] = -d[axis].signum();
        let mut id = 1 + axis as u32 * 2 + (d[axis] > 0.0) as u32;
        let mut dist = t;
        let p = view + d * t;
        // A table top (depth edge) at z = 1.5, and a pillar.
        let tz = (1.5 - view.z) / d.z;
        let q = view + d * tz;
        if tz > 0.0 && tz < dist && q.x.abs() < 0.8 && q.y < -0.3 && q.y > -1.0 {
            dist = tz;
            id = 9;
            normal = -Vec3::Z;
        }
        let tx = (-2.0 - view.x) / d.x;
        let q = view + d * tx;
        if tx > 0.0 && tx < dist && (q.z + 1.0).abs() < 0.3 {
            dist = tx;
            id = 10;
            normal = Vec3::X;
        }
        let hit = view + d * dist;
        let light = Vec3::new(0.5 * phase.sin(), 1.2, 0.5 * phase.cos());
        let to_light = light - hit;
        let lambert = normal.dot(to_light.normalize()).max(0.0);
        let falloff = 3.0 * lambert / (0.2 + to_light.length_squared()) + 0.05;
        let albedo = Vec3::new(0.5 + 0.04 * id as f32, 0.5, 0.55 - 0.03 * id as f32);
        let mut r = albedo * falloff;
        let (mut l, mut e) = (Vec3::splat(falloff), Vec3::ZERO);
        if id != 9 && id != 10 && axis == 0 && d.x > 0.0 && p.y.abs() < 0.5 && p.z.abs() < 1.0 {
            r = Vec3::new(40.0, 38.0, 35.0) * (1.0 + 0.1 * phase);
            (l, e) = (Vec3::ZERO, r);
            id = 20;
        }
        img.radiance.texels[i] = r;
        img.lighting.texels[i] = l;
        img.non_diffuse.texels[i] = e;
        img.distance.texels[i] = dist;
        img.object_id.texels[i] = id;
        img.normal.texels[i] = normal;
    }
    img
}

struct Fixture {
    manifest: Manifest,
    images: Vec<(u32, u32, RangeImage)>,
    blocks: Vec<(u32, Vec<VolumeSample>, Vec<[u32; 4]>)>,
}

fn fixture() -> Fixture {
    let mut manifest = Manifest::new(
        TimeRange {
            start: 0.0,
            end: 2.0,
        },
        0.5,
    );
    let mut images = Vec::new();
    let mut blocks = Vec::new();
    for v in 0..VIEWS {
        let pos = Vec3::new(v as f32 * 0.4 - 0.6, 0.2, -0.5);
        manifest.base_views.push(BaseView {
            id: v,
            position: pos,
            time_keys: (0..KEYS).map(|k| k as f32).collect(),
        });
        for k in 0..KEYS {
            images.push((v, k, room(pos, k as f32)));
        }
        // Volume samples: take the range image's values along jittered directions and times.
        let img = &images.last().unwrap().2;
        let mut state = 0x2545_f491_4f6c_dd1d_u64 ^ v as u64;
        let mut rnd = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        let samples: Vec<VolumeSample> = (0..BLOCK_SAMPLES)
            .map(|_| {
                let i = (rnd() * (6 * FACE * FACE) as f32) as usize % (6 * FACE * FACE) as usize;
                VolumeSample {
                    direction: cube::texel_direction(FACE, i),
                    t: rnd() * 0.5,
                    radiance: img.radiance.texels[i],
                    lighting: img.lighting.texels[i],
                    non_diffuse: img.non_diffuse.texels[i],
                    distance: img.distance.texels[i],
                    normal: img.normal.texels[i],
                    object_id: img.object_id.texels[i],
                    radius: 0.01,
                }
            })
            .collect();
        let tets = (0..BLOCK_SAMPLES as u32 - 3)
            .step_by(2)
            .map(|i| [i, i + 1, i + 2, i + 3])
            .collect();
        blocks.push((v, samples, tets));
    }
    Fixture {
        manifest,
        images,
        blocks,
    }
}

fn write(f: &Fixture, path: &std::path::Path) -> u64 {
    let mut w = PackWriter::create(path).unwrap();
    for (v, k, img) in &f.images {
        w.add_range_image(*v, *k, img, CubeFormats::default())
            .unwrap();
    }
    for (v, samples, tets) in &f.blocks {
        w.add_volume_block(*v, 0, (0.0, 0.5), samples, Some(tets))
            .unwrap();
    }
    let uncompressed = w.entries().iter().map(|e| e.uncompressed_length).sum();
    w.finish(&f.manifest).unwrap();
    uncompressed
}

fn read_all(path: &std::path::Path) -> usize {
    let r = PackReader::open(path).unwrap();
    (0..r.entries().len())
        .map(|i| r.chunk(i).is_ok() as usize)
        .sum()
}

fn pack_io(c: &mut Criterion) {
    let f = fixture();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bench.pack");
    let uncompressed = write(&f, &path);
    let stored = std::fs::metadata(&path).unwrap().len();
    let r = PackReader::open(&path).unwrap();
    let by_kind = |kind: ChunkKind| {
        r.entries()
            .iter()
            .filter(|e| e.kind == kind)
            .fold((0u64, 0u64), |a, e| {
                (a.0 + e.uncompressed_length, a.1 + e.length)
            })
    };
    println!(
        "pack_io: {} chunks, {:.2} MB uncompressed, {:.2} MB on disk, compression ratio {:.2}:1",
        r.entries().len(),
        uncompressed as f64 / 1e6,
        stored as f64 / 1e6,
        uncompressed as f64 / stored as f64
    );
    for kind in [
        ChunkKind::RadianceCube,
        ChunkKind::DistanceCube,
        ChunkKind::ObjectIdCube,
        ChunkKind::NormalCube,
        ChunkKind::VolumeBlock,
        ChunkKind::VolumeConnectivity,
    ] {
        let (u, s) = by_kind(kind);
        println!("pack_io:   {kind:?}: ratio {:.2}:1", u as f64 / s as f64);
    }

    let mut g = c.benchmark_group("pack_io");
    g.throughput(Throughput::Bytes(uncompressed));
    g.sample_size(10);
    let out = dir.path().join("bench-write.pack");
    g.bench_function("write", |b| b.iter(|| black_box(write(&f, &out))));
    g.bench_function("read_decode", |b| b.iter(|| black_box(read_all(&path))));
    g.finish();
    zstd_levels(c, &f);
}

/// The texel bytes of every cube of the fixture with a bake's noise, as the baker stores them.
fn noisy_texels(f: &Fixture) -> Vec<Vec<u8>> {
    use plenoptic_bake::quantise::{coarse_distance, coarsen_colour};
    let mut state = 0x9e37_79b9_7f4a_7c15_u64;
    let mut noise = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        1.0 + 0.1 * ((state >> 40) as f32 / (1u64 << 24) as f32 - 0.5)
    };
    let mut out = Vec::new();
    for (_, _, img) in &f.images {
        for cube in [&img.radiance, &img.lighting] {
            let bytes = cube
                .texels
                .iter()
                .flat_map(|&c| cube::rgb9e5_pack(coarsen_colour(c * noise())).to_le_bytes());
            out.push(bytes.collect());
        }
        let d = img.distance.texels.iter();
        out.push(d.flat_map(|&d| coarse_distance(d).to_le_bytes()).collect());
    }
    out
}

/// Every fifth radiance, lighting, non-diffuse and distance cube of the pack at `path`, as
/// texel bytes.
fn pack_texels(path: &str) -> Vec<Vec<u8>> {
    let r = PackReader::open(path).unwrap();
    let colour = |c: RadianceCube| -> Vec<u8> {
        c.texels
            .iter()
            .flat_map(|&c| cube::rgb9e5_pack(c).to_le_bytes())
            .collect()
    };
    r.entries()
        .iter()
        .filter(|e| {
            matches!(
                e.kind,
                ChunkKind::RadianceCube
                    | ChunkKind::LightingCube
                    | ChunkKind::NonDiffuseCube
                    | ChunkKind::DistanceCube
            )
        })
        .step_by(5)
        .map(|e| {
            let (v, k) = (e.base_view, e.key);
            match e.kind {
                ChunkKind::DistanceCube => (r.distance(v, k).unwrap().texels.iter())
                    .flat_map(|d| d.to_le_bytes())
                    .collect(),
                ChunkKind::RadianceCube => colour(r.radiance(v, k).unwrap()),
                ChunkKind::LightingCube => colour(r.lighting(v, k).unwrap()),
                _ => colour(r.non_diffuse(v, k).unwrap()),
            }
        })
        .collect()
}

/// zstd decoding at the writer's level against level 9 (see the module doc).
fn zstd_levels(c: &mut Criterion, f: &Fixture) {
    let raw = match std::env::var("PLENOPTIC_BENCH_PACK") {
        Ok(path) => pack_texels(&path),
        Err(_) => noisy_texels(f),
    };
    let total: usize = raw.iter().map(Vec::len).sum();
    let at = |level| -> Vec<Vec<u8>> {
        raw.iter()
            .map(|b| zstd::bulk::compress(b, level).unwrap())
            .collect()
    };
    let levels = [(9, at(9)), (15, at(15))];
    let size = |frames: &[Vec<u8>]| frames.iter().map(Vec::len).sum::<usize>() as f64;
    println!(
        "pack_io: zstd level 15 stores {:.3} of level 9's bytes of these texels",
        size(&levels[1].1) / size(&levels[0].1)
    );
    let mut g = c.benchmark_group("pack_io");
    g.throughput(Throughput::Bytes(total as u64));
    for (level, frames) in &levels {
        g.bench_function(format!("zstd_decode_level_{level}"), |b| {
            b.iter(|| {
                for (frame, bytes) in frames.iter().zip(&raw) {
                    black_box(zstd::bulk::decompress(frame, bytes.len()).unwrap());
                }
            })
        });
    }
    g.finish();
}

criterion_group!(benches, pack_io);
criterion_main!(benches);
