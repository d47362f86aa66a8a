//! Whole bakes: contents, determinism, resume, shards, and failures that leave no pack.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use common::*;
use glam::Vec3;
use plenoptic_bake::{BakeError, BakeOptions, bake_recipe};
use plenoptic_pack::{ChunkKind, MAGIC, PackReader};
use plenoptic_scene::builder::{MaterialDesc, NodeDesc};

const BIN: &str = env!("CARGO_BIN_EXE_plenoptic");

fn plenoptic(args: &[&str], threads: Option<usize>) -> std::process::Output {
    let mut c = Command::new(BIN);
    c.args(args);
    if let Some(n) = threads {
        c.env("RAYON_NUM_THREADS", n.to_string());
    }
    c.output().unwrap()
}

fn moving_recipe(dir: &Path) -> PathBuf {
    write_recipe(
        dir,
        &two_rooms(),
        ROOM_A_SEGMENT,
        "q = 0.9\nmax_time_depth = 2",
    )
}

fn pack_path(dir: &Path) -> PathBuf {
    dir.join("out/scene.pack")
}

#[test]
fn a_bake_writes_range_images_volumes_proxies_and_tracks() {
    let dir = tempfile::tempdir().unwrap();
    let recipe = moving_recipe(dir.path());
    let report = bake_recipe(&recipe, &BakeOptions::default()).unwrap();
    let pack = PackReader::open(pack_path(dir.path())).unwrap();
    let m = pack.manifest();
    assert_eq!(m.base_views.len(), report.plan.base_views.len());
    // Range images at every base view and key, with the moving box seen from room A.
    let mut saw_box = false;
    let cube_id = m.objects.iter().find(|o| o.name == "mover").unwrap().id;
    for (bv, v) in m.base_views.iter().enumerate() {
        for key in 0..v.time_keys.len() {
            let image = pack.range_image(bv as u32, key as u32).unwrap();
            assert!(
                image.object_id.texels.iter().all(|&id| id != 0),
                "closed room"
            );
            assert!(
                image
                    .distance
                    .texels
                    .iter()
                    .all(|d| d.is_finite() && *d > 0.0)
            );
            saw_box |= image.object_id.texels.contains(&cube_id);
        }
    }
    assert!(saw_box);
    // Temporal volumes: samples bucketed by time, inside their buckets.
    let mut volume = 0;
    for e in pack
        .entries()
        .iter()
        .filter(|e| e.kind == ChunkKind::VolumeBlock)
    {
        let block = pack.volume_block(e.base_view, e.key).unwrap();
        let (t0, t1) = m.bucket_range(e.key);
        for s in &block.samples {
            assert!(s.t >= t0 - 1e-4 && s.t <= t1 + 1e-4);
            assert!(s.radius > 0.0);
        }
        volume += block.samples.len();
    }
    assert!(volume > 0);
    assert_eq!(m.stats.sample_counts["volume_samples"], volume as u64);
    assert!(
        m.stats.phase_seconds.is_empty(),
        "timings live in the sidecar"
    );
    assert!(plenoptic_bake::write::timings_path(&pack_path(dir.path())).exists());
    // Proxy geometry and tracks: the mover moves in the tracks.
    for o in &m.objects {
        let mesh = pack.proxy_mesh(o.id).unwrap();
        assert_eq!(mesh.indices.len(), 36);
    }
    // Materials (pack 1.2): the scene's two, one per object; the boxes' UVs and tangents.
    assert_eq!(pack.materials().len(), 2);
    assert!(pack.textures().is_empty());
    for o in &m.objects {
        assert!(pack.object_material(o.id).is_some(), "{}", o.name);
        let a = pack
            .proxy_attributes(o.id)
            .unwrap()
            .expect("boxes have UVs");
        assert_eq!(
            a.tangents.len(),
            pack.proxy_mesh(o.id).unwrap().positions.len()
        );
    }
    // What 1.2 adds to this pack: the attribute chunks and the manifest's material entries.
    let mut without = m.clone();
    without.materials.clear();
    without.textures.clear();
    without.objects.iter_mut().for_each(|o| o.material = None);
    let manifest_growth = pack.header().manifest_length - without.to_json().unwrap().len() as u64;
    eprintln!(
        "pack {} bytes; 1.2 adds proxy attributes {} bytes (+ 48 per directory row), manifest {} bytes",
        pack.file_length(),
        m.stats.bytes.get("proxy_attributes").copied().unwrap_or(0),
        manifest_growth
    );
    let tracks = pack.tracks().unwrap();
    let mover = tracks
        .objects
        .iter()
        .find(|t| t.object_id == cube_id)
        .unwrap();
    let tr = mover.translation.as_ref().unwrap();
    assert!(tr.times.len() > 2);
    assert!((tr.values.last().unwrap().x - -3.8).abs() < 1e-4);
    assert!(
        !plenoptic_bake::WorkDir::for_output(&pack_path(dir.path()))
            .path
            .exists()
    );
}

