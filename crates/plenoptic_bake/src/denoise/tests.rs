//! Unit tests of the denoiser on synthetic cubes with known guides and noise.

use glam::Vec3;
use plenoptic_trace::RadianceSample;

use super::cube::CubeGrid;
use super::{DenoiseSettings, FIREFLY_RATIO, LightingCube, denoise};

/// Deterministic standard normal numbers (splitmix64 + Box–Muller).
struct Gauss(u64);

impl Gauss {
    fn next_u01(&mut self) -> f32 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^= z >> 31;
        ((z >> 40) as f32 + 0.5) / (1u64 << 24) as f32
    }

    fn next(&mut self) -> f32 {
        let (a, b) = (self.next_u01(), self.next_u01());
        (-2.0 * a.ln()).sqrt() * (std::f32::consts::TAU * b).cos()
    }
}

/// Variance of the luminance of RGB noise of unit variance per channel: Σ (Rec. 709 weight)².
const LUMINANCE_NOISE: f32 = 0.2126 * 0.2126 + 0.7152 * 0.7152 + 0.0722 * 0.0722;

/// What a texel sees: `(object, distance, normal)`; object 0 is a miss.
type Geometry = dyn Fn(Vec3) -> (u32, f32, Vec3);

/// A cube of face size `n` over `geometry`, lighting `light(dir, point)` (albedo 0.5, a
/// small residual), with Gaussian noise of standard deviation `sigma` per channel.
fn cube(
    n: u32,
    geometry: &Geometry,
    light: impl Fn(Vec3, Vec3) -> f32,
    sigma: f32,
    seed: u64,
) -> LightingCube {
    let grid = CubeGrid::new(n);
    let mut g = Gauss(seed);
    let samples: Vec<RadianceSample> = (0..grid.len())
        .map(|i| {
            let d = grid.direction(i);
            let (object, distance, normal) = geometry(d);
            if object == 0 {
                return RadianceSample {
                    radiance: Vec3::splat(0.3),
                    ..RadianceSample::MISS
                };
            }
            let albedo = Vec3::splat(0.5);
            let l = light(d, d * distance);
            let lighting = Vec3::new(
                l + sigma * g.next(),
                l + sigma * g.next(),
                l + sigma * g.next(),
            )
            .max(Vec3::ZERO);
            let diffuse = albedo * lighting;
            RadianceSample {
                radiance: diffuse + Vec3::splat(0.01),
                distance,
                object: object - 1,
                normal,
                diffuse,
                albedo,
                // The noise of the lighting's luminance, as the renderer would report it.
                lighting_variance: sigma * sigma * LUMINANCE_NOISE,
                ..RadianceSample::MISS
            }
        })
        .collect();
    LightingCube::from_samples(n, samples.iter())
}

/// A closed cube-shaped room of half-size 1 around the base view, one object.
fn room(d: Vec3) -> (u32, f32, Vec3) {
    let a = d.abs();
    let axis = if a.x >= a.y && a.x >= a.z {
        Vec3::X * d.x.signum()
    } else if a.y >= a.z {
        Vec3::Y * d.y.signum()
    } else {
        Vec3::Z * d.z.signum()
    };
    (1, 1.0 / d.dot(axis), -axis)
}

/// An infinite floor at y = −1, nothing above the horizon.
fn floor(d: Vec3) -> (u32, f32, Vec3) {
    if d.y >= -1e-4 {
        (0, f32::INFINITY, Vec3::ZERO)
    } else {
        (1, 1.0 / -d.y, Vec3::Y)
    }
}

fn mean_and_rms(values: impl Iterator<Item = f32>, truth: f32) -> (f32, f32) {
    let (mut n, mut s, mut s2) = (0.0f64, 0.0f64, 0.0f64);
    for v in values {
        n += 1.0;
        s += f64::from(v);
        s2 += f64::from(v - truth).powi(2);
    }
    ((s / n) as f32, (s2 / n).sqrt() as f32)
}

