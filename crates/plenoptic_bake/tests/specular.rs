//! A mirror and a glossy steel panel seen from a point between base views
//! (docs/architecture.md, "Pack v2": the view-dependent part for the actual camera): the
//! geometry-assisted frame against the path tracer on those pixels and on the diffuse pixels of
//! the same frame, with the specular part as the base views saw it ([`Specular::Baked`]) and
//! marched through the distance cubes for the camera ([`Specular::Marched`]). Errors are
//! variance-corrected relative LRMS against a reference rendered as two halves. Frames go to
//! `target/tmp/specular/`.

mod common;

use std::path::Path;

use glam::{Vec2, Vec3};
use plenoptic_eval::metrics::corrected_relative_lrms;
use plenoptic_recon::{Camera, Mode, Reconstructor, Specular};
use plenoptic_scene::builder::{LightDesc, MaterialDesc, NodeDesc, SceneBuilder};
use plenoptic_trace::Image;

/// A grey room (inner half-size 2) open to the sky, with coloured boxes, and on its +z wall
/// a mirror and a brushed-steel panel. With `lamp` a point light hangs in it; without, the
/// sun (left to the runtime) lights it through the opening.
fn scene(lamp: bool) -> SceneBuilder {
    let mut b = SceneBuilder::new();
    let grey = b.add_material(MaterialDesc::diffuse(Vec3::splat(0.6)));
    for (i, axis) in [Vec3::X, Vec3::Y, Vec3::Z].into_iter().enumerate() {
        let size = Vec3::splat(4.4) - axis * 4.2;
        let mesh = b.add_box(format!("wall{i}"), size, grey);
        for s in [-1.0f32, 1.0] {
            if axis == Vec3::Y && s > 0.0 && !lamp {
                continue;
            }
            b.add_node(
                NodeDesc::new(format!("wall{i}{s}"))
                    .mesh(mesh)
                    .translation(axis * s * 2.1),
            );
        }
    }
    let floor_mat = b.add_material(MaterialDesc::diffuse(Vec3::new(0.5, 0.45, 0.35)));
    let floor = b.add_plane("floor", Vec2::splat(3.9), 1, floor_mat);
    b.add_node(
        NodeDesc::new("floor")
            .mesh(floor)
            .translation(Vec3::new(0.0, -1.99, 0.0)),
    );
    for (name, colour, size, at) in [
        (
            "red",
            Vec3::new(0.8, 0.15, 0.1),
            Vec3::splat(0.8),
            Vec3::new(-1.2, -1.6, -1.0),
        ),
        (
            "blue",
            Vec3::new(0.1, 0.2, 0.8),
            Vec3::new(0.6, 1.6, 0.6),
            Vec3::new(1.2, -1.2, -1.3),
        ),
        (
            "green",
            Vec3::new(0.15, 0.7, 0.2),
            Vec3::new(1.2, 0.6, 0.3),
            Vec3::new(0.0, 0.2, -1.85),
        ),
    ] {
        let m = b.add_material(MaterialDesc::diffuse(colour));
        let mesh = b.add_box(name, size, m);
        b.add_node(NodeDesc::new(name).mesh(mesh).translation(at));
    }
    let mirror = b.add_material(MaterialDesc::metal(Vec3::splat(0.95), 0.0));
    let steel = b.add_material(MaterialDesc::metal(Vec3::splat(0.8), 0.3));
    let panel = |b: &mut SceneBuilder, name: &str, m, x: f32| {
        let mesh = b.add_box(name, Vec3::new(1.2, 1.6, 0.04), m);
        b.add_node(
            NodeDesc::new(name)
                .mesh(mesh)
                .translation(Vec3::new(x, -0.6, 1.97)),
        );
    };
    panel(&mut b, "mirror", mirror, -0.7);
    panel(&mut b, "steel", steel, 0.8);
    if lamp {
        b.add_node(
            NodeDesc::new("lamp")
                .light(LightDesc::point(Vec3::ONE, 20.0))
                .translation(Vec3::new(0.0, 1.5, 0.0)),
        );
    } else {
        let towards = Vec3::new(0.3, -1.0, 0.45).normalize();
        b.add_node(
            NodeDesc::new("sun")
                .light(LightDesc::directional(Vec3::ONE, 3.0))
                .rotation(glam::Quat::from_rotation_arc(Vec3::NEG_Z, towards)),
        );
    }
    b
}