#[test]
fn resume_shards_and_thread_counts_give_the_same_pack() {
    let dir = tempfile::tempdir().unwrap();
    let recipe = moving_recipe(dir.path());
    let r = recipe.to_str().unwrap();
    let pack = pack_path(dir.path());

    // Reference: one uninterrupted run, in this process.
    bake_recipe(&recipe, &BakeOptions::default()).unwrap();
    let reference = std::fs::read(&pack).unwrap();
    std::fs::remove_file(&pack).unwrap();

    // One thread.
    let out = plenoptic(&["bake", r, "-q"], Some(1));
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(std::fs::read(&pack).unwrap() == reference, "single thread");
    std::fs::remove_file(&pack).unwrap();

    // Interrupted after two items, then resumed.
    let out = plenoptic(&["bake", r, "-q", "--stop-after", "2"], None);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("interrupted"));
    assert!(!pack.exists(), "an interrupted bake leaves no pack");
    let out = plenoptic(&["bake", r, "-q", "--resume"], Some(2));
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(String::from_utf8_lossy(&out.stdout).contains("2 resumed"));
    assert!(std::fs::read(&pack).unwrap() == reference, "resumed");
    std::fs::remove_file(&pack).unwrap();

    // Three shards in parallel processes, then a merge.
    let shards: Vec<_> = (0..3)
        .map(|i| {
            Command::new(BIN)
                .args(["bake", r, "-q", "--shard", &format!("{i}/3")])
                .env("RAYON_NUM_THREADS", "1")
                .stdout(std::process::Stdio::null())
                .spawn()
                .unwrap()
        })
        .collect();
    for mut s in shards {
        assert!(s.wait().unwrap().success());
    }
    assert!(!pack.exists(), "shards write no pack");
    let out = plenoptic(&["merge", r], None);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(std::fs::read(&pack).unwrap() == reference, "merged shards");
}

#[test]
fn merging_with_a_missing_shard_fails_without_a_pack() {
    let dir = tempfile::tempdir().unwrap();
    let recipe = moving_recipe(dir.path());
    let r = recipe.to_str().unwrap();
    let out = plenoptic(&["bake", r, "-q", "--shard", "0/2"], None);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let out = plenoptic(&["merge", r], None);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("missing"));
    assert!(!pack_path(dir.path()).exists());
}

/// No file in `dir` (recursively) starts with the pack magic.
fn no_pack_in(dir: &Path) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let p = entry.unwrap().path();
        if p.is_dir() {
            no_pack_in(&p);
        } else {
            let bytes = std::fs::read(&p).unwrap();
            assert!(
                !bytes.starts_with(&MAGIC),
                "{} looks like a pack",
                p.display()
            );
        }
    }
}

#[test]
fn recipe_and_scene_errors_leave_no_pack() {
    // A scene file that is not glTF.
    let dir = tempfile::tempdir().unwrap();
    let recipe = write_recipe(dir.path(), &static_room(), STATIC_SEGMENT, "");
    std::fs::write(dir.path().join("scene.glb"), b"not a glb").unwrap();
    let err = bake_recipe(&recipe, &BakeOptions::default()).unwrap_err();
    assert!(matches!(err, BakeError::Scene(_)), "{err}");
    no_pack_in(dir.path());
    assert!(!pack_path(dir.path()).exists());

    // A missing scene file, through the command.
    std::fs::remove_file(dir.path().join("scene.glb")).unwrap();
    let out = plenoptic(&["bake", recipe.to_str().unwrap(), "-q"], None);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("scene.glb"));
    no_pack_in(dir.path());

    // An invalid recipe.
    std::fs::write(
        &recipe,
        "output = \"out/x.pack\"\n[view_space]\nkind = \"cone\"\n",
    )
    .unwrap();
    let err = bake_recipe(&recipe, &BakeOptions::default()).unwrap_err();
    assert!(matches!(err, BakeError::Recipe(_)), "{err}");
    no_pack_in(dir.path());
}

/// What the glTF import could not take over is printed before the bake, and the bake still
/// runs (an alpha cutoff above 1 is read as 1 with a warning).
#[test]
fn import_warnings_are_printed_by_the_bake_command() {
    let dir = tempfile::tempdir().unwrap();
    let mut scene = static_room();
    let fence = scene.add_material(
        MaterialDesc::diffuse(Vec3::splat(0.5))
            .alpha_mode(plenoptic_scene::AlphaMode::Mask { cutoff: 1.5 }),
    );
    let panel = scene.add_box("panel", Vec3::new(0.4, 0.4, 0.05), fence);
    scene.add_node(NodeDesc::new("fence").mesh(panel));
    let recipe = write_recipe(dir.path(), &scene, STATIC_SEGMENT, "");
    let out = plenoptic(&["bake", recipe.to_str().unwrap(), "-q"], None);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains("plenoptic: warning:") && err.contains("alphaCutoff 1.5"),
        "{err}"
    );
    assert!(pack_path(dir.path()).exists());
}

