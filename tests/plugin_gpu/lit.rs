//! The app's own meshes lit by the pack (`bevy_plenoptic::lit`): a white, rough
//! `StandardMaterial` sphere that is not in the pack, inside the test room, shows the diffuse
//! light of its nearest base view's radiance at the camera's time, through the irradiance
//! volume the plugin keeps over the scene (each voxel the ambient cube of its nearest base
//! view), wherever the camera is.

use crate::common::*;
use crate::pack::{PackSpec, room, write_pack};
use bevy::camera::Hdr;
use bevy::light::GlobalAmbientLight;
use bevy::prelude::*;
use bevy_plenoptic::lit::PackEnvironmentLight;
use bevy_plenoptic::lit::probes::{PlenopticProbe, ReflectionProbes};
use bevy_plenoptic::prelude::*;
use bevy_plenoptic::streaming::StreamState;
use plenoptic_pack::cube::texel_direction;
use plenoptic_recon::temporal::bracketing;

/// The irradiance over π (the outgoing radiance of a white Lambertian surface) at normal `n`
/// under the cubes `keys` (radiance per texel, weight), summed over their texels with each
/// texel's solid angle.
fn white_lambert(keys: &[(Vec<Vec3>, f32)], face: u32, n: Vec3) -> Vec3 {
    let mut sum = Vec3::ZERO;
    for (cube, w) in keys {
        for (i, l) in cube.iter().enumerate() {
            let d = texel_direction(face, i);
            // Solid angle of a texel whose centre is at d: (2/n)² · cos³ of its angle to the
            // face's axis.
            let axis = d.abs().max_element();
            let omega = (2.0 / face as f32).powi(2) * axis.powi(3);
            sum += *l * (*w * n.dot(d).max(0.0) * omega);
        }
    }
    sum / std::f32::consts::PI
}

/// What [`sphere_scene`] measured: the shown and the expected radiance of each sphere pixel
/// away from the silhouette, for each expected view.
struct SpherePixels {
    shown: Vec<Vec3>,
    /// Per base view asked for: its keys' white-Lambert radiance at each pixel's normal.
    expected: Vec<Vec<Vec3>>,
    /// The same through the view's ambient cube (Valve's six directions, blended by the
    /// squared normal, as Bevy samples an irradiance volume).
    ambient: Vec<Vec<Vec3>>,
    /// The camera's heaviest base view.
    heaviest: usize,
    /// The plugin's light probes: (base view, position, box side).
    probes: Vec<(u32, Vec3, f32)>,
    /// Whether the device has the binding arrays Bevy needs to apply reflection probes.
    binding_arrays: bool,
}

