//! The prepass's maths (fs_prepass in renderer/composite.wgsl), function for function: what it
//! writes into a host's normal and motion-vector prepass from a G-buffer texel.

use glam::{Mat4, Vec2, Vec3, Vec4};

use crate::geometry::oct_decode;

/// The host's normal target of the object's normal `e` (octahedral, its own space): the world
/// normal through `normal_from_local` as n·½ + ½; +z where it vanishes (as `prepass_normal`).
pub fn prepass_normal(e: [f32; 2], normal_from_local: Mat4) -> Vec4 {
    let world = (normal_from_local * oct_decode(e).extend(0.0)).truncate();
    let l2 = world.dot(world);
    let n = if l2 > 1e-30 {
        world * (1.0 / l2.sqrt())
    } else {
        Vec3::Z
    };
    (n * 0.5 + Vec3::splat(0.5)).extend(1.0)
}

/// The screen motion of the G-buffer point `x` since the previous frame, in UV units (y down);
/// 0 where either frame sees it behind the eye (as `prepass_motion`).
pub fn prepass_motion(x: Vec3, clip_from_patch: Mat4, previous_clip_from_patch: Mat4) -> Vec2 {
    let now = clip_from_patch * x.extend(1.0);
    let before = previous_clip_from_patch * x.extend(1.0);
    if !(now.w > 1e-20 && before.w > 1e-20) {
        return Vec2::ZERO;
    }
    (Vec2::new(now.x, now.y) / now.w - Vec2::new(before.x, before.y) / before.w)
        * Vec2::new(0.5, -0.5)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::oct_encode;
    use crate::renderer::normal_from_local;
    use glam::Quat;

    /// A world normal by cofactors: perpendicular to the images of the two tangents that the
    /// local normal is perpendicular to, whatever the scale.
    fn by_tangents(world_from_local: Mat4, n: Vec3) -> Vec3 {
        let t = n.any_orthonormal_vector();
        let b = n.cross(t);
        let m = |v: Vec3| world_from_local.transform_vector3(v);
        let w = m(t).cross(m(b)).normalize();
        if w.dot(m(n)) < 0.0 {
            -w
        } else {
            w
        }
    }

    #[test]
    fn normals_stay_perpendicular_to_the_surface_under_uneven_scales() {
        let world_from_local = Mat4::from_scale_rotation_translation(
            Vec3::new(2.0, 1.0, 0.25),
            Quat::from_rotation_z(0.5) * Quat::from_rotation_x(-0.3),
            Vec3::new(1.0, -2.0, 3.0),
        );
        let normal_from_local = normal_from_local(world_from_local);
        let mut uneven = 0;
        for k in 0..200 {
            let a = k as f32 * 0.37;
            let n = Vec3::new(a.cos() * (0.9 * a).sin(), a.sin(), (1.3 * a).cos()).normalize();
            let e = oct_encode(n);
            let got = prepass_normal(e, normal_from_local).truncate() * 2.0 - Vec3::ONE;
            let want = by_tangents(world_from_local, oct_decode(e));
            assert!((got - want).length() < 1e-5, "{n}: {got} against {want}");
            // Turning the normal as a direction would not be perpendicular.
            let naive = world_from_local
                .transform_vector3(oct_decode(e))
                .normalize();
            uneven += usize::from((naive - want).length() > 0.05);
        }
        assert!(uneven > 100, "{uneven} of 200 normals tell the two apart");
        // A vanishing normal gives +z, never NaN.
        let zero = prepass_normal([0.0, 0.0], Mat4::ZERO);
        assert_eq!(zero, Vec4::new(0.5, 0.5, 1.0, 1.0));
    }

    #[test]
    fn motion_is_the_clip_shift_in_uv_units_and_zero_behind_the_eye() {
        let projection = glam::camera::rh::proj::directx::perspective(1.0, 1.5, 0.1, 100.0);
        let view =
            glam::camera::rh::view::look_at_mat4(Vec3::new(0.0, -5.0, 1.0), Vec3::ZERO, Vec3::Z);
        let now = projection * view;
        let shift = Mat4::from_translation(Vec3::new(0.1, -0.2, 0.0));
        let x = Vec3::new(0.3, 0.2, 0.4);
        let m = prepass_motion(x, now, shift * now);
        // The previous frame saw the point 0.1 right and 0.2 down in NDC: UV x 0.05 left now,
        // and y (down) 0.1 further down.
        let want = Vec2::new(-0.05, -0.1);
        assert!((m - want).length() < 1e-6, "{m} against {want}");
        // Behind the eye in either frame: no motion.
        let behind = Vec3::new(0.0, -6.0, 1.0);
        assert_eq!(prepass_motion(behind, now, now), Vec2::ZERO);
    }
}