/// Corrected relative LRMS of `frame` on the pixels `which` (a one-row image of them).
fn region_error(
    frame: &[Vec3],
    (a, b): (&Image<Vec3>, &Image<Vec3>),
    which: &[usize],
) -> (f64, f64) {
    let row = |px: &dyn Fn(usize) -> Vec3| Image {
        width: which.len() as u32,
        height: 1,
        pixels: which.iter().map(|&j| px(j)).collect(),
    };
    let e = corrected_relative_lrms(
        &row(&|j| frame[j]),
        &row(&|j| a.pixels[j]),
        &row(&|j| b.pixels[j]),
    );
    (e.corrected, e.mean_ratio)
}

/// Per specular mode: (mirror, steel, diffuse) corrected relative LRMS over all their
/// pixels, and over those whose 8 neighbours show the same object; the reconstruction
/// at `supersampling`² samples per pixel.
fn measure(
    lamp: bool,
    face: u32,
    (width, height): (u32, u32),
    spp: u32,
    supersampling: u32,
) -> Vec<([f64; 3], [f64; 3])> {
    let dir = tempfile::tempdir().unwrap();
    let quality = format!(
        "range_image_size = {face}\nsamples_per_pixel = 4\nambient_samples = 64\n\
         ambient_rms = 0.1\nmax_specular_depth = 4"
    );
    let view = "kind = \"segment\"\na = [-1.2, 0.0, -0.6]\nb = [1.2, 0.0, -0.6]";
    let recipe = common::write_recipe(dir.path(), &scene(lamp), view, &quality);
    plenoptic_bake::bake_recipe(&recipe, &plenoptic_bake::BakeOptions::default()).unwrap();
    let scene = plenoptic_scene::load(&dir.path().join("scene.glb")).unwrap();
    // Between the base views, looking down at the panels from the side.
    let camera = Camera::look_at(
        Vec3::new(0.35, 0.3, -0.9),
        Vec3::new(0.0, -0.6, 1.97),
        Vec3::Y,
        60f32.to_radians(),
        width,
        height,
    )
    .unwrap();
    let (a, b) = common::reference_halves(&scene, &camera, 0.5, spp, 77);
    let mut rec = Reconstructor::open(dir.path().join("out/scene.pack")).unwrap();
    let id = |name: &str| {
        rec.pack()
            .manifest()
            .objects
            .iter()
            .find(|o| o.name == name)
            .unwrap()
            .id
    };
    let (mirror, steel) = (id("mirror"), id("steel"));
    assert!(
        plenoptic_recon::specular::glossy_allowed(&rec),
        "every light's highlight is evaluated at runtime (the lamp is placed)"
    );
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join("specular");
    std::fs::create_dir_all(&out).unwrap();
    let exposure = 0.5 / a.mean_luminance() as f32;
    a.save_png(
        out.join(format!(
            "{width}_{}_reference.png",
            if lamp { "lamp" } else { "sun" }
        )),
        exposure,
    )
    .unwrap();
    let mut results = Vec::new();
    for specular in [Specular::Baked, Specular::default()] {
        rec.settings.specular = specular;
        rec.settings.supersampling = supersampling;
        let (frame, report) = rec.render(&camera, 0.5, Mode::GeometryAssisted).unwrap();
        assert!(report.missing.is_empty(), "{:?}", report.missing);
        // The pixels whose 3 × 3 neighbourhood shows their object alone. At an outline the
        // path tracer's pixel mixes two surfaces and, below 2 × 2 supersampling, this one
        // shows the centre's: an error of every object's outline, whatever its material
        // (at 160 × 90 it raised the diffuse pixels' error by about 40 %, 0.066 → 0.094 under
        // the sun: their squared error doubled).
        let (w, h) = (width as usize, height as usize);
        let inside = |j: usize| {
            let (x, y) = (j % w, j / w);
            x > 0
                && y > 0
                && x + 1 < w
                && y + 1 < h
                && (y - 1..=y + 1).all(|ny| {
                    (x - 1..=x + 1).all(|nx| frame.object[ny * w + nx] == frame.object[j])
                })
        };
        let regions = |keep: &dyn Fn(usize) -> bool| {
            let of = |o: u32| -> Vec<usize> {
                (0..frame.object.len())
                    .filter(|&j| frame.object[j] == o && keep(j))
                    .collect()
            };
            let diffuse: Vec<usize> = (0..frame.object.len())
                .filter(|&j| ![0, mirror, steel].contains(&frame.object[j]) && keep(j))
                .collect();
            [of(mirror), of(steel), diffuse]
        };
        let halves = (&a, &b);
        let errors = |keep: &dyn Fn(usize) -> bool| {
            let [m, s, d] = regions(keep);
            assert!(m.len() > 300 && s.len() > 300, "{} {}", m.len(), s.len());
            [&m, &s, &d].map(|r| region_error(&frame.radiance, halves, r))
        };
        let [(em, rm), (es, rs), (ed, rd)] = errors(&|_| true);
        let [(im, _), (is, _), (id, _)] = errors(&inside);
        let label = match specular {
            Specular::Baked => "baked",
            Specular::Marched { .. } => "marched",
        };
        println!(
            "{face}-px cubes at {width}×{height}, {supersampling}² samples, specular {label}: \
             mirror {em:.3} (mean ×{rm:.2}), steel {es:.3} (×{rs:.2}), diffuse {ed:.3} \
             (×{rd:.2}): {:.2}× and {:.2}×; inside the outlines: mirror {im:.3}, steel {is:.3}, \
             diffuse {id:.3}: {:.2}× and {:.2}×; {:?} reflections (marched, unanswered)",
            em / ed,
            es / ed,
            im / id,
            is / id,
            report.reflections
        );
        Image {
            width,
            height,
            pixels: frame.radiance.clone(),
        }
        .save_png(
            out.join(format!(
                "{width}_{}_{label}_{supersampling}.png",
                if lamp { "lamp" } else { "sun" }
            )),
            exposure,
        )
        .unwrap();
        results.push(([em, es, ed], [im, is, id]));
    }
    results
}

