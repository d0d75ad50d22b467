//! Spherical harmonics of bands 0–2 (nine coefficients): the low-frequency part of a sample
//! point's cube map, projected once at bake time from all of its texels (oslf-format's
//! irradiance section) and convolved with the diffuse lobe when shaded, so that the diffuse
//! base is read, not sampled (Ramamoorthi & Hanrahan 2001, "An Efficient Representation for
//! Irradiance Environment Maps").
//! Twin: `sh.wgsl` (`sh_` + the same names).

use glam::Vec3;

/// Coefficients per colour channel: bands 0, 1 and 2.
pub const COEFFS: usize = 9;

/// The band factors `Λ_l / π` of the clamped cosine `max(⟨n,l⟩, 0)`: convolved with them the
/// coefficients give `∫ L(l) max(⟨n,l⟩, 0) dl / π`, the irradiance ÷ π (1 under a uniform
/// radiance of 1).
pub const COSINE: [f32; 3] = [1.0, 2.0 / 3.0, 0.25];

/// The band factors `Λ_l / π` of the Ashikhmin–Shirley diffuse lobe (thesis Eq. 5.4 without
/// its constant factors): `k(c) = c (1 − (1 − c/2)⁵)` for `c = ⟨n,l⟩ > 0`, 0 below. Band 0 is
/// 23/28, which the thesis's 28/23 normalises.
pub const AS_DIFFUSE: [f32; 3] = [23.0 / 28.0, 0.585_193_45, 0.268_229_17];

/// The basis's normalisations: `Y₀₀ = ½ √(1/π)`; band 1 `√(3/4π)`; `Y₂₋₂, Y₂₋₁, Y₂₁`
/// `½ √(15/π)`; `Y₂₀` `¼ √(5/π)`; `Y₂₂` `¼ √(15/π)`.
pub const Y0: f32 = 0.282_094_8;
pub const Y1: f32 = 0.488_602_5;
pub const Y2: f32 = 1.092_548_4;
pub const Y20: f32 = 0.315_391_57;
pub const Y22: f32 = 0.546_274_2;

/// The nine real spherical harmonics at the unit direction `d`, in the order
/// (l, m) = (0, 0), (1, −1), (1, 0), (1, 1), (2, −2), (2, −1), (2, 0), (2, 1), (2, 2).
pub fn basis(d: Vec3) -> [f32; COEFFS] {
    [
        Y0,
        Y1 * d.y,
        Y1 * d.z,
        Y1 * d.x,
        Y2 * d.x * d.y,
        Y2 * d.y * d.z,
        Y20 * (3.0 * d.z * d.z - 1.0),
        Y2 * d.x * d.z,
        Y22 * (d.x * d.x - d.y * d.y),
    ]
}

/// The band of coefficient `i` (0, 1 or 2).
pub fn band(i: usize) -> usize {
    match i {
        0 => 0,
        1..=3 => 1,
        _ => 2,
    }
}

/// `∫ L(l) k(⟨n,l⟩) dl / π` for the radiance `L` of coefficients `c` (RGB per coefficient)
/// and the zonal lobe `k` of band factors `bands` ([`COSINE`], [`AS_DIFFUSE`]), at the unit
/// normal `n` (Funk–Hecke). Negative results, which a truncated expansion can give where
/// the light is very uneven, are clamped to 0.
pub fn convolve(c: &[Vec3; COEFFS], bands: [f32; 3], n: Vec3) -> Vec3 {
    let y = basis(n);
    let mut e = Vec3::ZERO;
    for i in 0..COEFFS {
        e += c[i] * (y[i] * bands[band(i)]);
    }
    e.max(Vec3::ZERO)
}

