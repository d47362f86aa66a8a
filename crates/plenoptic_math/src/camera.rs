//! Camera orientation in the glTF convention the tracer's and the reconstruction's cameras
//! share: a camera looks along its local −Z with +Y up.

use glam::{Mat3, Quat, Vec3};

/// The rotation of a camera at `eye` looking at `target` with `up` roughly up: local −Z
/// towards the target, local +Y in the plane of `up` and the view direction. `None` when
/// `eye` equals `target` or `up` is parallel to the view.
#[inline]
pub fn look_at_rotation(eye: Vec3, target: Vec3, up: Vec3) -> Option<Quat> {
    let forward = (target - eye).normalize_or_zero();
    let right = forward.cross(up).normalize_or_zero();
    if forward == Vec3::ZERO || right == Vec3::ZERO {
        return None;
    }
    let true_up = right.cross(forward);
    Some(Quat::from_mat3(&Mat3::from_cols(right, true_up, -forward)).normalize())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn looks_along_negative_z() {
        let eye = Vec3::new(1.0, 2.0, 3.0);
        let target = Vec3::new(-2.0, 0.5, -1.0);
        let q = look_at_rotation(eye, target, Vec3::Y).unwrap();
        let forward = q * Vec3::NEG_Z;
        assert!(forward.abs_diff_eq((target - eye).normalize(), 1e-6));
        assert!((q * Vec3::Y).dot(Vec3::Y) > 0.0);
        assert!((q * Vec3::X).dot(Vec3::Y).abs() < 1e-6);
        assert_eq!(look_at_rotation(eye, eye, Vec3::Y), None);
        assert_eq!(look_at_rotation(eye, eye + Vec3::Y, Vec3::Y), None);
    }
}
