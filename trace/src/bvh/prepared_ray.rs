//! A ray prepared for the traversal: what the node and triangle tests need of it, computed
//! once per ray.

use glam::{Vec3, Vec3A};
use obvhs::cwbvh::node::CwBvhNode;

use oslf_scene::tolerance::SELF_TOLERANCE;

use crate::ray::Ray;

/// Byte offsets in [`CwBvhNode`] of the quantised child planes.
pub(super) const CHILD_MIN_X: usize = std::mem::offset_of!(CwBvhNode, child_min_x);
pub(super) const CHILD_MAX_X: usize = std::mem::offset_of!(CwBvhNode, child_max_x);
pub(super) const CHILD_MIN_Y: usize = std::mem::offset_of!(CwBvhNode, child_min_y);
pub(super) const CHILD_MAX_Y: usize = std::mem::offset_of!(CwBvhNode, child_max_y);
pub(super) const CHILD_MIN_Z: usize = std::mem::offset_of!(CwBvhNode, child_min_z);
pub(super) const CHILD_MAX_Z: usize = std::mem::offset_of!(CwBvhNode, child_max_z);

/// Offsets of the near and far planes per axis for a ray direction: `(near, far)` is
/// `(min, max)` for a non-negative component and `(max, min)` for a negative one.
pub(super) fn plane_offsets(d: Vec3) -> [[usize; 2]; 3] {
    let pick = |neg: bool, lo: usize, hi: usize| if neg { [hi, lo] } else { [lo, hi] };
    [
        pick(d.x < 0.0, CHILD_MIN_X, CHILD_MAX_X),
        pick(d.y < 0.0, CHILD_MIN_Y, CHILD_MAX_Y),
        pick(d.z < 0.0, CHILD_MIN_Z, CHILD_MAX_Z),
    ]
}

/// Per-ray constants of the watertight test and the node test.
#[derive(Clone, Copy)]
pub(super) struct PreparedRay {
    pub(super) origin: Vec3,
    pub(super) dir: Vec3,
    /// Rows of the permute-and-shear transform: `x' = rx·p`, `y' = ry·p`, `z' = p[kz]`.
    pub(super) rx: Vec3,
    pub(super) ry: Vec3,
    pub(super) rz: Vec3,
    /// `1 / d[kz]`.
    pub(super) sz: f32,
    /// Reciprocal direction for the slab test (tiny components clamped to ±1e20).
    pub(super) inv_dir: Vec3A,
    /// Distance from a triangle's plane within which the origin counts as on the triangle.
    pub(super) self_tolerance: f32,
    /// Byte offsets of the near and far child planes per axis (see [`plane_offsets`]).
    #[cfg_attr(
        not(all(target_arch = "x86_64", target_feature = "sse2")),
        allow(dead_code)
    )]
    pub(super) planes: [[usize; 2]; 3],
    /// The same choice as indices into `min x, max x, min y, max y, min z, max z`.
    #[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
    pub(super) plane_index: [[usize; 2]; 3],
}

impl PreparedRay {
    /// `None` for a ray that cannot hit anything (non-finite or zero direction, non-finite
    /// origin, `t_max` not positive or NaN).
    #[inline(always)]
    pub(super) fn new(ray: &Ray, t_max: f32) -> Option<Self> {
        let (o, d) = (ray.origin, ray.dir);
        if !o.is_finite() || !d.is_finite() || d == Vec3::ZERO || t_max.is_nan() || t_max <= 0.0 {
            return None;
        }
        let a = d.abs();
        // kz: the axis of the largest |d| component; kx = kz + 1, ky = kz + 2 (mod 3).
        let kz = if a.x > a.y {
            if a.x > a.z {
                0
            } else {
                2
            }
        } else if a.y > a.z {
            1
        } else {
            2
        };
        let (ex, ey, ez, dx, dy, dz) = match kz {
            0 => (Vec3::Y, Vec3::Z, Vec3::X, d.y, d.z, d.x),
            1 => (Vec3::Z, Vec3::X, Vec3::Y, d.z, d.x, d.y),
            _ => (Vec3::X, Vec3::Y, Vec3::Z, d.x, d.y, d.z),
        };
        let sx = -dx / dz;
        let sy = -dy / dz;
        let inv = |c: f32| {
            if c.abs() < 1e-20 {
                if c < 0.0 {
                    -1e20
                } else {
                    1e20
                }
            } else {
                1.0 / c
            }
        };
        Some(Self {
            origin: o,
            dir: d,
            rx: ex + ez * sx,
            ry: ey + ez * sy,
            rz: ez,
            sz: 1.0 / dz,
            inv_dir: Vec3A::new(inv(d.x), inv(d.y), inv(d.z)),
            self_tolerance: SELF_TOLERANCE * o.abs().max_element(),
            planes: plane_offsets(d),
            plane_index: {
                let neg = |c: f32| usize::from(c < 0.0);
                let (nx, ny, nz) = (neg(d.x), neg(d.y), neg(d.z));
                [[nx, 1 - nx], [2 + ny, 3 - ny], [4 + nz, 5 - nz]]
            },
        })
    }
}