/// Both panels are marched in both scenes: under the sun (left to the runtime), and under a
/// point lamp, which pack 4.1 places so that the steel adds its highlight at runtime (baked,
/// the highlight stays where the base views saw it) and pack 5 lights at runtime. Measured at
/// 160 × 90, 64-px cubes, 2 × 64 spp, one sample per pixel (`cargo test -p plenoptic_bake
/// --test specular -- --nocapture`):
///
/// | scene | mirror baked | mirror marched | steel baked | steel marched | diffuse |
/// |---|---|---|---|---|---|
/// | sun | 0.588 | 0.233 | 0.199 | 0.169 | 0.094 |
/// | lamp | 0.186 | 0.062 | 0.192 | 0.096 | 0.032 |
///
/// (The mirror's hits are shaded as pixels, `ReconSettings::shaded_reflections`. At one
/// sample per pixel its sharp reflection aliases: the antialiased test below measures it
/// without.) The steel's 8 rays per pixel are each weighted by the lobe's
/// `F·G·(ω_o·h)/((n·ω_o)(n·h))`, the unbiased estimate of the lobe.
#[test]
fn mirror_and_steel_reflect_for_the_camera() {
    let sun: Vec<_> = measure(false, 64, (160, 90), 128, 1)
        .into_iter()
        .map(|r| r.0)
        .collect();
    let lamp: Vec<_> = measure(true, 64, (160, 90), 128, 1)
        .into_iter()
        .map(|r| r.0)
        .collect();
    for r in [&sun, &lamp] {
        let ([.., baked_diffuse], [.., marched_diffuse]) = (r[0], r[1]);
        assert!(
            (baked_diffuse - marched_diffuse).abs() < 1e-9,
            "diffuse pixels changed"
        );
    }
    let ([mirror_b, steel_b, _], [mirror_m, steel_m, diffuse]) = (sun[0], sun[1]);
    assert!(
        mirror_m < 0.5 * mirror_b,
        "sun: mirror {mirror_b} -> {mirror_m}"
    );
    assert!(
        mirror_m < 3.0 * diffuse,
        "sun: mirror {mirror_m}, diffuse {diffuse}"
    );
    // The baked steel's highlight is interpolated between the lighting pass's anchors
    // (geometry/sparse.rs), which blurs its texels a little; the marched steel's rays are
    // answered at the point the proxies say they meet, where a view sees it, before any march.
    assert!(
        steel_m < 0.95 * steel_b,
        "sun: steel {steel_b} -> {steel_m}"
    );
    let ([mirror_b, steel_b, _], [mirror_m, steel_m, diffuse]) = (lamp[0], lamp[1]);
    assert!(
        mirror_m < 0.6 * mirror_b,
        "lamp: mirror {mirror_b} -> {mirror_m}"
    );
    // The bound is the mirror's error within 2× the diffuse pixels'; at one sample per pixel
    // the mirror's sharp edges alias (0.062 against 0.032, 1.9×). The antialiased test below
    // holds 2×; held here: what the sun's scene holds.
    assert!(
        mirror_m < 3.0 * diffuse,
        "lamp: mirror {mirror_m}, diffuse {diffuse}"
    );
    // Pack 4.1 places the lamp: the steel reflects for the camera and adds the lamp's
    // highlight at runtime (plenoptic_recon::lamps) instead of keeping the baked one.
    assert!(
        steel_m < 0.6 * steel_b,
        "lamp: steel {steel_b} -> {steel_m}"
    );
}

