//! A pinhole camera: the one view description shared by the bake's renders (`oslf truth`) and
//! the runtime's frames (`oslf render`), so both see the same pixels through the same rays.

use glam::Vec3;

use crate::{GeometryError, Result};

/// The narrowest vertical field of view a camera may have, in degrees: narrower, the image
/// spans directions closer together than f32 rays resolve (a telephoto lens of 2 000 mm on
/// full frame is still 0.7°).
pub const VFOV_MIN_DEG: f32 = 0.1;
/// The widest vertical field of view, in degrees (a pinhole camera reaches 180° only in the
/// limit).
pub const VFOV_MAX_DEG: f32 = 179.0;

/// A pinhole camera looking from `position` at `target`, `up` giving the roll, `vfov_deg` the
/// full vertical field of view in degrees.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub position: Vec3,
    pub target: Vec3,
    pub up: Vec3,
    pub vfov_deg: f32,
}

impl Camera {
    /// Errors if a vector is not finite, `target == position`, `up` is parallel to the view
    /// direction, or the field of view is outside [`VFOV_MIN_DEG`] to [`VFOV_MAX_DEG`].
    pub fn validate(&self) -> Result<()> {
        if !(self.position.is_finite() && self.target.is_finite() && self.up.is_finite()) {
            return Err(GeometryError::Invalid(
                "camera vectors must be finite".into(),
            ));
        }
        let forward = (self.target - self.position)
            .try_normalize()
            .ok_or_else(|| {
                GeometryError::Invalid("camera target coincides with its position".into())
            })?;
        if forward.cross(self.up).length_squared() < 1e-12 {
            return Err(GeometryError::Invalid(
                "camera up vector is parallel to the view direction".into(),
            ));
        }
        if !(VFOV_MIN_DEG..=VFOV_MAX_DEG).contains(&self.vfov_deg) {
            return Err(GeometryError::Invalid(format!(
                "camera vertical field of view {} must be within {VFOV_MIN_DEG} to {VFOV_MAX_DEG} degrees",
                self.vfov_deg
            )));
        }
        Ok(())
    }

    /// The orthonormal `(right, up, forward)` basis. Degenerate cameras (see
    /// [`Camera::validate`]) fall back to looking along +x with +z up, or to any up vector
    /// perpendicular to the view direction.
    pub fn basis(&self) -> (Vec3, Vec3, Vec3) {
        let forward = (self.target - self.position)
            .try_normalize()
            .unwrap_or(Vec3::X);
        let right = forward
            .cross(self.up)
            .try_normalize()
            .unwrap_or_else(|| forward.any_orthonormal_vector());
        let up = right.cross(forward);
        (right, up, forward)
    }

    /// The unit direction of the ray from [`Camera::position`] through image position
    /// `(px, py)` in pixel units (`(0, 0)` the top-left corner of the image, `(width, height)`
    /// the bottom-right; pixel `(i, j)` has its centre at `(i + ½, j + ½)`), for an image of
    /// `width × height` pixels with square pixels.
    pub fn direction(&self, px: f32, py: f32, width: u32, height: u32) -> Vec3 {
        let (right, up, forward) = self.basis();
        let vfov = if self.vfov_deg.is_finite() {
            self.vfov_deg.clamp(1e-3, 179.0)
        } else {
            60.0
        };
        let tan_half = (0.5 * vfov.to_radians()).tan();
        let (w, h) = (width.max(1) as f32, height.max(1) as f32);
        let aspect = w / h;
        let sx = (2.0 * px / w - 1.0) * aspect * tan_half;
        let sy = (1.0 - 2.0 * py / h) * tan_half;
        (forward + right * sx + up * sy)
            .try_normalize()
            .unwrap_or(forward)
    }
}
