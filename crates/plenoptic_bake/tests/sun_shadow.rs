//! A sun-shadow edge on a floor (docs/architecture.md, "The runtime sun"): the error of the
//! geometry-assisted frame against the path tracer in a 4-pixel band along the edge, against
//! the error elsewhere on the floor. Pack 3 leaves the sun's direct light to the runtime
//! (shadow rays against the proxies; for this sun without a disc, the lit fraction of each
//! pixel an edge crosses is measured along the edge, `plenoptic_recon`'s `sun_edge`), so the
//! edge is at screen resolution; pack 2.0 had it in the stored lighting, at cube resolution.
//!
//! The errors are variance-corrected RMS errors, as every comparison with the path tracer: from
//! two reference halves, the reference's own variance is estimated and subtracted per region
//! (`plenoptic_eval::metrics::ErrorSums`). An antialiased edge is where a path tracer is
//! noisiest, so the uncorrected error of a perfect frame is itself about twice as large in the
//! band as elsewhere; the mean absolute errors (the reference's noise left in) are printed
//! beside. Frames go to `target/tmp/sun_shadow/`.

mod common;

use std::path::Path;

use glam::{Quat, Vec2, Vec3};
use plenoptic_eval::metrics::ErrorSums;
use plenoptic_recon::{Camera, Mode, Reconstructor, Shading};
use plenoptic_scene::builder::{LightDesc, MaterialDesc, NodeDesc, SceneBuilder};
use plenoptic_trace::image::luminance;
use plenoptic_trace::{Image, SceneAccel};

/// Where the sunlight travels.
fn sun_direction() -> Vec3 {
    Vec3::new(0.5, -1.0, 0.3).normalize()
}

/// A 6 m floor under a sun, with a box on a post casting a shadow onto it.
fn scene() -> SceneBuilder {
    let mut b = SceneBuilder::new();
    let grey = b.add_material(MaterialDesc::diffuse(Vec3::splat(0.6)));
    let floor = b.add_plane("floor", Vec2::splat(6.0), 1, grey);
    b.add_node(NodeDesc::new("floor").mesh(floor));
    let block = b.add_box("block", Vec3::new(1.0, 0.2, 1.0), grey);
    b.add_node(
        NodeDesc::new("block")
            .mesh(block)
            .translation(Vec3::new(-0.5, 1.2, 0.0)),
    );
    b.add_node(
        NodeDesc::new("sun")
            .light(LightDesc::directional(Vec3::ONE, 3.0))
            .rotation(Quat::from_rotation_arc(Vec3::NEG_Z, sun_direction())),
    );
    b
}

/// Mean relative absolute error in the band along the shadow edge and elsewhere on the floor,
/// per `(shading, shadow rays, edge rays)` of `configs`, all from one bake.
fn measure(
    face: u32,
    width: u32,
    height: u32,
    spp: u32,
    configs: &[(Shading, u32, u32)],
) -> Vec<(f64, f64)> {
    let dir = tempfile::tempdir().unwrap();
    let quality = format!(
        "range_image_size = {face}\nsamples_per_pixel = 4\nambient_samples = 64\nambient_rms = 0.1"
    );
    let view = "kind = \"segment\"\na = [-1.0, 1.0, -1.5]\nb = [1.0, 1.0, -1.5]";
    let recipe = common::write_recipe(dir.path(), &scene(), view, &quality);
    plenoptic_bake::bake_recipe(&recipe, &plenoptic_bake::BakeOptions::default()).unwrap();
    let scene = plenoptic_scene::load(&dir.path().join("scene.glb")).unwrap();
    let camera = Camera::look_at(
        Vec3::new(0.3, 1.4, -2.0),
        Vec3::new(0.3, 0.0, 0.2),
        Vec3::Y,
        50f32.to_radians(),
        width,
        height,
    )
    .unwrap();
    let (a, b) = common::reference_halves(&scene, &camera, 0.5, spp, 31);
    let accel = SceneAccel::new(&scene).unwrap();
    let placed = accel.at_time(0.5);
    let mut rec = Reconstructor::open(dir.path().join("out/scene.pack")).unwrap();
    assert!(
        rec.runtime_sun().is_some(),
        "the bake leaves the sun to the runtime"
    );
    let mut out = Vec::new();
    for &(shading, rays, edge_rays) in configs {
        rec.settings.shading = shading;
        rec.settings.sun_shadow_rays = rays;
        rec.settings.sun_edge_rays = edge_rays;
        out.push(errors(&rec, &placed, &camera, (&a, &b), face, rays));
    }
    out
}

