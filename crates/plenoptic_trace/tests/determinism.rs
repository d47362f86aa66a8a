//! The same inputs give the same pixels, bit for bit, for any number of threads.

use glam::Vec3;
use plenoptic_trace::{
    AmbientField, AmbientSettings, CubeCamera, MultiStageRenderer, MultiStageSettings, PathTracer,
    PathTracerSettings, SceneAccel, shapes,
};

fn bits(img: &plenoptic_trace::Image<plenoptic_trace::RadianceSample>) -> Vec<u32> {
    img.pixels
        .iter()
        .flat_map(|s| {
            let r = s.radiance.to_array().map(f32::to_bits);
            [r[0], r[1], r[2], s.distance.to_bits(), s.object]
        })
        .collect()
}

#[test]
fn renders_are_bit_identical_across_runs_and_thread_counts() {
    let scene = shapes::furnished_room();
    let accel = SceneAccel::new(&scene).unwrap();
    let cam = shapes::room_camera(24, 18).unwrap();
    let run = || {
        let placed = accel.at_time(0.5);
        let pt = PathTracer::new(PathTracerSettings {
            samples_per_pixel: 4,
            ..PathTracerSettings::default()
        })
        .render(&placed, &cam);
        let field = AmbientField::build(
            &placed,
            &AmbientSettings {
                quality: 0.1,
                rays_per_point: 8,
                seed: 4,
                ..AmbientSettings::low()
            },
        )
        .unwrap();
        let renderer = MultiStageRenderer::new(
            MultiStageSettings {
                samples_per_pixel: 2,
                ..MultiStageSettings::default()
            },
            &field,
        );
        let ms = renderer.render(&placed, &cam);
        let cube = renderer.render_cube(
            &placed,
            &CubeCamera::new(Vec3::new(0.0, 1.0, 0.0), 6).unwrap(),
        );
        (
            bits(&pt),
            bits(&ms),
            cube.iter().flat_map(bits).collect::<Vec<_>>(),
        )
    };
    let a = run();
    let b = run();
    assert!(a == b, "two runs differ");
    for threads in [1, 3] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let c = pool.install(run);
        assert!(a == c, "{threads} threads differ");
    }
    // Different seeds do differ.
    let placed = accel.at_time(0.5);
    let other = PathTracer::new(PathTracerSettings {
        samples_per_pixel: 4,
        seed: 99,
        ..PathTracerSettings::default()
    })
    .render(&placed, &cam);
    assert!(bits(&other) != a.0);
}

#[test]
fn ambient_fields_interpolate_in_time() {
    let scene = shapes::furnished_room();
    let accel = SceneAccel::new(&scene).unwrap();
    let settings = AmbientSettings {
        quality: 0.1,
        rays_per_point: 16,
        seed: 4,
        max_bounces: 2,
        ..AmbientSettings::low()
    };
    let layout = std::sync::Arc::new(
        plenoptic_trace::multistage::FieldLayout::new(&scene, settings.quality).unwrap(),
    );
    let f0 = AmbientField::compute(&accel.at_time(0.0), layout.clone(), &settings);
    let f2 = AmbientField::compute(&accel.at_time(2.0), layout.clone(), &settings);
    let mid = AmbientField::lerp(&f0, &f2, 0.5).unwrap();
    assert_eq!(mid.time(), 1.0);
    let expected = (f0.mean_irradiance() + f2.mean_irradiance()) * 0.5;
    assert!(mid.mean_irradiance().abs_diff_eq(expected, 1e-4));
    // Fields on another layout do not mix.
    let other = AmbientField::build(
        &accel.at_time(0.0),
        &AmbientSettings {
            quality: 0.5,
            ..settings
        },
    )
    .unwrap();
    assert!(AmbientField::lerp(&f0, &other, 0.5).is_err());
    println!(
        "field relative RMS between t = 0 and t = 2: {:.4}",
        f0.relative_rms(&f2)
    );
}
