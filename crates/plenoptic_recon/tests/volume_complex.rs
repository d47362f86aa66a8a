//! Volume mode with the baked (x, y, t) complex: slicing a block's stored tetrahedra at t
//! reproduces a radiance linear in the complex's coordinates, and the report says so.

use std::path::Path;

use plenoptic_pack::glam::{Quat, Vec2, Vec3};
use plenoptic_pack::{
    BaseView, ChunkKind, CubeFormats, CubeImage, Manifest, Motion, ObjectEntry, PackReader,
    PackWriter, RangeImage, TimeRange, VolumeSample, cube, decode_volume_block,
    encode_connectivity, encode_volume_block,
};
use plenoptic_recon::delaunay3::tetrahedralize;
use plenoptic_recon::volume::{complex_point, slice_to_cube};
use plenoptic_recon::{Camera, Mode, Reconstructor};

/// Radiance linear in the complex's (x, y, t), every channel in [0.5, 2).
fn radiance(x: f32, y: f32, t: f32) -> Vec3 {
    Vec3::new(
        1.2 + 0.3 * x + 0.2 * y + 0.25 * t,
        1.3 - 0.2 * x + 0.1 * y - 0.3 * t,
        1.1 + 0.1 * x + 0.3 * y + 0.2 * t,
    )
}

/// Distance linear in (x, y, t).
fn distance(x: f32, y: f32, t: f32) -> f32 {
    3.0 + x + 0.5 * y + t
}

/// One base view at the origin, one bucket [0, 1) whose samples lie on three time layers over
/// a jittered grid of octahedral (x, y) in [−0.8, 0.8]²; its complex stored when `complex`.
fn write_pack(path: &Path, complex: bool) {
    let mut w = PackWriter::create(path).unwrap();
    let mut image = RangeImage::new(8);
    image.radiance = CubeImage::filled(8, Vec3::ONE);
    image.distance = CubeImage::filled(8, 3.0);
    image.object_id = CubeImage::filled(8, 1);
    image.normal = CubeImage::filled(8, Vec3::Z);
    w.add_range_image(0, 0, &image, CubeFormats::default())
        .unwrap();
    let mut samples = Vec::new();
    let mut state = 12345u32;
    let mut jitter = || {
        state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        ((state >> 8) as f32 / (1u32 << 24) as f32 - 0.5) * 0.05
    };
    for t in [0.1f32, 0.5, 0.9] {
        for j in 0..9 {
            for i in 0..9 {
                let x = (-0.8 + 0.2 * i as f32 + jitter()).clamp(-0.8, 0.8);
                let y = (-0.8 + 0.2 * j as f32 + jitter()).clamp(-0.8, 0.8);
                samples.push(VolumeSample {
                    direction: cube::oct_decode(Vec2::new(x, y)),
                    t,
                    radiance: radiance(x, y, t),
                    lighting: radiance(x, y, t),
                    non_diffuse: Vec3::ZERO,
                    distance: distance(x, y, t),
                    normal: Vec3::Z,
                    object_id: 1,
                    radius: 0.1,
                });
            }
        }
    }
    let enc = encode_volume_block(0.0, 1.0, &samples).unwrap();
    w.add_raw_chunk(
        ChunkKind::VolumeBlock,
        0,
        0,
        &enc.bytes,
        enc.uncompressed_length,
        None,
    )
    .unwrap();
    if complex {
        // As the baker does: the complex of the stored (quantized) samples, in stored order.
        let block = decode_volume_block(&enc.bytes).unwrap();
        let points: Vec<[f64; 3]> = block
            .samples
            .iter()
            .map(|s| complex_point(s.direction, s.t, block.t_start, block.t_end))
            .collect();
        let tets = tetrahedralize(&points).unwrap().tets;
        let (bytes, len) = encode_connectivity(points.len() as u32, &tets).unwrap();
        w.add_raw_chunk(ChunkKind::VolumeConnectivity, 0, 0, &bytes, len, None)
            .unwrap();
    }
    let mut manifest = Manifest::new(
        TimeRange {
            start: 0.0,
            end: 1.0,
        },
        1.0,
    );
    manifest.base_views.push(BaseView {
        id: 0,
        position: Vec3::ZERO,
        time_keys: vec![0.0],
    });
    manifest.objects.push(ObjectEntry {
        id: 1,
        name: "shell".into(),
        node_path: "/shell".into(),
        motion: Motion::Static,
        proxy_mesh: None,
        material: None,
        coverage: None,
    });
    w.finish(&manifest).unwrap();
}