/// [`measure`] of one reconstruction.
fn errors(
    rec: &Reconstructor,
    placed: &plenoptic_trace::PlacedScene<'_>,
    camera: &Camera,
    (a, b): (&Image<Vec3>, &Image<Vec3>),
    face: u32,
    rays: u32,
) -> (f64, f64) {
    let (width, height) = (camera.width, camera.height);
    let (frame, _) = rec.render(camera, 0.5, Mode::GeometryAssisted).unwrap();
    // Floor pixels and whether the sun reaches their point.
    let floor = rec
        .pack()
        .manifest()
        .objects
        .iter()
        .find(|o| o.name == "floor")
        .unwrap()
        .id;
    let (w, h) = (width as usize, height as usize);
    let basis = camera.basis();
    let lit: Vec<Option<bool>> = (0..w * h)
        .map(|j| {
            (frame.object[j] == floor).then(|| {
                let d = basis.direction((j % w) as f32 + 0.5, (j / w) as f32 + 0.5);
                let p = basis.position + d * frame.depth[j] + Vec3::Y * 1e-3;
                !placed.segment_occluded(p, p - sun_direction() * 100.0)
            })
        })
        .collect();
    // The pixels within 2 of pixel j, itself included (fewer at the frame's border).
    let window = |j: usize| {
        let (x, y) = ((j % w) as i64, (j / w) as i64);
        (-2..=2i64)
            .flat_map(move |dy| (-2..=2i64).map(move |dx| (x + dx, y + dy)))
            .filter(|&(nx, ny)| nx >= 0 && ny >= 0 && (nx as usize) < w && (ny as usize) < h)
            .map(|(nx, ny)| ny as usize * w + nx as usize)
    };
    // The band: floor pixels within 2 pixels of one whose sunlight differs.
    let near_edge = |j: usize| window(j).any(|k| lit[k].is_some_and(|l| Some(l) != lit[j]));
    // Compared: floor pixels at least 3 pixels inside the floor's outline in the frame. At
    // the outline the path tracer's pixels mix the floor with what lies behind it, and this
    // reconstruction shows one surface per pixel (it does not antialias geometry): that
    // error is the same whether the sun is there or not, and kept in, it dominated both
    // regions (the floor's far edge runs through the band where the shadow meets it, and
    // it measured the rest of the floor at 0.018 instead of 0.002).
    let inside = |j: usize| window(j).count() == 25 && window(j).all(|k| lit[k].is_some());
    let floor_px: Vec<usize> = (0..w * h).filter(|&j| inside(j)).collect();
    // Squared errors against the reference's halves, per region, with the reference's
    // variance estimated and removed (plenoptic_eval::metrics); and mean absolute errors,
    // which keep the reference's noise in.
    let (mut band, mut rest) = (ErrorSums::default(), ErrorSums::default());
    let (mut band_abs, mut rest_abs) = ((0.0, 0.0), (0.0, 0.0));
    for &j in &floor_px {
        let (x, pa, pb) = (frame.radiance[j], a.pixels[j], b.pixels[j]);
        let m = 0.5 * f64::from(luminance(pa) + luminance(pb));
        let (sums, abs) = if near_edge(j) {
            (&mut band, &mut band_abs)
        } else {
            (&mut rest, &mut rest_abs)
        };
        sums.add_colours(x, pa, pb);
        abs.0 += (f64::from(luminance(x)) - m).abs();
        abs.1 += (f64::from(luminance(pa)) - m).abs();
    }
    let mean_ref = (band.reference + rest.reference) / (band.count + rest.count) as f64;
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join("sun_shadow");
    std::fs::create_dir_all(&out).unwrap();
    let exposure = 0.5 / a.mean_luminance() as f32;
    a.save_png(out.join(format!("{width}_reference.png")), exposure)
        .unwrap();
    Image {
        width,
        height,
        pixels: frame.radiance.clone(),
    }
    .save_png(
        out.join(format!(
            "{width}_recon_{face}_{:?}_{rays}_{}.png",
            rec.settings.shading, rec.settings.sun_edge_rays
        )),
        exposure,
    )
    .unwrap();
    assert!(band.count > 0 && rest.count > 0);
    let (eb, er) = (
        band.corrected_rms() / mean_ref,
        rest.corrected_rms() / mean_ref,
    );
    let mean_abs =
        |(sum, own): (f64, f64), n: usize| (sum / n as f64 / mean_ref, own / n as f64 / mean_ref);
    let ((ab, rb), (ar, rr)) = (
        mean_abs(band_abs, band.count),
        mean_abs(rest_abs, rest.count),
    );
    println!(
        "{face}-px cubes at {width}×{height}, {:?}, {rays} shadow rays per pixel ({} at edges): \
         corrected relative RMS error in the edge band ({} px) {eb:.4}, rest of the floor ({} \
         px) {er:.4}: {:.2}× (target ≤ 2×); the reference's noise {:.4} and {:.4}; mean \
         luminance over the reference's {:.4} and {:.4}. Mean \
         absolute (the reference's noise in): band {ab:.3}, rest {ar:.3} ({:.2}×); the \
         reference's own (half A against the mean): {rb:.3} and {rr:.3}",
        rec.settings.shading,
        rec.settings.sun_edge_rays,
        band.count,
        rest.count,
        eb / er,
        band.noise_rms() / mean_ref,
        rest.noise_rms() / mean_ref,
        band.test / band.reference,
        rest.test / rest.reference,
        ab / ar,
    );
    // Away from the edge the bake's floor agrees with the path tracer.
    assert!(er < 0.15, "{er}");
    (eb, er)
}

