//! Cameras: pinhole, cube (six faces in KTX2/Vulkan order and orientation) and equidistant
//! fisheye. Each maps a pixel and a sub-pixel offset to a world ray.
//!
//! Cameras look along their local −Z with +Y up, as glTF cameras do; image rows run from the
//! top, so row 0 looks towards +Y.

use glam::{Quat, Vec2, Vec3};
use std::f32::consts::PI;

use crate::accel::Ray;
use crate::{Result, TraceError};

/// Anything that turns pixels into rays.
pub trait Camera: Sync {
    /// Width and height in pixels.
    fn resolution(&self) -> (u32, u32);
    /// The ray through pixel (x, y) at sub-pixel offset `offset` in [0, 1)² (0.5, 0.5 is the
    /// centre); `None` where the pixel sees nothing (outside a fisheye's circle).
    fn ray(&self, x: u32, y: u32, offset: Vec2) -> Option<Ray>;
}

fn check_resolution(width: u32, height: u32) -> Result<()> {
    if width == 0 || height == 0 {
        return Err(TraceError::InvalidCamera(format!(
            "resolution {width}×{height} is empty"
        )));
    }
    Ok(())
}

fn check_position(position: Vec3, rotation: Quat) -> Result<()> {
    if !position.is_finite() || !rotation.is_finite() || !rotation.is_normalized() {
        return Err(TraceError::InvalidCamera(format!(
            "position {position} or rotation {rotation} is not finite and normalised"
        )));
    }
    Ok(())
}

/// A perspective camera with a vertical field of view.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PinholeCamera {
    /// Eye position.
    pub position: Vec3,
    /// Orientation: the camera looks along `rotation · −Z` with `rotation · +Y` up.
    pub rotation: Quat,
    /// Vertical field of view in radians.
    pub yfov: f32,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
}

impl PinholeCamera {
    /// A camera with the given pose; fails for an empty resolution or a field of view outside
    /// (0, π).
    pub fn new(position: Vec3, rotation: Quat, yfov: f32, width: u32, height: u32) -> Result<Self> {
        check_resolution(width, height)?;
        check_position(position, rotation)?;
        if !(yfov > 0.0 && yfov < PI) {
            return Err(TraceError::InvalidCamera(format!(
                "vertical field of view {yfov} rad is outside (0, π)"
            )));
        }
        Ok(Self {
            position,
            rotation,
            yfov,
            width,
            height,
        })
    }

    /// A camera at `eye` looking at `target` with `up` roughly up.
    pub fn look_at(
        eye: Vec3,
        target: Vec3,
        up: Vec3,
        yfov: f32,
        width: u32,
        height: u32,
    ) -> Result<Self> {
        let rotation = plenoptic_math::look_at_rotation(eye, target, up).ok_or_else(|| {
            TraceError::InvalidCamera(
                "look_at: eye equals target or up is parallel to the view".into(),
            )
        })?;
        Self::new(eye, rotation, yfov, width, height)
    }
}

impl Camera for PinholeCamera {
    fn resolution(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    fn ray(&self, x: u32, y: u32, offset: Vec2) -> Option<Ray> {
        let tan = (self.yfov * 0.5).tan();
        let aspect = self.width as f32 / self.height as f32;
        let sx = (2.0 * (x as f32 + offset.x) / self.width as f32 - 1.0) * tan * aspect;
        let sy = (1.0 - 2.0 * (y as f32 + offset.y) / self.height as f32) * tan;
        let dir = self.rotation * Vec3::new(sx, sy, -1.0).normalize();
        Some(Ray::new(self.position, dir))
    }
}

/// The six faces of a cube map, in KTX2/Vulkan layer order.
pub const CUBE_FACES: [CubeFace; 6] = [
    CubeFace::PosX,
    CubeFace::NegX,
    CubeFace::PosY,
    CubeFace::NegY,
    CubeFace::PosZ,
    CubeFace::NegZ,
];

/// One face of a cube map.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum CubeFace {
    /// Layer 0, +X.
    PosX,
    /// Layer 1, −X.
    NegX,
    /// Layer 2, +Y.
    PosY,
    /// Layer 3, −Y.
    NegY,
    /// Layer 4, +Z.
    PosZ,
    /// Layer 5, −Z.
    NegZ,
}