#[test]
fn split_recovers_the_radiance_and_leaves_misses_alone() {
    let c = cube(8, &room, |_, _| 2.0, 0.3, 1);
    for i in 0..c.len() {
        let expect = c.albedo[i] * c.lighting[i] + c.residual[i];
        assert!((c.radiance(i) - expect).abs().max_element() < 1e-6);
        assert!((c.residual[i] - Vec3::splat(0.01)).abs().max_element() < 1e-5);
    }
    let mut f = cube(8, &floor, |_, _| 1.0, 0.3, 2);
    let before = f.clone();
    denoise(&mut f, &DenoiseSettings::default());
    for i in 0..f.len() {
        if f.object[i] == 0 {
            assert_eq!(f.radiance(i), before.radiance(i));
        }
        assert_eq!(f.residual[i], before.residual[i]);
        assert_eq!(f.albedo[i], before.albedo[i]);
    }
}

/// A sample lit by the sun, a lamp and the ambient field, with a highlight: the lighting
/// keeps only the ambient share, and the texel's radiance is what the renderer returned.
#[test]
fn the_runtimes_direct_light_leaves_the_lighting_and_stays_in_the_radiance() {
    let albedo = Vec3::new(0.5, 0.4, 0.3);
    let (ambient, sun, lamp) = (Vec3::splat(0.2), Vec3::splat(0.8), Vec3::splat(0.6));
    let highlight = Vec3::splat(0.05);
    let s = RadianceSample {
        radiance: albedo * (ambient + sun + lamp) + highlight,
        diffuse: albedo * (ambient + sun + lamp),
        albedo,
        sun: albedo * sun,
        sun_diffuse: albedo * sun,
        lamp_diffuse: albedo * lamp,
        ambient: albedo * ambient,
        distance: 1.0,
        object: 0,
        normal: Vec3::Y,
        ..RadianceSample::MISS
    };
    let c = LightingCube::from_samples(1, std::iter::repeat_n(&s, 6));
    assert!(
        (c.lighting[0] - ambient).abs().max_element() < 1e-6,
        "{}",
        c.lighting[0]
    );
    assert!((c.residual[0] - highlight).abs().max_element() < 1e-6);
    assert!((c.radiance(0) - s.radiance).abs().max_element() < 1e-6);
    assert_eq!(
        super::split_sample(&s),
        (c.lighting[0], c.residual[0]),
        "a volume sample is split as a texel"
    );
}

#[test]
fn noise_on_a_flat_room_is_reduced_by_a_large_factor() {
    let sigma = 0.2;
    let c = cube(64, &room, |_, _| 1.0, sigma, 3);
    let lum = |c: &LightingCube| {
        c.lighting
            .iter()
            .map(|l| plenoptic_trace::image::luminance(*l))
            .collect::<Vec<_>>()
    };
    let (m0, r0) = mean_and_rms(lum(&c).into_iter(), 1.0);
    for sample_variance in [true, false] {
        let mut d = c.clone();
        let settings = DenoiseSettings {
            sample_variance,
            ..DenoiseSettings::default()
        };
        denoise(&mut d, &settings);
        let (m1, r1) = mean_and_rms(lum(&d).into_iter(), 1.0);
        println!(
            "noise (sample variance {sample_variance}): mean {m0:.4} → {m1:.4}, rms {r0:.4} → {r1:.4} ({:.1}×)",
            r0 / r1
        );
        assert!((m1 - 1.0).abs() < 0.01, "mean {m1}");
        assert!(r1 < r0 / 8.0, "rms {r0} → {r1}");
    }
}

#[test]
fn a_shadow_edge_well_above_the_noise_is_kept() {
    // One flat surface, lighting 1 and 3 on either side of x = 0 (a sun shadow's edge), with
    // noise of a known variance reported by the renderer.
    let level = |d: Vec3, _: Vec3| if d.x < 0.0 { 1.0 } else { 3.0 };
    let mut c = cube(64, &room, level, 0.05, 10);
    let grid = CubeGrid::new(64);
    let side = move |i: usize| {
        let d = grid.direction(i);
        // The ±Z walls, where the edge runs down the middle of the face.
        (d.z.abs() > d.x.abs() && d.z.abs() > d.y.abs()).then_some(d.x >= 0.0)
    };
    assert_edge_kept(&mut c, side, "shadow edge");
}

