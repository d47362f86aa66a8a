//! Windows in geometry-assisted mode: through an open window the sky shows per pixel; through
//! a pane exported as `alphaMode: BLEND` (coverage 0.25) the pixel is the mean the path
//! tracer samples, 0.25 × the pane + 0.75 × the sky behind it, composited at full resolution
//! instead of the baked texels' mix (`plenoptic_recon`'s glazing module).

mod common;

use common::{PackSpec, WINDOW, reference, windowed_room, write_pack_with};
use plenoptic_pack::plenoptic_sky::{Environment, SkyParams, SunTrack, SunTrackSample};
use plenoptic_recon::{Camera, Mode, Reconstructor};
use plenoptic_trace::SceneAccel;
use plenoptic_trace::glam::Vec3;

const ALPHA: f32 = 0.25;

/// A sky of a few units (the test shading's range), lit by a low sun in front of the window.
fn sky() -> (Environment, SunTrack) {
    let sky = Environment::Sky(SkyParams {
        scale: 1.0,
        ..SkyParams::default()
    });
    let sun = SunTrack::new(vec![SunTrackSample {
        time: 0.0,
        direction: Vec3::new(0.3, 0.35, 1.0).normalize(),
        illuminance: Vec3::splat(50_000.0),
    }])
    .unwrap();
    (sky, sun)
}

/// Looking at the window from inside, between the two base views.
fn camera() -> Camera {
    let (lo, hi) = WINDOW;
    let centre = Vec3::new(0.5 * (lo.x + hi.x), 0.5 * (lo.y + hi.y), 2.5);
    Camera::look_at(Vec3::new(0.2, 1.3, 1.0), centre, Vec3::Y, 1.3, 64, 48).unwrap()
}

fn pack(dir: &std::path::Path, name: &str, alpha: Option<f32>, glazing: bool) -> Reconstructor {
    let path = dir.join(name);
    let spec = PackSpec {
        glazing,
        ..PackSpec::segment(2, vec![0.0], 48)
    };
    let (env, sun) = sky();
    write_pack_with(&windowed_room(alpha), &spec, &path, Some((env, Some(sun))));
    Reconstructor::open(&path).unwrap()
}

/// Mean over `pixels` of |got − want| / (want + 0.02), largest channel.
fn mean_error(got: &[Vec3], want: &[Vec3], pixels: &[usize]) -> f32 {
    pixels
        .iter()
        .map(|&j| ((got[j] - want[j]).abs() / (want[j] + Vec3::splat(0.02))).max_element())
        .sum::<f32>()
        / pixels.len().max(1) as f32
}

#[test]
fn an_open_window_shows_the_sky_and_a_blended_pane_is_composited_over_it() {
    let dir = tempfile::tempdir().unwrap();
    let camera = camera();
    let basis = camera.basis();
    let w = camera.width as usize;
    let direction = |j: usize| basis.direction((j % w) as f32 + 0.5, (j / w) as f32 + 0.5);
    let (env, track) = sky();
    let env = env.at(Some(track.at(0.0).0));

    // Open window: the opening's pixels are the sky, exactly.
    let open = pack(dir.path(), "open.pack", None, true);
    let (frame, _) = open.render(&camera, 0.0, Mode::GeometryAssisted).unwrap();
    let opening: Vec<usize> = (0..frame.object.len())
        .filter(|&j| frame.object[j] == 0)
        .collect();
    let fraction = opening.len() as f32 / frame.object.len() as f32;
    eprintln!("window: {:.1} % of the frame", 100.0 * fraction);
    assert!((0.2..0.8).contains(&fraction), "window fraction {fraction}");
    for &j in &opening {
        let e = env.radiance(direction(j));
        assert!((frame.radiance[j] - e).abs().max_element() <= 1e-3 * e.max_element());
    }

    // Glazed: the pane's pixels against 0.25 × the pane (shaded as if opaque) + 0.75 × sky.
    let glazed = pack(dir.path(), "glazed.pack", Some(ALPHA), true);
    let solid = windowed_room(Some(1.0));
    let accel = SceneAccel::new(&solid).unwrap();
    let pane_ref = reference(&accel.at_time(0.0), &camera).pixels;
    let pane_id = solid.objects.len() as u32;
    let mask = glazed.proxy().unwrap().mask_raster(&camera, 0.0);
    let pane: Vec<usize> = (0..mask.object.len())
        .filter(|&j| mask.object[j] == pane_id)
        .collect();
    assert!(
        pane.len() * 10 >= opening.len() * 9,
        "the pane fills the window"
    );
    let mut want = vec![Vec3::ZERO; camera.pixel_count()];
    for &j in &pane {
        want[j] = pane_ref[j] * ALPHA + env.radiance(direction(j)) * (1.0 - ALPHA);
    }
    let (frame, report) = glazed.render(&camera, 0.0, Mode::GeometryAssisted).unwrap();
    assert_eq!(report.glazing_pixels, pane.len());
    let composited = mean_error(&frame.radiance, &want, &pane);
    let luminance = |c: &[Vec3]| {
        pane.iter()
            .map(|&j| c[j].dot(Vec3::new(0.2126, 0.7152, 0.0722)))
            .sum::<f32>()
    };
    let ratio = luminance(&frame.radiance) / luminance(&want);

    // The same pack drawn as before, the pane an opaque proxy showing its baked texels.
    let baked = pack(dir.path(), "baked.pack", Some(ALPHA), false);
    let (old, report) = baked.render(&camera, 0.0, Mode::GeometryAssisted).unwrap();
    assert_eq!(report.glazing_pixels, 0);
    let texels = mean_error(&old.radiance, &want, &pane);
    eprintln!(
        "pane pixels {}: mean relative error composited {composited:.4}, baked texels \
         {texels:.4}; mean-luminance ratio composited {ratio:.4}, baked texels {:.4}",
        pane.len(),
        luminance(&old.radiance) / luminance(&want)
    );
    assert!(
        (ratio - 1.0).abs() < 0.02,
        "composited mean luminance ratio {ratio}"
    );
    // Most of the error is the pane's own reconstruction where the sky below the horizon is
    // black behind it: a quarter of the cube's texels saw the pane, the rest is hole fill.
    assert!(composited < 0.1, "composited glazing error {composited}");
    assert!(
        composited * 4.0 < texels,
        "{composited} vs {texels}: compositing beats the baked texels"
    );
    // Pixels beside the window are untouched by the glazing.
    let room: Vec<usize> = (0..mask.object.len())
        .filter(|&j| mask.object[j] != 0 && mask.object[j] != pane_id)
        .collect();
    let (plain, _) = open.render(&camera, 0.0, Mode::GeometryAssisted).unwrap();
    let beside = mean_error(&frame.radiance, &plain.radiance, &room);
    assert!(beside < 0.02, "room pixels changed by {beside}");
}
