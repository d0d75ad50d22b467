//! The Trowbridge–Reitz (GGX) microfacet distribution with separable Smith masking-shadowing
//! and the distribution of visible normals, as glTF 2.0's metallic-roughness BRDF uses them
//! (the specification's Appendix B). Twin: `ggx.wgsl` (`ggx_` + the same names).
//!
//! With `α = roughness²`, `h` the half vector and every cosine taken against the normal `n`:
//!
//! - `D = α² χ⁺(n·h) / (π ((n·h)² (α² − 1) + 1)²)`, its denominator computed as
//!   `α²(n·h)² + |n × h|²` so that the peak of a narrow lobe keeps the digits `α²` needs;
//! - `Λ(c) = c + √(α² + (1 − α²) c²)`, `G₁(c) = 2c / Λ(c)`, `V = 1 / (Λ(n·l) Λ(n·v))`;
//! - visible normals drawn as Heitz 2018 ("Sampling the GGX Distribution of Visible Normals").

use std::f32::consts::PI;

use glam::Vec3;

/// The smallest `α = roughness²` drawn: a lobe narrower than that (roughness below 0.03) is
/// drawn at that width, about 0.06° across, finer than any cube map the bake writes resolves.
pub const MIN_ALPHA: f32 = 1e-3;

/// Specular reflectance at normal incidence of glTF's dielectrics (index of refraction 1.5).
pub const DIELECTRIC_F0: f32 = 0.04;

/// `α = roughness²`, at least [`MIN_ALPHA`].
pub fn alpha(roughness: f32) -> f32 {
    (roughness * roughness).max(MIN_ALPHA)
}

/// The denominator of `D` before squaring: `α²(n·h)² + |n × h|²`, with `sin2 = |n × h|²`
/// computed by the caller without cancellation (not as `1 − (n·h)²`).
pub fn distribution_denominator(a2: f32, nh: f32, sin2: f32) -> f32 {
    a2 * nh * nh + sin2
}

/// Trowbridge–Reitz `D` for `α²`, `n·h` and `|n × h|²`; 0 where `n·h ≤ 0`.
pub fn distribution(a2: f32, nh: f32, sin2: f32) -> f32 {
    if nh <= 0.0 {
        return 0.0;
    }
    let d = distribution_denominator(a2, nh, sin2);
    a2 / (PI * d * d)
}

/// [`distribution`] at the half vector `h` about the normal `n` (both unit, in any frame).
pub fn distribution_at(a2: f32, n: Vec3, h: Vec3) -> f32 {
    distribution(a2, n.dot(h), n.cross(h).length_squared())
}

/// Smith's `Λ(c) = c + √(α² + (1 − α²) c²)` (`2c / G₁(c)`).
pub fn smith_lambda(a2: f32, c: f32) -> f32 {
    c + (a2 + (1.0 - a2) * c * c).sqrt()
}

/// Smith's masking `G₁` for `α²` and the cosine `c` (`n·v` or `n·l`).
pub fn smith_g1(a2: f32, c: f32) -> f32 {
    2.0 * c / smith_lambda(a2, c)
}

/// The separable Smith visibility `V = G / (4 n·l n·v) = 1 / (Λ(n·l) Λ(n·v))`.
pub fn visibility(a2: f32, nl: f32, nv: f32) -> f32 {
    1.0 / (smith_lambda(a2, nl) * smith_lambda(a2, nv))
}