/// Lighting 1 on one side and 3 on the other of an edge where the guides change; after
/// filtering, the texels next to the edge keep their side's level.
fn assert_edge_kept(c: &mut LightingCube, side: impl Fn(usize) -> Option<bool>, name: &str) {
    let grid = CubeGrid::new(c.face_size);
    denoise(c, &DenoiseSettings::default());
    let lum = |i: usize| plenoptic_trace::image::luminance(c.lighting[i]);
    for (which, truth) in [(false, 1.0f32), (true, 3.0f32)] {
        // Texels on this side with a 1-texel neighbour on the other side.
        let border: Vec<usize> = (0..c.len())
            .filter(|&i| side(i) == Some(which))
            .filter(|&i| {
                let (f, x, y) = grid.coords(i);
                [(-1, 0), (1, 0), (0, -1), (0, 1)]
                    .iter()
                    .any(|&(dx, dy)| side(grid.offset(f, x, y, dx, dy)) == Some(!which))
            })
            .collect();
        assert!(border.len() > 10, "{name}: {} border texels", border.len());
        let (m, _) = mean_and_rms(border.iter().map(|&i| lum(i)), truth);
        println!(
            "{name}: side {truth}: {} texels at the edge, mean {m:.4}",
            border.len()
        );
        assert!(
            (m - truth).abs() < 0.03 * truth,
            "{name}: side {truth} mean {m}"
        );
    }
}

#[test]
fn an_object_id_edge_is_not_blurred() {
    // The room split into two objects at x = 0.
    let geometry = |d: Vec3| {
        let (_, t, n) = room(d);
        (if d.x < 0.0 { 1 } else { 2 }, t, n)
    };
    let level = |d: Vec3, _: Vec3| if d.x < 0.0 { 1.0 } else { 3.0 };
    let mut c = cube(64, &geometry, level, 0.2, 4);
    let objects = c.object.clone();
    assert_edge_kept(&mut c, |i| Some(objects[i] == 2), "id edge");
}

#[test]
fn a_depth_step_is_not_blurred() {
    // One object; on the floor, a platform raised to y = −0.6 for x ≥ 0.
    let geometry = |d: Vec3| {
        let (o, t, n) = room(d);
        if n == Vec3::Y {
            let tf = 1.0 / -d.y;
            if d.x * tf >= 0.0 {
                return (o, 0.6 / -d.y, n);
            }
        }
        (o, t, n)
    };
    let level = |_: Vec3, p: Vec3| if p.y > -0.8 { 3.0 } else { 1.0 };
    let mut c = cube(64, &geometry, level, 0.2, 5);
    let grid = CubeGrid::new(64);
    let (normal, dist) = (c.normal.clone(), c.distance.clone());
    let side =
        move |i: usize| (normal[i] == Vec3::Y).then(|| (grid.direction(i) * dist[i]).y > -0.8);
    assert_edge_kept(&mut c, side, "depth step");
}

/// The texel pairs across the seam between −Y (face 3) and +X (face 0), `(on −Y, on +X)`,
/// with their inner neighbours `(on −Y, on +X)`.
/// Found through directions here, not with [`CubeGrid::offset`], so that the test does not
/// depend on the addressing it checks.
fn seam_pairs(grid: &CubeGrid) -> Vec<[usize; 4]> {
    use plenoptic_pack::cube::{direction_to_texel, face_uv_to_direction};
    let n = grid.face_size();
    let at = |face: usize, i: f32, j: f32| {
        let d = face_uv_to_direction(face, (i + 0.5) / n as f32, (j + 0.5) / n as f32);
        direction_to_texel(n as u32, d)
    };
    let mut pairs = Vec::new();
    for k in n / 4..3 * n / 4 {
        // On −Y, u = 1 is +X (sc = +rx): column n − 1.
        let a = 3 * n * n + k * n + (n - 1);
        let (k, last) = (k as f32, (n - 1) as f32);
        let b = at(3, last + 1.0, k);
        let a_in = at(3, last - 1.0, k);
        let b_in = at(3, last + 2.0, k);
        assert_eq!(grid.coords(b).0, 0, "the neighbour across is on +X");
        assert_eq!(grid.coords(b_in).0, 0, "and the next one too");
        pairs.push([a, b, a_in, b_in]);
    }
    pairs
}

