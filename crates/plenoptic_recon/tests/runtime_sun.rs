//! The runtime sun (pack 3): its BSDF is the tracer's, value for value, for random surfaces
//! and directions (`plenoptic_recon::brdf` repeats the formulas of
//! `plenoptic_trace::material`, since the runtime core does not depend on the tracer).

use glam::{Vec2, Vec3};
use plenoptic_recon::brdf::{Bsdf, SurfaceMaterial};
use plenoptic_trace::Hit;
use plenoptic_trace::material::{Bsdf as TraceBsdf, Lobes, SurfaceProps};

/// A small deterministic generator (xorshift64*).
struct Rng(u64);

impl Rng {
    fn f(&mut self) -> f32 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 40) as f32 / (1u64 << 24) as f32
    }

    fn unit(&mut self) -> Vec3 {
        loop {
            let v = Vec3::new(self.f(), self.f(), self.f()) * 2.0 - Vec3::ONE;
            if v.length_squared() > 0.01 && v.length_squared() <= 1.0 {
                return v.normalize();
            }
        }
    }
}

#[test]
fn the_runtime_bsdf_is_the_tracers() {
    let mut rng = Rng(0x1234_5678_9abc_def1);
    let mut compared = 0;
    let mut nonzero = 0;
    for case in 0..4000 {
        let roughness = match case % 5 {
            0 => 0.01,
            _ => rng.f(),
        };
        let m = SurfaceMaterial {
            base: Vec3::new(rng.f(), rng.f(), rng.f()),
            metallic: if case % 3 == 0 { 0.0 } else { rng.f() },
            roughness,
            transmission: if case % 4 == 0 { rng.f() } else { 0.0 },
            ior: 1.0 + rng.f(),
            // Transmission crossing a thin wall, and refracting into a solid.
            thin_walled: case % 8 < 4,
        };
        let ng = rng.unit();
        // A shading normal near the geometric one, on its side.
        let mut ns = (ng + rng.unit() * 0.3).normalize();
        if ns.dot(ng) < 0.0 {
            ns = -ns;
        }
        let wo = rng.unit();
        let wi = rng.unit();
        let front_face = wo.dot(ng) > 0.0;
        let props = SurfaceProps {
            base_color: m.base,
            metallic: m.metallic,
            roughness: m.roughness,
            emissive: Vec3::ZERO,
            transmission: m.transmission,
            ior: m.ior,
            thin_walled: m.thin_walled,
            double_sided: true,
        };
        let hit = Hit {
            distance: 1.0,
            object: 0,
            triangle: 0,
            barycentrics: Vec2::ZERO,
            position: Vec3::ZERO,
            geometric_normal: ng,
            shading_normal: ns,
            uv: Vec2::ZERO,
            front_face,
        };
        let theirs = TraceBsdf::new(&props, &hit, wo);
        let ours = Bsdf::new(m, ng, ns, wo, front_face);
        assert_eq!(
            ours.takes_light_samples(),
            !theirs.is_delta(Lobes::All),
            "case {case}: {m:?}"
        );
        assert!(
            (ours.normal() - theirs.normal()).length() < 1e-5,
            "case {case}"
        );
        let a = ours.eval(wi);
        let (b, _) = theirs.eval(wi, Lobes::All);
        // Relative to the larger value, with an absolute floor for values that rounding
        // decides (a half-vector on the edge of the transmission lobe).
        let scale = a.max_element().max(b.max_element());
        assert!(
            (a - b).abs().max_element() <= 1e-4 * scale + 1e-5,
            "case {case}: runtime {a} against the tracer's {b} for {m:?}"
        );
        // The Lambertian lobe alone: what a runtime lamp's diffuse light goes through.
        let (a_d, b_d) = (ours.eval_diffuse(wi), theirs.eval(wi, Lobes::Diffuse).0);
        let scale = a_d.max_element().max(b_d.max_element());
        assert!(
            (a_d - b_d).abs().max_element() <= 1e-4 * scale + 1e-5,
            "case {case}: runtime diffuse {a_d} against the tracer's {b_d} for {m:?}"
        );
        compared += 1;
        if b.max_element() > 0.0 {
            nonzero += 1;
        }
    }
    // The directions were random: about half reflect into the surface's hemisphere.
    assert!(nonzero > compared / 4, "{nonzero} of {compared}");
}