/// The comparison with antialiased frames, as the tour's are compared (about 25 s on 2
/// cores): 320 × 180, 4 × 4 samples per pixel, 2 × 64 spp. Both panels reflect for the camera
/// in both scenes; under the lamp the steel adds the placed lamp's highlight at runtime. Held
/// here: both within 2× the diffuse pixels' error; the
/// mirror within 1.25× (what shading its hits with every base view's lighting reaches); and
/// the mirror's error below half the baked one's. Measured:
///
/// | scene | mirror | steel | diffuse |
/// |---|---|---|---|
/// | sun | 0.055 (0.89×) | 0.067 (1.09×) | 0.062 |
/// | lamp | 0.036 (1.01×) | 0.048 (1.37×) | 0.035 |
///
/// The mirror's hits are shaded as pixels (`ReconSettings::shaded_reflections`, reflected.rs
/// in plenoptic_recon), lit by every base view that shows them: the views blended for the
/// camera alone leave hits in the gap behind the red box to a gather of 8 rays, noisy and too
/// bright there. The base views' radiance at the hit would show the reflected floor's
/// sun-shadow edges at cube resolution, and a pale ghost beside the red box, whose front no
/// base view sees (the views stand level with it).
#[test]
fn mirror_and_steel_antialiased() {
    let sun = measure(false, 64, (320, 180), 128, 4);
    let lamp = measure(true, 64, (320, 180), 128, 4);
    for r in [&sun, &lamp] {
        let ([mirror_b, ..], _) = r[0];
        let ([mirror, steel, diffuse], _) = r[1];
        assert!(mirror < 0.5 * mirror_b, "mirror {mirror_b} -> {mirror}");
        assert!(
            mirror <= 2.0 * diffuse && steel <= 2.0 * diffuse,
            "mirror {mirror}, steel {steel}, diffuse {diffuse}"
        );
        assert!(
            mirror <= 1.25 * diffuse,
            "mirror {mirror}, diffuse {diffuse}"
        );
    }
}