#[test]
fn plan_and_inspect_commands() {
    let dir = tempfile::tempdir().unwrap();
    let recipe = write_recipe(dir.path(), &static_room(), STATIC_SEGMENT, "q = 0.0");
    let r = recipe.to_str().unwrap();
    let out = plenoptic(&["plan", r], None);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("base views: 2") && text.contains("range images:"),
        "{text}"
    );
    assert!(dir.path().join("out/scene.pack.plan.json").exists());

    let out = plenoptic(&["bake", r, "-q"], None);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let pack = pack_path(dir.path());
    let p = pack.to_str().unwrap();
    let out = plenoptic(&["inspect", p, "--chunks"], None);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("RadianceCube") && text.contains("base views: 2"),
        "{text}"
    );
    let ktx = dir.path().join("c0.ktx2");
    let out = plenoptic(
        &["inspect", p, "--extract", "0", ktx.to_str().unwrap()],
        None,
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let bytes = std::fs::read(&ktx).unwrap();
    assert_eq!(&bytes[..12], b"\xABKTX 20\xBB\r\n\x1A\n");
}

#[test]
fn floor_radiance_is_at_least_the_analytic_direct_light() {
    // A point light of intensity I at L over a diffuse floor of albedo ρ: direct radiance
    // ρ/π · I cosθ / r²; indirect light only adds to it.
    let dir = tempfile::tempdir().unwrap();
    let recipe = write_recipe(
        dir.path(),
        &static_room(),
        STATIC_SEGMENT,
        "q = 0.0\nsamples_per_pixel = 4",
    );
    let report = bake_recipe(&recipe, &BakeOptions::default()).unwrap();
    let pack = PackReader::open(pack_path(dir.path())).unwrap();
    let view = &report.plan.base_views[0];
    let image = pack.range_image(0, 0).unwrap();
    let n = image.face_size();
    let light = glam::Vec3::new(0.0, 1.5, 0.0);
    let mut checked = 0;
    for i in 0..(6 * n * n) as usize {
        let d = plenoptic_pack::cube::texel_direction(n, i).normalize();
        if d.y > -0.9 {
            continue;
        }
        let hit = view.position + d * ((-2.0 - view.position.y) / d.y);
        let distance = (hit - view.position).length();
        assert!((image.distance.texels[i] - distance).abs() < 1e-3 * distance);
        let to_light = light - hit;
        let r = to_light.length();
        let direct = 0.6 / std::f32::consts::PI * 20.0 * (to_light.y / r) / (r * r);
        let l = image.radiance.texels[i].x;
        assert!(
            l > 0.8 * direct && l < 10.0 * direct,
            "texel {i}: {l} vs direct {direct}"
        );
        checked += 1;
    }
    assert!(checked > 0);
}

#[test]
fn volume_blocks_carry_their_delaunay_complex_when_asked() {
    let dir = tempfile::tempdir().unwrap();
    let recipe = moving_recipe(dir.path());
    let options = BakeOptions {
        volume_complex: true,
        ..Default::default()
    };
    bake_recipe(&recipe, &options).unwrap();
    let pack = PackReader::open(pack_path(dir.path())).unwrap();
    let mut complexes = 0;
    for e in pack
        .entries()
        .iter()
        .filter(|e| e.kind == ChunkKind::VolumeBlock)
    {
        let block = pack.volume_block(e.base_view, e.key).unwrap();
        if pack
            .find(ChunkKind::VolumeConnectivity, e.base_view, e.key)
            .is_some()
        {
            let tets = pack.connectivity(e.base_view, e.key).unwrap();
            assert!(!tets.is_empty());
            assert!(
                tets.iter()
                    .flatten()
                    .all(|&i| (i as usize) < block.samples.len())
            );
            complexes += 1;
        }
    }
    assert!(complexes > 0);
}