/// A white rough sphere (`centre`, `radius`) in the 3-view test room (faces of 16 texels),
/// seen from `eye` towards `target` at t = 0.7; its pixels, and the radiance expected under
/// each of `views`' cubes at t.
fn sphere_scene(
    eye: Vec3,
    target: Vec3,
    centre: Vec3,
    radius: f32,
    views: &[usize],
) -> SpherePixels {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("room.pack");
    let face = 16;
    write_pack(
        &room(true),
        &PackSpec::segment(3, vec![0.0, 1.0, 2.0], face),
        &path,
    );
    let t = 0.7;
    let mut app = headless_app_in(dir.path());
    app.world_mut().resource_mut::<PlenopticSettings>().backend = Backend::Gpu;
    // Bevy's own ambient light at its default (80 cd/m², hundreds of times this room's light
    // at the camera's exposure): the plugin turns it off for a camera it lights with the pack,
    // so that only the pack lights the sphere.
    assert_eq!(
        app.world().resource::<GlobalAmbientLight>().brightness,
        GlobalAmbientLight::default().brightness
    );
    let handle: Handle<RadiancePack> = app.world().resource::<AssetServer>().load("room.pack");
    let image = hdr_target(&mut app);
    let transform = Transform::from_translation(eye).looking_at(target, Vec3::Y);
    let camera = app
        .world_mut()
        .spawn((
            camera_into(image.clone(), transform),
            Hdr,
            Msaa::Off,
            PlenopticCamera {
                playback: Playback::Manual,
                time: t,
                ..PlenopticCamera::new(handle.clone())
            },
        ))
        .id();
    let mesh = app
        .world_mut()
        .resource_mut::<Assets<Mesh>>()
        .add(Sphere::new(radius).mesh().ico(5).unwrap());
    let material = app
        .world_mut()
        .resource_mut::<Assets<StandardMaterial>>()
        .add(StandardMaterial {
            base_color: Color::WHITE,
            perceptual_roughness: 1.0,
            reflectance: 0.0,
            ..default()
        });
    app.world_mut().spawn((
        Mesh3d(mesh),
        MeshMaterial3d(material),
        Transform::from_translation(centre),
    ));
    for _ in 0..500 {
        app.update();
        let ready = app.world().get::<StreamState>(camera).unwrap().complete
            && app.world().get::<PackEnvironmentLight>(camera).is_some();
        if ready {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    assert!(
        app.world().get::<PackEnvironmentLight>(camera).is_some(),
        "the camera got no environment light"
    );
    let shown = rgba16f_pixels(&settled_frame(&mut app, &image));
    let mut q = app.world_mut().query::<(&PlenopticProbe, &Transform)>();
    let mut probes: Vec<(u32, Vec3, f32)> = q
        .iter(app.world())
        .map(|(p, t)| (p.view, t.translation, t.scale.x))
        .collect();
    probes.sort_by_key(|p| p.0);
    // The plugin's reading of Bevy's own test (binding arrays), made once in `finish`.
    let binding_arrays = app.world().resource::<ReflectionProbes>().0;

    // The expected radiance of the sphere's pixels, from the pack itself: each asked view at
    // t, its bracketing keys blended.
    let (heaviest, keys) = {
        let packs = app.world().resource::<Assets<RadiancePack>>();
        let pack = packs.get(&handle).unwrap();
        let m = pack.reader.manifest();
        let heaviest = ReconSettings::default().view_weights(m, &pack.usable_views, eye)[0].0;
        let keys: Vec<Vec<(Vec<Vec3>, f32)>> = views
            .iter()
            .map(|&v| {
                let (k0, k1, f) = bracketing(&m.base_views[v].time_keys, t).unwrap();
                let cube = |k: usize| pack.reader.radiance(v as u32, k as u32).unwrap().texels;
                vec![(cube(k0), 1.0 - f), (cube(k1), f)]
            })
            .collect();
        (heaviest, keys)
    };
    let basis = plenoptic_recon::Camera::new(
        eye,
        transform.rotation,
        std::f32::consts::FRAC_PI_4,
        WIDTH,
        HEIGHT,
    )
    .unwrap()
    .basis();
    let mut shown_px = Vec::new();
    let mut expected = vec![Vec::new(); views.len()];
    let mut ambient = vec![Vec::new(); views.len()];
    let cubes: Vec<Vec<Vec3>> = keys
        .iter()
        .map(|k| {
            [
                Vec3::X,
                Vec3::NEG_X,
                Vec3::Y,
                Vec3::NEG_Y,
                Vec3::Z,
                Vec3::NEG_Z,
            ]
            .map(|a| white_lambert(k, face, a))
            .to_vec()
        })
        .collect();
    for y in 0..HEIGHT {
        for x in 0..WIDTH {
            let sx = (2.0 * (x as f32 + 0.5) / WIDTH as f32 - 1.0) * basis.tan_x;
            let sy = (1.0 - 2.0 * (y as f32 + 0.5) / HEIGHT as f32) * basis.tan_y;
            let d = (basis.forward + sx * basis.right + sy * basis.up).normalize();
            // The ray against the sphere.
            let oc = eye - centre;
            let b = oc.dot(d);
            let disc = b * b - (oc.length_squared() - radius * radius);
            if disc <= 0.0 {
                continue;
            }
            let n = (eye + (-b - disc.sqrt()) * d - centre).normalize();
            // Away from the silhouette (the mesh is faceted, the pixel may miss it there).
            if n.dot(-d) < 0.5 {
                continue;
            }
            shown_px.push(shown[(y * WIDTH + x) as usize]);
            for (e, k) in expected.iter_mut().zip(&keys) {
                e.push(white_lambert(k, face, n));
            }
            for (e, c) in ambient.iter_mut().zip(&cubes) {
                let side = |i: usize, x: f32| c[2 * i + (x < 0.0) as usize] * x * x;
                e.push(side(0, n.x) + side(1, n.y) + side(2, n.z));
            }
        }
    }
    SpherePixels {
        shown: shown_px,
        expected,
        ambient,
        heaviest,
        probes,
        binding_arrays,
    }
}

/// (mean relative error, share within 5 %, share within 20 %, mean luminance ratio) of
/// `gpu` against `cpu`, the error per pixel the largest channel's, as the GPU-against-CPU
/// tests take it.
fn errors(gpu: &[Vec3], cpu: &[Vec3]) -> (f32, f32, f32, f32) {
    let err: Vec<f32> = gpu
        .iter()
        .zip(cpu)
        .map(|(g, c)| ((*g - *c).abs() / (c.abs() + Vec3::splat(0.02))).max_element())
        .collect();
    let mean = err.iter().sum::<f32>() / err.len() as f32;
    let within = |limit: f32| err.iter().filter(|e| **e < limit).count() as f32 / err.len() as f32;
    let lum = |px: &[Vec3]| px.iter().map(|c| c.x + c.y + c.z).sum::<f32>() / px.len() as f32;
    (mean, within(0.05), within(0.2), lum(gpu) / lum(cpu))
}

/// A sphere in front of the camera, nearest base view 1 (also the camera's heaviest): its
/// pixels show view 1's ambient cube, blended by the squared normal as Bevy samples it.
#[test]
fn own_mesh_is_lit_by_the_pack_near_it() {
    let (eye, target) = (Vec3::new(0.3, 1.3, 1.0), Vec3::new(0.0, 1.0, -1.5));
    let s = sphere_scene(eye, target, Vec3::new(0.1, 1.1, -0.4), 0.45, &[1]);
    assert_eq!(s.heaviest, 1);
    let gpu = &s.shown;
    assert!(gpu.len() > 200, "{} sphere pixels", gpu.len());
    let (mean, f5, f20, ratio) = errors(gpu, &s.ambient[0]);
    let (exact, _, _, exact_ratio) = errors(gpu, &s.expected[0]);
    eprintln!(
        "sphere: {} pixels; against view 1's ambient cube: mean relative error {mean:.4}, \
         within 5 % {f5:.3}, within 20 % {f20:.3}, luminance ratio {ratio:.3}; against the \
         exact irradiance: mean {exact:.3}, ratio {exact_ratio:.3}",
        gpu.len()
    );
    // The expected values vary over the sphere: a uniform grey would not pass.
    let sum = |c: &Vec3| c.x + c.y + c.z;
    let spread = s.ambient[0].iter().map(sum).fold(0.0f32, f32::max)
        / s.ambient[0].iter().map(sum).fold(f32::MAX, f32::min);
    eprintln!("brightest over darkest expected pixel: {spread:.2}");
    assert!(spread > 1.3, "{spread}");
    // Measured on lavapipe: 857 pixels, mean 0.008, 97 % within 5 %, ratio 0.995; the
    // ambient cube against the exact irradiance: mean 0.11, ratio 1.085 (Valve's six
    // directions are an approximation). The camera's environment light alone matches the
    // exact irradiance within 0.018 (ratio 1.004) when its cubemap's z is negated for Bevy's
    // left-handed cubemaps, and is off by 1.54 (ratio 2.15) without.
    assert!((ratio - 1.0).abs() < 0.03, "mean luminance ratio {ratio}");
    assert!(mean < 0.05 && f20 > 0.95, "mean {mean}, within 20 %: {f20}");
}

/// A sphere placed at base view 0, seen from base view 2 (the camera's heaviest view): it
/// shows view 0's light, not the camera's. The plugin keeps a light probe at every base view
/// (boxes of 1 m: the views are 1 m apart) and the irradiance volume takes its voxels from
/// them. (Bevy applies the probes' reflections only where the device has binding arrays;
/// Mesa 22.3's lavapipe has none. The diffuse light comes from the volume on every device.)
#[test]
fn own_mesh_at_a_base_view_is_lit_by_that_view() {
    let (a, b) = crate::pack::segment_ends();
    let eye = b + Vec3::new(0.0, 0.0, 0.3);
    let s = sphere_scene(eye, a, a, 0.3, &[0, 2]);
    assert_eq!(s.heaviest, 2);
    eprintln!("probes: {:?}", s.probes);
    assert_eq!(s.probes.len(), 3, "{:?}", s.probes);
    for (v, at, side) in &s.probes {
        let view = a.lerp(b, *v as f32 / 2.0);
        assert!(
            (*at - view).length() < 1e-5 && (side - 1.0).abs() < 1e-5,
            "{v}: {at} {side}"
        );
    }
    assert!(s.shown.len() > 40, "{} sphere pixels", s.shown.len());
    let (mean, f5, f20, ratio) = errors(&s.shown, &s.ambient[0]);
    let (camera, _, _, camera_ratio) = errors(&s.shown, &s.ambient[1]);
    let (apart, _, _, _) = errors(&s.ambient[1], &s.ambient[0]);
    eprintln!(
        "sphere at view 0: {} pixels; against view 0's ambient cube: mean {mean:.4}, within \
         5 % {f5:.3}, within 20 % {f20:.3}, luminance ratio {ratio:.3}; against the camera's \
         view 2: mean {camera:.4}, ratio {camera_ratio:.3}; the two apart by {apart:.3}; \
         binding arrays: {}",
        s.shown.len(),
        s.binding_arrays
    );
    // The two views light the sphere differently, so the match below is view 0's.
    assert!(apart > 0.1, "{apart}");
    // Measured on lavapipe: mean 0.005, 100 % within 5 %, ratio 0.995 (against view 2:
    // mean 0.35, ratio 1.29).
    assert!((ratio - 1.0).abs() < 0.03, "mean luminance ratio {ratio}");
    assert!(mean < 0.05 && f20 > 0.95, "mean {mean}, within 20 %: {f20}");
}
