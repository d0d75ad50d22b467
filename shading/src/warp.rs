//! Sample warps from `[0, 1)²` to discs, hemispheres and spheres, and the orthonormal frame
//! about a normal. Every warp comes as a triplet in the pbrt-v4 / Mitsuba style:
//! `sample_x(u) -> value`, `x_pdf(value) -> density` and `invert_x(value) -> u`, with
//! `invert_x(sample_x(u)) == u` up to rounding wherever the warp is one-to-one. Densities are
//! with respect to solid angle for directions and to area of the unit square for points in
//! `[0,1)²`. No function here returns NaN or infinity for any finite input; a direction outside
//! the support has density 0. Twin: `warp.wgsl` (the warps the GPU bake draws; the inverses
//! and densities it does not need are Rust only).

use std::f32::consts::{FRAC_1_PI, FRAC_PI_2, FRAC_PI_4, PI};

use glam::{Vec2, Vec3};

use crate::random::ONE_MINUS_EPSILON;

/// `atan2(y, x)` mapped to `[0, 1)` (0 on the +x axis, increasing counter-clockwise).
fn azimuth_fraction(y: f32, x: f32) -> f32 {
    let mut f = y.atan2(x) * (0.5 * FRAC_1_PI);
    if f < 0.0 {
        f += 1.0;
    }
    if f.is_finite() {
        f.clamp(0.0, ONE_MINUS_EPSILON)
    } else {
        0.0
    }
}

/// Shirley–Chiu concentric map from `[0,1)²` to the unit disc.
pub fn sample_uniform_disk_concentric(u: Vec2) -> Vec2 {
    let o = 2.0 * u - Vec2::ONE;
    if o.x == 0.0 && o.y == 0.0 {
        return Vec2::ZERO;
    }
    let (r, theta) = if o.x.abs() > o.y.abs() {
        (o.x, FRAC_PI_4 * (o.y / o.x))
    } else {
        (o.y, FRAC_PI_2 - FRAC_PI_4 * (o.x / o.y))
    };
    r * Vec2::new(theta.cos(), theta.sin())
}

/// Density of [`sample_uniform_disk_concentric`] with respect to area: `1/π` inside the disc.
pub fn uniform_disk_concentric_pdf(p: Vec2) -> f32 {
    if p.length_squared() <= 1.0 {
        FRAC_1_PI
    } else {
        0.0
    }
}

/// Inverse of [`sample_uniform_disk_concentric`] (pbrt-v4 `InvertUniformDiskConcentricSample`).
pub fn invert_uniform_disk_concentric(p: Vec2) -> Vec2 {
    let theta = p.y.atan2(p.x); // (-π, π]
    let r = p.length();
    let (ox, oy);
    if theta.abs() < FRAC_PI_4 || theta.abs() > 3.0 * FRAC_PI_4 {
        let r = r.copysign(p.x);
        ox = r;
        oy = if p.x < 0.0 {
            if p.y < 0.0 {
                (PI + theta) * r / FRAC_PI_4
            } else {
                (theta - PI) * r / FRAC_PI_4
            }
        } else {
            theta * r / FRAC_PI_4
        };
    } else {
        let r = r.copysign(p.y);
        oy = r;
        ox = if p.y < 0.0 {
            -(FRAC_PI_2 + theta) * r / FRAC_PI_4
        } else {
            (FRAC_PI_2 - theta) * r / FRAC_PI_4
        };
    }
    let u = Vec2::new((ox + 1.0) * 0.5, (oy + 1.0) * 0.5);
    if u.is_finite() {
        u.clamp(Vec2::ZERO, Vec2::splat(ONE_MINUS_EPSILON))
    } else {
        Vec2::ZERO
    }
}

/// Cosine-weighted direction on the hemisphere around +z (Malley's method on the concentric
/// disc). Returns a unit vector in the local frame.
pub fn sample_cosine_hemisphere(u: Vec2) -> Vec3 {
    let d = sample_uniform_disk_concentric(u);
    let z = (1.0 - d.length_squared()).max(0.0).sqrt();
    Vec3::new(d.x, d.y, z)
}