#[test]
fn reference_render_and_compare_commands() {
    let dir = tempfile::tempdir().unwrap();
    let recipe = write_recipe(dir.path(), &static_room(), STATIC_SEGMENT, "q = 0.0");
    let r = recipe.to_str().unwrap();
    let path = dir.path().join("path.json");
    std::fs::write(
        &path,
        r#"{ "frame_rate": 2.0, "width": 16, "height": 12, "keyframes": [
            { "time": 0.0, "position": [-0.5, 0.5, -0.5], "yaw_deg": 30.0, "vfov_deg": 70.0 },
            { "time": 0.5, "position": [0.5, 0.5, 0.5], "yaw_deg": 40.0, "vfov_deg": 70.0 } ] }"#,
    )
    .unwrap();
    let p = path.to_str().unwrap();
    let reference = dir.path().join("reference");
    let out = plenoptic(
        &[
            "reference",
            r,
            "--path",
            p,
            "--out",
            reference.to_str().unwrap(),
            "--spp",
            "4",
            "--halves",
        ],
        None,
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let reference_b = dir.path().join("reference_b");
    for half in [&reference, &reference_b] {
        assert!(half.join("frame_00000.exr").exists());
        assert!(half.join("frame_00001.png").exists());
    }
    // Different seeds: the halves differ.
    assert_ne!(
        std::fs::read(reference.join("frame_00000.exr")).unwrap(),
        std::fs::read(reference_b.join("frame_00000.exr")).unwrap()
    );

    let out = plenoptic(&["bake", r, "-q"], None);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let frames = dir.path().join("frames");
    let pack = pack_path(dir.path());
    let out = plenoptic(
        &[
            "render",
            pack.to_str().unwrap(),
            "--path",
            p,
            "--mode",
            "image",
            "--out",
            frames.to_str().unwrap(),
        ],
        None,
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(frames.join("frame_00001.exr").exists());
    // Geometry-assisted with version 1's shading; a bad shading is a named error.
    let radiance = dir.path().join("frames_radiance");
    let render = |shading: &str, out: &std::path::Path| {
        plenoptic(
            &[
                "render",
                pack.to_str().unwrap(),
                "--path",
                p,
                "--shading",
                shading,
                "--out",
                out.to_str().unwrap(),
            ],
            None,
        )
    };
    let out = render("radiance", &radiance);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(radiance.join("frame_00001.exr").exists());
    let out = render("glossy", &radiance);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("shading 'glossy'"));
    let csv = dir.path().join("compare.csv");
    let plot = dir.path().join("compare.png");
    let out = plenoptic(
        &[
            "compare",
            "--reference",
            reference.to_str().unwrap(),
            &format!("image={}", frames.display()),
            "--csv",
            csv.to_str().unwrap(),
            "--plot",
            plot.to_str().unwrap(),
        ],
        None,
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        stdout.contains("rel. LRMS") && stdout.contains("\nimage "),
        "{stdout}"
    );
    assert!(csv.exists() && plot.exists() && plot.with_extension("svg").exists());

    // Variance-corrected against the two halves.
    let out = plenoptic(
        &[
            "compare",
            "--reference",
            reference.to_str().unwrap(),
            "--reference-b",
            reference_b.to_str().unwrap(),
            &format!("image={}", frames.display()),
            "--csv",
            csv.to_str().unwrap(),
            "--plot",
            plot.to_str().unwrap(),
        ],
        None,
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    println!("{stdout}");
    assert!(
        stdout.contains("corrected") && stdout.contains("noise floor"),
        "{stdout}"
    );
    let text = std::fs::read_to_string(&csv).unwrap();
    assert!(
        text.starts_with(
            "frame,noise_floor,halves_ssim,image_lrms_corrected,image_lrms,image_psnr,\
             image_mean_ratio,image_ssim"
        ),
        "{text}"
    );
    assert_eq!(text.lines().count(), 3, "{text}");
}

#[test]
fn quality_denoise_filters_the_stored_lighting_and_keeps_the_guides() {
    // The static room at 4 spp, baked with and without `denoise = true`: the guides are the
    // same, the radiance is not, and its mean over the cube stays within 2 %.
    let bake_with = |denoise: bool| {
        let dir = tempfile::tempdir().unwrap();
        let recipe = write_recipe(
            dir.path(),
            &static_room(),
            STATIC_SEGMENT,
            &format!("q = 0.0\nsamples_per_pixel = 4\nrange_image_size = 24\ndenoise = {denoise}"),
        );
        let report = bake_recipe(&recipe, &BakeOptions::default()).unwrap();
        assert_eq!(report.plan.quality.denoise, denoise);
        let pack = PackReader::open(pack_path(dir.path())).unwrap();
        pack.range_image(0, 0).unwrap()
    };
    let (off, on) = (bake_with(false), bake_with(true));
    assert_eq!(off.object_id, on.object_id);
    assert_eq!(off.distance, on.distance);
    assert_ne!(off.radiance, on.radiance);
    let mean = |c: &plenoptic_pack::CubeImage<glam::Vec3>| {
        c.texels.iter().map(|t| t.x + t.y + t.z).sum::<f32>() / c.texels.len() as f32
    };
    let (m_off, m_on) = (mean(&off.radiance), mean(&on.radiance));
    assert!((m_on / m_off - 1.0).abs() < 0.02, "mean {m_off} → {m_on}");
}