#[test]
fn a_constant_across_a_seam_stays_constant() {
    let mut c = cube(32, &floor, |_, _| 2.0, 0.0, 6);
    let guides_only = DenoiseSettings {
        sigma_luminance: f32::INFINITY,
        ..DenoiseSettings::default()
    };
    denoise(&mut c, &guides_only);
    for i in 0..c.len() {
        if c.filterable(i) {
            assert!((c.lighting[i] - Vec3::splat(2.0)).abs().max_element() < 1e-4);
        }
    }
}

#[test]
fn a_gradient_across_a_seam_stays_continuous() {
    let n = 64;
    let grid = CubeGrid::new(n);
    // Smooth and bounded over the sphere of directions, changing across the seam between
    // −Y and +X (a gradient linear in the floor's x would run to infinity at the horizon,
    // and any footprint in texel space would average it unevenly).
    let light = |d: Vec3, _: Vec3| 2.0 + d.x + 0.5 * d.z;
    let input = cube(n, &floor, light, 0.0, 7);
    let mut c = input.clone();
    // Noise-free input reports no variance, which would stop the luminance weight from
    // filtering at all: weights from the guides alone, the widest footprint.
    let guides_only = DenoiseSettings {
        sigma_luminance: f32::INFINITY,
        ..DenoiseSettings::default()
    };
    denoise(&mut c, &guides_only);
    let l = |c: &LightingCube, i: usize| c.lighting[i].x;
    let (mut worst_jump, mut worst_inner, mut worst_dev) = (0.0f32, 0.0f32, 0.0f32);
    for [a, b, a_in, b_in] in seam_pairs(&grid) {
        // The step across the seam against the steps beside it, before and after.
        let jump = (l(&c, b) - l(&c, a)).abs();
        let inner = (l(&c, a) - l(&c, a_in))
            .abs()
            .max((l(&c, b_in) - l(&c, b)).abs());
        let inner_in = (l(&input, a) - l(&input, a_in))
            .abs()
            .max((l(&input, b_in) - l(&input, b)).abs());
        let jump_in = (l(&input, b) - l(&input, a)).abs();
        worst_jump = worst_jump.max(jump / jump_in.max(1e-6));
        worst_inner = worst_inner.max(jump / inner.max(inner_in).max(1e-6));
        worst_dev = worst_dev.max(
            (l(&c, a) - l(&input, a))
                .abs()
                .max((l(&c, b) - l(&input, b)).abs()),
        );
    }
    println!(
        "seam: jump/input jump ≤ {worst_jump:.3}, jump/inner step ≤ {worst_inner:.3}, |out − in| ≤ {worst_dev:.4}"
    );
    assert!(worst_jump < 1.5, "the seam step grew {worst_jump}×");
    assert!(
        worst_inner < 2.0,
        "the seam step is {worst_inner}× the steps beside it"
    );
    // Not vacuous: the footprint (radius 62 texels) does reshape the gradient near the
    // horizon's cut, and it does so on both sides of the seam alike.
    assert!(worst_dev > 1e-3, "the filter did nothing ({worst_dev})");
}

