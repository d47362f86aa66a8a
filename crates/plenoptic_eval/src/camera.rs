//! The reconstruction camera ([`plenoptic_recon::Camera`]) as the tracer's
//! [`PinholeCamera`] and back: the reference renderer and the ray-cast mask trace exactly
//! the pixels reconstruction fills.

use plenoptic_recon::Camera;
use plenoptic_trace::PinholeCamera;

use crate::Result;

/// The same camera as the tracer's pinhole.
pub fn to_pinhole(camera: &Camera) -> Result<PinholeCamera> {
    Ok(PinholeCamera::new(
        camera.position,
        camera.orientation,
        camera.vfov,
        camera.width,
        camera.height,
    )?)
}

/// The tracer's pinhole as a reconstruction camera.
pub fn from_pinhole(p: &PinholeCamera) -> Camera {
    Camera {
        position: p.position,
        orientation: p.rotation,
        vfov: p.yfov,
        width: p.width,
        height: p.height,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;
    use plenoptic_trace::Camera as _;

    #[test]
    fn reconstruction_rays_are_the_tracer_rays() {
        let c =
            Camera::look_at(Vec3::new(1.0, 2.0, 3.0), Vec3::ZERO, Vec3::Y, 1.0, 40, 30).unwrap();
        let p = to_pinhole(&c).unwrap();
        assert_eq!(from_pinhole(&p), c);
        let traced = PinholeCamera::look_at(c.position, Vec3::ZERO, Vec3::Y, 1.0, 40, 30).unwrap();
        assert!(traced.rotation.abs_diff_eq(c.orientation, 1e-6));
        let b = c.basis();
        for (x, y) in [(0, 0), (39, 29), (13, 7)] {
            let r = p.ray(x, y, glam::Vec2::splat(0.5)).unwrap();
            let d = b.direction(x as f32 + 0.5, y as f32 + 0.5);
            assert!(r.direction.abs_diff_eq(d, 1e-5), "{} {d}", r.direction);
        }
    }
}
