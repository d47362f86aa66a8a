//! The reconstruction camera: a pinhole with the same convention as the tracer's pinhole
//! camera (looks along its local −Z with +Y up, row 0 at the top, pixel centres at
//! half-integer offsets), plus the inverse mapping (world → pixel) that depth reprojection
//! needs (thesis appendix A.2). `plenoptic_eval::camera` converts it to and from the tracer's
//! camera and tests that both cast the same rays.

use glam::{Quat, Vec3};

use crate::{Error, Result};

/// A pinhole camera: pose, vertical field of view and resolution.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Eye position, world space.
    pub position: Vec3,
    /// Orientation: the camera looks along `orientation · −Z` with `orientation · +Y` up.
    pub orientation: Quat,
    /// Vertical field of view, radians, in (0, π).
    pub vfov: f32,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
}

impl Camera {
    /// A camera; fails for an empty resolution, a non-finite pose or a field of view outside
    /// (0, π).
    pub fn new(
        position: Vec3,
        orientation: Quat,
        vfov: f32,
        width: u32,
        height: u32,
    ) -> Result<Self> {
        let c = Camera {
            position,
            orientation: orientation.normalize(),
            vfov,
            width,
            height,
        };
        c.validate()?;
        Ok(c)
    }

    /// A camera at `eye` looking at `target` with `up` roughly up.
    pub fn look_at(
        eye: Vec3,
        target: Vec3,
        up: Vec3,
        vfov: f32,
        width: u32,
        height: u32,
    ) -> Result<Self> {
        let orientation = plenoptic_math::look_at_rotation(eye, target, up).ok_or_else(|| {
            Error::Camera("look_at: eye equals target or up is parallel to the view".into())
        })?;
        Self::new(eye, orientation, vfov, width, height)
    }

    /// Checks the resolution (not empty), the pose (finite, a unit quaternion) and the field
    /// of view (inside (0, π)).
    pub fn validate(&self) -> Result<()> {
        if self.width == 0 || self.height == 0 {
            return Err(Error::Camera(format!(
                "resolution {}×{} is empty",
                self.width, self.height
            )));
        }
        let q = self.orientation;
        if !self.position.is_finite() || !q.is_finite() || !q.is_normalized() {
            return Err(Error::Camera(format!(
                "position {} or rotation {q} is not finite and normalised",
                self.position
            )));
        }
        if !(self.vfov > 0.0 && self.vfov < std::f32::consts::PI) {
            return Err(Error::Camera(format!(
                "vertical field of view {} rad is outside (0, π)",
                self.vfov
            )));
        }
        Ok(())
    }

    /// Number of pixels.
    pub fn pixel_count(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// Precomputed basis for per-pixel work.
    pub fn basis(&self) -> CameraBasis {
        let tan = (self.vfov * 0.5).tan();
        let aspect = self.width as f32 / self.height as f32;
        CameraBasis {
            position: self.position,
            right: self.orientation * Vec3::X,
            up: self.orientation * Vec3::Y,
            forward: self.orientation * -Vec3::Z,
            tan_x: tan * aspect,
            tan_y: tan,
            width: self.width as f32,
            height: self.height as f32,
            focal_px: self.height as f32 / (2.0 * tan),
        }
    }
}

/// A camera's world-space basis with the projection constants, for the per-pixel loops.
#[derive(Clone, Copy, Debug)]
pub struct CameraBasis {
    /// Eye.
    pub position: Vec3,
    /// World direction of +x on the image.
    pub right: Vec3,
    /// World direction of up on the image.
    pub up: Vec3,
    /// Viewing direction.
    pub forward: Vec3,
    /// tan(hfov/2).
    pub tan_x: f32,
    /// tan(vfov/2).
    pub tan_y: f32,
    /// Width, pixels.
    pub width: f32,
    /// Height, pixels.
    pub height: f32,
    /// Focal length in pixels (height / (2 tan(vfov/2))).
    pub focal_px: f32,
}

impl CameraBasis {
    /// Unit direction through the continuous image point (px, py) (pixel (x, y)'s centre is
    /// (x + ½, y + ½)); identical to the tracer's pinhole rays.
    #[inline]
    pub fn direction(&self, px: f32, py: f32) -> Vec3 {
        self.ray(px, py).normalize()
    }

    /// The ray through the continuous image point (px, py), not normalised:
    /// `forward + right · sx + up · sy`, one unit along the viewing direction (so its length
    /// is 1 / cos of its angle to the axis, and a camera-space depth times that length is the
    /// distance along the ray).
    #[inline]
    pub fn ray(&self, px: f32, py: f32) -> Vec3 {
        let sx = (2.0 * px / self.width - 1.0) * self.tan_x;
        let sy = (1.0 - 2.0 * py / self.height) * self.tan_y;
        self.right * sx + self.up * sy + self.forward
    }

    /// Projects a world point: continuous image coordinates and the depth along the viewing
    /// direction; `None` behind the eye (depth ≤ 1e-4).
    #[inline]
    pub fn project(&self, world: Vec3) -> Option<(f32, f32, f32)> {
        let d = world - self.position;
        let z = d.dot(self.forward);
        if z.is_nan() || z <= 1e-4 {
            return None;
        }
        let sx = d.dot(self.right) / (z * self.tan_x);
        let sy = d.dot(self.up) / (z * self.tan_y);
        Some((
            (sx + 1.0) * 0.5 * self.width,
            (1.0 - sy) * 0.5 * self.height,
            z,
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn projects_pixel_rays_back_to_their_pixels() {
        let c =
            Camera::look_at(Vec3::new(1.0, 2.0, 3.0), Vec3::ZERO, Vec3::Y, 1.0, 40, 30).unwrap();
        let b = c.basis();
        // The centre pixel's ray points at the target.
        let centre = b.direction(20.0, 15.0);
        assert!(
            centre.abs_diff_eq(-c.position.normalize(), 1e-5),
            "{centre}"
        );
        for (x, y) in [(0, 0), (39, 29), (13, 7)] {
            let d = b.direction(x as f32 + 0.5, y as f32 + 0.5);
            let (px, py, _) = b.project(c.position + d * 2.5).unwrap();
            assert!((px - x as f32 - 0.5).abs() < 1e-3 && (py - y as f32 - 0.5).abs() < 1e-3);
        }
    }

    #[test]
    fn rejects_bad_cameras() {
        let q = Quat::IDENTITY;
        assert!(Camera::new(Vec3::ZERO, q, 1.0, 0, 4).is_err());
        assert!(Camera::new(Vec3::ZERO, q, 3.2, 4, 4).is_err());
        assert!(Camera::new(Vec3::NAN, q, 1.0, 4, 4).is_err());
        assert!(Camera::look_at(Vec3::ZERO, Vec3::Y, Vec3::Y, 1.0, 4, 4).is_err());
    }
}