/// At full size (release, about 2.5 minutes): 64-px cubes at 1280 × 720, the default
/// settings within 2× of the rest of the floor; beside them, 4 and 16 rays per pixel
/// without the edges measured, and the radiance at cube resolution. The reference takes
/// 512 samples per pixel: at 64, the uncertainty of its own variance in the band's few
/// hundred edge pixels is as large as the error measured.
#[test]
#[ignore]
fn sun_shadow_edge_at_1280x720() {
    let configs = [
        (Shading::Materials, 4, 32),
        (Shading::Materials, 4, 0),
        (Shading::Materials, 16, 0),
        (Shading::Radiance, 4, 32),
    ];
    let e = measure(64, 1280, 720, 512, &configs);
    let (band, rest) = e[0];
    assert!(band <= 2.0 * rest, "edge band {band:.4} against {rest:.4}");
}

/// CI's size: 16-px cubes at 320 × 180. The edge comes from the shadow rays, not the cubes,
/// so a tiny bake still gives a sharp one. Beside it, the same pack's radiance (which keeps
/// the sun, at cube resolution, as pack 2.0's lighting did): the runtime sun's edge must be
/// far better, and within a bound of the rest of the floor (4×: at 32 samples per pixel the
/// reference cannot measure finer; 2.8× today). And the same frame without the edge pixels
/// measured: measuring them must at least halve the band's error (a third of it today).
#[test]
fn sun_shadow_edge_is_at_screen_resolution() {
    let e = measure(
        16,
        320,
        180,
        32,
        &[
            (Shading::Materials, 4, 32),
            (Shading::Radiance, 4, 32),
            (Shading::Materials, 4, 0),
        ],
    );
    let ((eb, er), (cube_band, _), (unrefined, _)) = (e[0], e[1], e[2]);
    assert!(
        eb < 0.25 * cube_band,
        "edge band {eb:.3}, at cube resolution {cube_band:.3}"
    );
    assert!(eb < 4.0 * er.max(0.01), "edge band {eb:.3} against {er:.3}");
    assert!(
        eb < 0.5 * unrefined,
        "edge band {eb:.3}, without refining edge pixels {unrefined:.3}"
    );
}