#[test]
fn two_keys_of_a_static_scene_come_out_closer() {
    let settings = DenoiseSettings::default();
    let light = |d: Vec3, _: Vec3| 1.0 + 0.3 * d.y;
    let (mut a, mut b) = (
        cube(48, &room, light, 0.2, 8),
        cube(48, &room, light, 0.2, 9),
    );
    let diff = |a: &LightingCube, b: &LightingCube| {
        let s: f64 = (0..a.len())
            .map(|i| f64::from((a.radiance(i) - b.radiance(i)).length_squared()))
            .sum();
        (s / a.len() as f64).sqrt()
    };
    let before = diff(&a, &b);
    denoise(&mut a, &settings);
    denoise(&mut b, &settings);
    let after = diff(&a, &b);
    println!("keys: RMS difference {before:.4} → {after:.4}");
    assert!(after < 0.2 * before, "{before} → {after}");
}

#[test]
fn an_isolated_firefly_in_the_non_diffuse_part_is_clamped_and_a_patch_is_kept() {
    let mut c = cube(16, &room, |_, _| 1.0, 0.0, 1);
    let grid = CubeGrid::new(16);
    // Face 4 (+Z): one bright texel at (3, 3), a 3 × 3 bright patch around (10, 10).
    let at = |i: usize, j: usize| grid.offset(4, i, j, 0, 0);
    c.residual[at(3, 3)] = Vec3::splat(5.0);
    for j in 9..=11 {
        for i in 9..=11 {
            c.residual[at(i, j)] = Vec3::splat(5.0);
        }
    }
    let clamped = c.clamped_residual();
    // The speck falls to FIREFLY_RATIO × its neighbours' 0.01.
    assert!(
        (clamped[at(3, 3)].x - FIREFLY_RATIO * 0.01).abs() < 1e-4,
        "{}",
        clamped[at(3, 3)]
    );
    // The patch keeps its value, corners included (each has a bright neighbour).
    for (i, j) in [(10, 10), (9, 10), (9, 9), (11, 11)] {
        assert_eq!(clamped[at(i, j)], Vec3::splat(5.0), "({i}, {j})");
    }
    // Elsewhere nothing changes, and the radiance keeps the unclamped speck.
    assert_eq!(clamped[at(6, 6)], c.residual[at(6, 6)]);
    assert!(c.to_range_image().radiance.texels[at(3, 3)].x > 5.0);
}

#[test]
fn the_ambient_share_is_smoothed_keeping_its_mean_and_the_direct_share_is_kept() {
    // Direct light with a sharp edge (1 and 3 either side of x = 0) and an ambient share
    // with the skewed noise of a one-ray final gather: mostly 0.256, one texel in 40 at 10
    // (mean 0.5).
    let direct = |d: Vec3| if d.x < 0.0 { 1.0 } else { 3.0 };
    let mut c = cube(64, &room, |d, _| direct(d), 0.0, 12);
    let mut u = Gauss(13);
    let grid = CubeGrid::new(64);
    for i in 0..c.len() {
        let a = if u.next_u01() < 0.025 {
            10.0
        } else {
            0.25 / 0.975
        };
        c.ambient[i] = Vec3::splat(a);
        c.lighting[i] += Vec3::splat(a);
    }
    let ambient = |c: &LightingCube| c.ambient.iter().map(|a| a.x).collect::<Vec<_>>();
    let (m0, r0) = mean_and_rms(ambient(&c).into_iter(), 0.5);
    let mut s = c.clone();
    s.smooth_ambient(3);
    let (m1, r1) = mean_and_rms(ambient(&s).into_iter(), 0.5);
    println!("ambient: mean {m0:.4} → {m1:.4}, rms {r0:.3} → {r1:.3}");
    assert!((m1 / m0 - 1.0).abs() < 0.01, "mean {m0} → {m1}");
    assert!(r1 < r0 / 4.0, "rms {r0} → {r1}");
    for i in 0..s.len() {
        let kept = s.lighting[i] - s.ambient[i];
        let want = Vec3::splat(direct(grid.direction(i)));
        assert!(
            (kept - want).abs().max_element() < 1e-4,
            "texel {i}: {kept} vs {want}"
        );
    }
}