/// The share `1 − W(⟨n,v⟩)` of a cosine lobe that the dielectric Fresnel weight `(1 − ⟨v,h⟩)⁵`
/// leaves, averaged over the lobe under uniform light: `W(c) = ∫ (1 − ⟨v,h⟩)⁵ ⟨n,l⟩ dl / π`
/// with `h` the half vector of `v` and `l`, as a polynomial in `1 − c` fitted to quadrature
/// (within 2·10⁻⁵; `W` is at most 0.028). glTF's diffuse base `(1 − F(⟨v,h⟩)) C / π`
/// integrated against the irradiance is `(1 − F₀) (1 − W) C E / π` where the light is smooth.
pub fn fresnel_cosine_weight(nv: f32) -> f32 {
    let s = 1.0 - nv.clamp(0.0, 1.0);
    let w = 8.280_397e-5
        + s * (2.011_767_4e-3 + s * (9.362_331e-3 + s * (7.705_992e-3 + s * 9.002_511e-3)));
    1.0 - w
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// `f` integrated over the sphere by the midpoint rule in (cos θ, φ).
    fn sphere(n: usize, f: impl Fn(Vec3) -> f64) -> f64 {
        let mut sum = 0.0;
        for i in 0..n {
            let z = -1.0 + (i as f64 + 0.5) * 2.0 / n as f64;
            let r = (1.0 - z * z).sqrt();
            for j in 0..2 * n {
                let phi = (j as f64 + 0.5) * PI / n as f64;
                let d = Vec3::new((r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32);
                sum += f(d);
            }
        }
        sum * (2.0 / n as f64) * (PI / n as f64)
    }

    #[test]
    fn the_basis_is_orthonormal() {
        for i in 0..COEFFS {
            for j in 0..COEFFS {
                let g = sphere(400, |d| f64::from(basis(d)[i]) * f64::from(basis(d)[j]));
                let want = if i == j { 1.0 } else { 0.0 };
                assert!((g - want).abs() < 1e-4, "⟨Y{i}, Y{j}⟩ = {g}");
            }
        }
    }

    /// The band factors of the lobe `k` by quadrature: `2 ∫₀¹ k(t) P_l(t) dt`.
    fn band_factors(k: impl Fn(f64) -> f64) -> [f64; 3] {
        let p = [
            |_t: f64| 1.0,
            |t: f64| t,
            |t: f64| 0.5 * (3.0 * t * t - 1.0),
        ];
        let n = 100_000;
        p.map(|p| {
            (0..n)
                .map(|i| {
                    let t = (i as f64 + 0.5) / n as f64;
                    k(t) * p(t)
                })
                .sum::<f64>()
                * 2.0
                / n as f64
        })
    }

    #[test]
    fn band_factors_are_the_lobes() {
        let cosine = band_factors(|t| t);
        let ashikhmin = band_factors(|t| t * (1.0 - (1.0 - 0.5 * t).powi(5)));
        for l in 0..3 {
            assert!(
                (cosine[l] - f64::from(COSINE[l])).abs() < 1e-6,
                "{cosine:?}"
            );
            assert!(
                (ashikhmin[l] - f64::from(AS_DIFFUSE[l])).abs() < 1e-6,
                "{ashikhmin:?}"
            );
        }
    }

    #[test]
    fn convolution_gives_the_analytic_irradiance() {
        // L = 1 + z: coefficients by projection; irradiance ÷ π is 5/3 facing up, 1 sideways,
        // 1/3 facing down (exact: L lies in bands 0 and 1).
        let mut c = [Vec3::ZERO; COEFFS];
        for (i, ci) in c.iter_mut().enumerate() {
            *ci = Vec3::splat(sphere(300, |d| f64::from((1.0 + d.z) * basis(d)[i])) as f32);
        }
        let e = |n: Vec3| convolve(&c, COSINE, n).x;
        assert!((e(Vec3::Z) - 5.0 / 3.0).abs() < 1e-4, "{}", e(Vec3::Z));
        assert!((e(Vec3::X) - 1.0).abs() < 1e-4, "{}", e(Vec3::X));
        assert!((e(-Vec3::Z) - 1.0 / 3.0).abs() < 1e-4, "{}", e(-Vec3::Z));
    }

    #[test]
    fn the_fresnel_weight_fits_its_quadrature() {
        let f0 = 0.0;
        for k in 0..=20 {
            let nv = k as f32 / 20.0;
            let v = Vec3::new((1.0 - nv * nv).max(0.0).sqrt(), 0.0, nv);
            let w = sphere(600, |l| {
                if l.z <= 0.0 {
                    return 0.0;
                }
                let h = (v + l).normalize_or_zero();
                let vh = f64::from(v.dot(h).clamp(0.0, 1.0));
                (1.0 - vh).powi(5) * f64::from(l.z)
            }) / PI;
            let fit = 1.0 - f64::from(fresnel_cosine_weight(nv));
            assert!(
                (fit - w).abs() < 2e-5 + f0,
                "nv {nv}: fit {fit}, quadrature {w}"
            );
        }
        assert_eq!(fresnel_cosine_weight(-1.0), fresnel_cosine_weight(0.0));
        assert_eq!(fresnel_cosine_weight(2.0), fresnel_cosine_weight(1.0));
    }
}