#[test]
fn slicing_the_complex_reproduces_a_linear_radiance() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("complex.pack");
    write_pack(&path, true);
    let pack = PackReader::open(&path).unwrap();
    let block = pack.volume_block(0, 0).unwrap();
    let tets = pack.connectivity(0, 0).unwrap();
    let t = 0.3;
    let n = 32;
    let (r, d, o) = slice_to_cube(&block, &tets, t, n).unwrap().unwrap();
    let (mut err_r, mut err_d, mut inside) = (0.0f32, 0.0f32, 0);
    for i in 0..6 * (n * n) as usize {
        let e = cube::oct_encode(cube::texel_direction(n, i));
        // Inside the hull of the jittered grid (whose outer rows lie within 0.025 of ±0.8).
        if e.x.abs() > 0.7 || e.y.abs() > 0.7 {
            continue;
        }
        inside += 1;
        let want = radiance(e.x, e.y, t);
        err_r = err_r.max((r.texels[i] - want).abs().max_element());
        err_d = err_d.max((d.texels[i] - distance(e.x, e.y, t)).abs());
        assert_eq!(o.texels[i], 1);
    }
    println!("{inside} texels inside the hull: radiance error {err_r:e}, distance error {err_d:e}");
    assert!(inside > 1000, "{inside}");
    // RGB9E5 with every channel below 2: ≤ 2·2⁻⁹ ≈ 3.9e-3 per channel; the coordinates'
    // quantization (≤ 1.5e-5 in x, y; 7.6e-6 in t) adds < 1e-5.
    assert!(err_r < 4e-3, "radiance error {err_r}");
    // Distances are stored exactly: only the coordinates' quantization and rounding remain.
    assert!(err_d < 1e-4, "distance error {err_d}");
}

#[test]
fn volume_mode_uses_the_complex_when_the_pack_has_it() {
    let dir = tempfile::tempdir().unwrap();
    let t = 0.3;
    // Looking along +Z (octahedral (0, 0)), well inside the hull.
    let camera = Camera::new(
        Vec3::ZERO,
        Quat::from_rotation_y(std::f32::consts::PI),
        0.6,
        24,
        24,
    )
    .unwrap();
    for complex in [true, false] {
        let path = dir.path().join(format!("v{complex}.pack"));
        write_pack(&path, complex);
        let recon = Reconstructor::open(&path).unwrap();
        let (frame, report) = recon.render(&camera, t, Mode::Volume).unwrap();
        assert_eq!(report.used_mode, Mode::Volume);
        assert!(report.missing.is_empty(), "{:?}", report.missing);
        assert_eq!(
            report.volume_complex_blocks,
            usize::from(complex),
            "{report:?}"
        );
        if complex {
            let basis = camera.basis();
            let mut err = 0.0f32;
            for y in 4..20 {
                for x in 4..20 {
                    let e = cube::oct_encode(basis.direction(x as f32 + 0.5, y as f32 + 0.5));
                    let got = frame.radiance[y * 24 + x];
                    err = err.max((got - radiance(e.x, e.y, t)).abs().max_element());
                }
            }
            println!("frame radiance error (texel-sized warp) {err:e}");
            // The warp samples texel centres: the error is about the gradient times a texel.
            assert!(err < 0.03, "frame radiance error {err}");
        }
    }
}