/// Density of [`sample_cosine_hemisphere`] with respect to solid angle, given `cos θ` (the local
/// z component): `cos θ / π`, and 0 below the horizon.
pub fn cosine_hemisphere_pdf(cos_theta: f32) -> f32 {
    if cos_theta > 0.0 {
        cos_theta * FRAC_1_PI
    } else {
        0.0
    }
}

/// Inverse of [`sample_cosine_hemisphere`]: the `u` that maps to local direction `w`.
pub fn invert_cosine_hemisphere(w: Vec3) -> Vec2 {
    invert_uniform_disk_concentric(Vec2::new(w.x, w.y))
}

/// Uniform direction on the unit sphere: `z = 1 − 2u₀`, `φ = 2πu₁`.
pub fn sample_uniform_sphere(u: Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Density of [`sample_uniform_sphere`]: `1 / 4π` everywhere.
pub fn uniform_sphere_pdf() -> f32 {
    0.25 * FRAC_1_PI
}

/// Inverse of [`sample_uniform_sphere`].
pub fn invert_uniform_sphere(w: Vec3) -> Vec2 {
    let ux = ((1.0 - w.z) * 0.5).clamp(0.0, ONE_MINUS_EPSILON);
    let ux = if ux.is_finite() { ux } else { 0.0 };
    Vec2::new(ux, azimuth_fraction(w.y, w.x))
}

/// An orthonormal frame `(x, y, z)` with `z` a given unit normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    pub x: Vec3,
    pub y: Vec3,
    pub z: Vec3,
}

impl Frame {
    /// A right-handed frame around `n` (Duff et al. 2017, "Building an orthonormal basis,
    /// revisited", branchless and continuous except across `n.z = 0`). `n` is normalised first;
    /// a zero or non-finite `n` gives the world frame.
    pub fn from_normal(n: Vec3) -> Self {
        let n = n.try_normalize().unwrap_or(Vec3::Z);
        let sign = 1.0f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let x = Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let y = Vec3::new(b, sign + n.y * n.y * a, -n.y);
        Frame { x, y, z: n }
    }

    /// Local coordinates (z along the normal) to world.
    pub fn to_world(&self, v: Vec3) -> Vec3 {
        self.x * v.x + self.y * v.y + self.z * v.z
    }

    /// World coordinates to local.
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.x), v.dot(self.y), v.dot(self.z))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::random::Rng;

    #[test]
    fn frame_is_orthonormal() {
        let mut rng = Rng::new(9, 9);
        for _ in 0..1000 {
            let n = sample_uniform_sphere(rng.next_vec2());
            let f = Frame::from_normal(n);
            assert!((f.x.length() - 1.0).abs() < 1e-5);
            assert!((f.y.length() - 1.0).abs() < 1e-5);
            assert!(f.x.dot(f.y).abs() < 1e-5 && f.x.dot(f.z).abs() < 1e-5);
            assert!((f.x.cross(f.y) - f.z).length() < 1e-5);
            let v = sample_uniform_sphere(rng.next_vec2());
            assert!((f.to_world(f.to_local(v)) - v).length() < 1e-5);
        }
        for n in [Vec3::Z, -Vec3::Z, Vec3::ZERO, Vec3::NAN] {
            let f = Frame::from_normal(n);
            assert!(f.x.is_finite() && f.y.is_finite() && f.z.is_finite());
        }
    }

    #[test]
    fn disk_round_trip() {
        let mut rng = Rng::new(5, 5);
        for _ in 0..10_000 {
            let u = rng.next_vec2();
            let p = sample_uniform_disk_concentric(u);
            assert!(p.length() <= 1.0 + 1e-6);
            let back = invert_uniform_disk_concentric(p);
            assert!((back - u).abs().max_element() < 1e-4, "{u} {back}");
        }
    }
}