/// A microfacet normal drawn from the GGX distribution of normals visible from `v` (Heitz
/// 2018, listing 1), both in the local frame (`z` the surface normal). `(r2, phi_fraction)` is
/// the point of the unit disc at radius `√r2` and angle `2π · phi_fraction`. A degenerate draw
/// gives the normal itself.
pub fn sample_visible_normal(v: Vec3, alpha: f32, r2: f32, phi_fraction: f32) -> Vec3 {
    let vh = Vec3::new(alpha * v.x, alpha * v.y, v.z).normalize();
    let len2 = vh.x * vh.x + vh.y * vh.y;
    let t1 = if len2 > 0.0 {
        Vec3::new(-vh.y, vh.x, 0.0) / len2.sqrt()
    } else {
        Vec3::X
    };
    let t2 = vh.cross(t1);
    let r = r2.sqrt();
    let phi = 2.0 * PI * phi_fraction;
    let p1 = r * phi.cos();
    let s = 0.5 * (1.0 + vh.z);
    let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * r * phi.sin();
    let nh = p1 * t1 + p2 * t2 + (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt() * vh;
    Vec3::new(alpha * nh.x, alpha * nh.y, nh.z.max(0.0)).normalize_or(Vec3::Z)
}

/// `n·h` of a half vector drawn from `D(h) (n·h)` (the distribution itself, not its visible
/// part) at `xi ∈ [0, 1)`: `√((1 − ξ) / (1 + (α² − 1) ξ))`.
pub fn sample_distribution_cos(a2: f32, xi: f32) -> f32 {
    ((1.0 - xi) / (1.0 + (a2 - 1.0) * xi)).max(0.0).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn visible_normals_face_the_viewer() {
        let v = Vec3::new(0.6, 0.0, 0.8);
        for i in 0..64 {
            let (x, y) = ((i % 8) as f32 / 8.0 + 0.06, (i / 8) as f32 / 8.0 + 0.06);
            let m = sample_visible_normal(v, 0.3, x, y);
            assert!((m.length() - 1.0).abs() < 1e-5 && m.z >= 0.0 && m.dot(v) >= 0.0);
        }
    }

    #[test]
    fn distribution_integrates_to_one_over_projected_area() {
        // ∫ D(h) (n·h) dω = 1, by the midpoint rule in θ.
        for a in [0.05_f32, 0.3, 1.0] {
            let a2 = a * a;
            let steps = 200_000;
            let mut sum = 0.0_f64;
            for i in 0..steps {
                let theta = (i as f64 + 0.5) / steps as f64 * std::f64::consts::FRAC_PI_2;
                let (s, c) = (theta.sin() as f32, theta.cos() as f32);
                let d = distribution(a2, c, s * s) as f64;
                sum += d * c as f64 * s as f64 * 2.0 * std::f64::consts::PI;
            }
            sum *= std::f64::consts::FRAC_PI_2 / steps as f64;
            assert!((sum - 1.0).abs() < 2e-3, "α {a}: {sum}");
        }
    }

    #[test]
    fn masking_is_one_at_normal_incidence_and_bounded() {
        for a2 in [1e-6_f32, 0.01, 0.5, 1.0] {
            assert!((smith_g1(a2, 1.0) - 1.0).abs() < 1e-6);
            for i in 1..=100 {
                let g = smith_g1(a2, i as f32 / 100.0);
                assert!(g > 0.0 && g <= 1.0 + 1e-6);
            }
            let v = visibility(a2, 1.0, 1.0);
            assert!((v - 0.25).abs() < 1e-6, "V(1, 1) = G / 4");
        }
    }

    #[test]
    fn sampled_cosines_follow_the_distribution() {
        // The mass of D(h) (n·h) between the normal and the drawn angle is ξ.
        let a2 = 0.09_f32;
        for xi in [0.1_f32, 0.5, 0.9] {
            let theta_max = (sample_distribution_cos(a2, xi) as f64).acos();
            let steps = 100_000;
            let mut mass = 0.0_f64;
            for i in 0..steps {
                let theta = (i as f64 + 0.5) / steps as f64 * theta_max;
                let (s, c) = (theta.sin() as f32, theta.cos() as f32);
                mass += distribution(a2, c, s * s) as f64 * c as f64 * s as f64;
            }
            mass *= 2.0 * std::f64::consts::PI * theta_max / steps as f64;
            assert!((mass - xi as f64).abs() < 1e-3, "ξ {xi}: {mass}");
        }
        assert_eq!(sample_distribution_cos(a2, 0.0), 1.0);
    }
}