impl CubeFace {
    /// The world direction at face coordinates (s', t') in [−1, 1]², where s' grows with the
    /// column and t' with the row (row 0 first in memory).
    ///
    /// This inverts the Vulkan cube map selection table (Vulkan spec, "Cube Map Face
    /// Selection"; identical to OpenGL's): for major axis +X, s = −z/|x| and t = −y/|x|; −X:
    /// s = z, t = −y; +Y: s = x, t = z; −Y: s = x, t = −z; +Z: s = x, t = −y; −Z: s = −x,
    /// t = −y (all over the major axis's magnitude). So KTX2 files written from these faces
    /// sample back the same directions on the GPU.
    pub fn direction(self, s: f32, t: f32) -> Vec3 {
        match self {
            CubeFace::PosX => Vec3::new(1.0, -t, -s),
            CubeFace::NegX => Vec3::new(-1.0, -t, s),
            CubeFace::PosY => Vec3::new(s, 1.0, t),
            CubeFace::NegY => Vec3::new(s, -1.0, -t),
            CubeFace::PosZ => Vec3::new(s, -t, 1.0),
            CubeFace::NegZ => Vec3::new(-s, -t, -1.0),
        }
    }

    /// The layer index (0..6).
    pub fn index(self) -> usize {
        self as usize
    }
}

/// A cube camera: six square faces around a point, aligned with the world axes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CubeCamera {
    /// Centre.
    pub position: Vec3,
    /// Edge of each face in pixels.
    pub face_size: u32,
}

/// One face of a [`CubeCamera`], usable as a [`Camera`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CubeFaceCamera {
    /// Centre.
    pub position: Vec3,
    /// Edge in pixels.
    pub face_size: u32,
    /// Which face.
    pub face: CubeFace,
}

impl CubeCamera {
    /// A cube camera; fails for a zero face size or a non-finite position.
    pub fn new(position: Vec3, face_size: u32) -> Result<Self> {
        check_resolution(face_size, face_size)?;
        check_position(position, Quat::IDENTITY)?;
        Ok(Self {
            position,
            face_size,
        })
    }

    /// The camera of one face.
    pub fn face(&self, face: CubeFace) -> CubeFaceCamera {
        CubeFaceCamera {
            position: self.position,
            face_size: self.face_size,
            face,
        }
    }

    /// The six face cameras in layer order.
    pub fn faces(&self) -> [CubeFaceCamera; 6] {
        CUBE_FACES.map(|f| self.face(f))
    }
}

impl Camera for CubeFaceCamera {
    fn resolution(&self) -> (u32, u32) {
        (self.face_size, self.face_size)
    }

    fn ray(&self, x: u32, y: u32, offset: Vec2) -> Option<Ray> {
        let n = self.face_size as f32;
        let s = 2.0 * (x as f32 + offset.x) / n - 1.0;
        let t = 2.0 * (y as f32 + offset.y) / n - 1.0;
        Some(Ray::new(
            self.position,
            self.face.direction(s, t).normalize(),
        ))
    }
}

/// An equidistant fisheye: the angle from the view axis grows linearly with the distance from
/// the image centre, reaching `field / 2` at the inscribed circle. Square images.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FisheyeCamera {
    /// Centre.
    pub position: Vec3,
    /// Orientation, as for [`PinholeCamera`].
    pub rotation: Quat,
    /// Full field of view in radians, up to 2π (π is a hemisphere, 2π the whole sphere).
    pub field: f32,
    /// Edge in pixels.
    pub size: u32,
}

impl FisheyeCamera {
    /// A fisheye; fails for a zero size or a field outside (0, 2π].
    pub fn new(position: Vec3, rotation: Quat, field: f32, size: u32) -> Result<Self> {
        check_resolution(size, size)?;
        check_position(position, rotation)?;
        if !(field > 0.0 && field <= 2.0 * PI) {
            return Err(TraceError::InvalidCamera(format!(
                "fisheye field {field} rad is outside (0, 2π]"
            )));
        }
        Ok(Self {
            position,
            rotation,
            field,
            size,
        })
    }
}

impl Camera for FisheyeCamera {
    fn resolution(&self) -> (u32, u32) {
        (self.size, self.size)
    }

    fn ray(&self, x: u32, y: u32, offset: Vec2) -> Option<Ray> {
        let n = self.size as f32;
        let u = 2.0 * (x as f32 + offset.x) / n - 1.0;
        let v = 1.0 - 2.0 * (y as f32 + offset.y) / n;
        let r = (u * u + v * v).sqrt();
        if r > 1.0 {
            return None;
        }
        let theta = r * self.field * 0.5;
        let (cu, cv) = if r > 0.0 { (u / r, v / r) } else { (0.0, 0.0) };
        let local = Vec3::new(theta.sin() * cu, theta.sin() * cv, -theta.cos());
        Some(Ray::new(self.position, self.rotation * local))
    }
}
