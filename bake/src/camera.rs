//! A pinhole camera and a deterministic parallel renderer.

use glam::Vec3;
use rayon::prelude::*;

use crate::integrator::{Integrator, RayStats};
use crate::ray::{Intersector, Ray};
use crate::sampling::{hash_u64, stratified_2d, Rng};
use crate::{BakeError, Result};

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
    /// direction, or the field of view is outside `(0°, 180°)`.
    pub fn validate(&self) -> Result<()> {
        if !(self.position.is_finite() && self.target.is_finite() && self.up.is_finite()) {
            return Err(BakeError::Invalid("camera vectors must be finite".into()));
        }
        let forward = (self.target - self.position)
            .try_normalize()
            .ok_or_else(|| {
                BakeError::Invalid("camera target coincides with its position".into())
            })?;
        if forward.cross(self.up).length_squared() < 1e-12 {
            return Err(BakeError::Invalid(
                "camera up vector is parallel to the view direction".into(),
            ));
        }
        if !(self.vfov_deg > 0.0 && self.vfov_deg < 180.0) {
            return Err(BakeError::Invalid(format!(
                "camera vertical field of view {} must be in (0, 180) degrees",
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

    /// The ray through image position `(px, py)` in pixel units (`(0, 0)` the top-left corner
    /// of the image, `(width, height)` the bottom-right; pixel `(i, j)` has its centre at
    /// `(i + ½, j + ½)`), for an image of `width × height` pixels with square pixels.
    pub fn ray(&self, px: f32, py: f32, width: u32, height: u32) -> Ray {
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
        let dir = (forward + right * sx + up * sy)
            .try_normalize()
            .unwrap_or(forward);
        Ray::new(self.position, dir)
    }
}

/// Renders `width × height` pixels (row-major, row 0 at the top) with `spp` samples per pixel
/// (0 is treated as 1), returning the mean radiance per pixel and the rays traced.
///
/// Each pixel's samples are jittered in `spp` strata of the pixel ([`stratified_2d`]) and use
/// their own generator `Rng::new(seed, hash_u64(&[seed, x, y]))`, so the image depends only on
/// the scene, the camera, `spp` and `seed`: never on the number of threads. Rows are rendered
/// in parallel with rayon.
pub fn render<I: Intersector>(
    integrator: &Integrator<I>,
    camera: &Camera,
    width: u32,
    height: u32,
    spp: u32,
    seed: u64,
) -> (Vec<glam::Vec3>, RayStats) {
    let spp = spp.max(1);
    let rows: Vec<(Vec<Vec3>, RayStats)> = (0..height)
        .into_par_iter()
        .map(|y| {
            let mut stats = RayStats::default();
            let mut row = Vec::with_capacity(width as usize);
            for x in 0..width {
                let mut rng = Rng::new(seed, hash_u64(&[seed, x as u64, y as u64]));
                let mut sum = Vec3::ZERO;
                for s in 0..spp {
                    let j = stratified_2d(s, spp, &mut rng);
                    let ray = camera.ray(x as f32 + j.x, y as f32 + j.y, width, height);
                    sum += integrator.radiance(&ray, &mut rng, &mut stats).radiance;
                }
                row.push(sum / spp as f32);
            }
            (row, stats)
        })
        .collect();
    let mut image = Vec::with_capacity(width as usize * height as usize);
    let mut stats = RayStats::default();
    for (row, s) in rows {
        image.extend(row);
        stats.add(&s);
    }
    (image, stats)
}
