//! The background: what pixels off the object show. As shade/background.wgsl, function for function.

use glam::Vec3;
use oslf_format::INVALID_INDEX;

use super::pixel::finite3;
use super::{CubeTexels, Shader};

#[allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]
impl<C: CubeTexels> Shader<'_, C> {
    /// The unit direction of the camera ray through the centre of pixel `(px, py)`, as
    /// [`oslf_geometry::Camera::direction`] computes it (as `camera_ray`).
    pub fn camera_ray(&self, px: u32, py: u32) -> Vec3 {
        let u = &self.uniform;
        let (w, h) = (u.size[0] as f32, u.size[1] as f32);
        let aspect = w / h;
        let tan_half = u.cam_right[3];
        let sx = (2.0 * (px as f32 + 0.5) / w - 1.0) * aspect * tan_half;
        let sy = (1.0 - 2.0 * (py as f32 + 0.5) / h) * tan_half;
        let forward = Vec3::from_slice(&u.cam_forward[..3]);
        let d = forward
            + Vec3::from_slice(&u.cam_right[..3]) * sx
            + Vec3::from_slice(&u.cam_up[..3]) * sy;
        let l2 = d.dot(d);
        if l2 > 0.0 && l2 <= 3.0e38 {
            return d / l2.sqrt();
        }
        forward
    }

    /// What background pixel `(px, py)` shows, alpha 0 (as `background`): the environment
    /// cube is read without a feedback mark, as it is pinned resident, and filtered across
    /// face edges ([`Self::seamless_read`]).
    pub(super) fn background(&self, px: u32, py: u32) -> [f32; 4] {
        let u = &self.uniform;
        let c = match u.background {
            0 => return [0.0; 4],
            1 if u.env_cube == INVALID_INDEX => Vec3::ZERO,
            1 => self
                .seamless_read(u.env_cube, self.camera_ray(px, py))
                .unwrap_or(Vec3::ZERO),
            _ => Vec3::from_slice(&u.bg_color[..3]),
        };
        let c = finite3(c);
        [c.x, c.y, c.z, 0.0]
    }
}
