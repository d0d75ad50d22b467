//! The noise of a path-traced reference, and errors corrected for it.
//!
//! A reference rendered with N paths per pixel keeps Monte Carlo noise of its own, and the
//! RMSE of any test against it carries that noise too: in expectation
//! RMSE² = e² + σ², with e the test's own error and σ the reference's noise, independent of
//! the test. Two independent renders `a` and `b` of the reference (other seeds) measure σ:
//! Var(a − b) = 2σ², so their mean, σ²/2 in variance, has a noise of RMSE(a, b) / 2. A test
//! judged against the mean then has e = √(RMSE² − RMSE(a, b)² / 4). The correction is exact in
//! linear RGB and first-order in CIELAB (the noise small against the colour).

use serde::{Deserialize, Serialize};

use crate::metrics::Metrics;
use crate::{MeasureError, Result};

/// The per-pixel mean of two renders of one image (RGBA, row-major, equal sizes; alpha, the
/// object mask, from `a`).
pub fn mean_image(a: &[[f32; 4]], b: &[[f32; 4]]) -> Result<Vec<[f32; 4]>> {
    if a.len() != b.len() {
        return Err(MeasureError::Invalid(format!(
            "invalid parameter: the two references differ in size: {} and {} pixels",
            a.len(),
            b.len()
        )));
    }
    Ok(a.iter()
        .zip(b)
        .map(|(p, q)| {
            [
                0.5 * (p[0] + q[0]),
                0.5 * (p[1] + q[1]),
                0.5 * (p[2] + q[2]),
                p[3],
            ]
        })
        .collect())
}

/// A test's error against the mean of two independent references, with the mean's own noise
/// taken out.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Corrected {
    /// The noise of the references' mean: half the RMSE between the two, per L*, a*, b*.
    pub reference_noise_lab: [f64; 3],
    /// The same per linear R, G, B.
    pub reference_noise_rgb: [f64; 3],
    /// The test's RMSE with that noise removed in quadrature, per L*, a*, b* (0 where the
    /// measured error is within the noise).
    pub rmse_lab: [f64; 3],
    /// The same per linear R, G, B.
    pub rmse_rgb: [f64; 3],
}

/// `measured`: the test against the references' mean; `between`: the first reference against
/// the second, over the same mask.
pub fn corrected(measured: &Metrics, between: &Metrics) -> Corrected {
    let noise = |v: [f64; 3]| v.map(|x| 0.5 * x);
    let less =
        |e: [f64; 3], n: [f64; 3]| [0, 1, 2].map(|i| (e[i] * e[i] - n[i] * n[i]).max(0.0).sqrt());
    let (lab, rgb) = (noise(between.rmse_lab), noise(between.rmse_rgb));
    Corrected {
        reference_noise_lab: lab,
        reference_noise_rgb: rgb,
        rmse_lab: less(measured.rmse_lab, lab),
        rmse_rgb: less(measured.rmse_rgb, rgb),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::metrics::compare;

    /// A smooth image, two references with independent noise of σ = 0.02 over it, and a test
    /// off by 0.01 everywhere: against the references' mean the raw RMSE is √(0.01² + 0.02²/2)
    /// ≈ 0.017; the corrected one finds the 0.01 again, and the noise 0.02/√2.
    #[test]
    fn the_correction_finds_the_tests_own_error_under_the_references_noise() {
        let (w, h) = (200usize, 150usize);
        let clean: Vec<[f32; 4]> = (0..w * h)
            .map(|i| {
                let v = 0.3 + 0.2 * ((i % w) as f32 / w as f32);
                [v, 0.8 * v, 0.6 * v, 1.0]
            })
            .collect();
        // A small deterministic generator: two independent Gaussian fields (Box–Muller).
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut uniform = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            ((state >> 11) as f64 + 0.5) / (1u64 << 53) as f64
        };
        let sigma = 0.02;
        let mut noisy = |img: &[[f32; 4]]| -> Vec<[f32; 4]> {
            img.iter()
                .map(|p| {
                    let mut q = *p;
                    for c in q.iter_mut().take(3) {
                        let (u, v) = (uniform(), uniform());
                        let g = (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos();
                        *c += (sigma * g) as f32;
                    }
                    q
                })
                .collect()
        };
        let (a, b) = (noisy(&clean), noisy(&clean));
        let test: Vec<[f32; 4]> = clean
            .iter()
            .map(|p| [p[0] + 0.01, p[1] + 0.01, p[2] + 0.01, 1.0])
            .collect();
        let mean = mean_image(&a, &b).unwrap();
        let all = |_: usize| true;
        let measured = compare(&mean, &test, w, all, 1.0).unwrap();
        let between = compare(&a, &b, w, all, 1.0).unwrap();
        let c = corrected(&measured, &between);
        for ch in 0..3 {
            let raw = measured.rmse_rgb[ch];
            assert!((raw - (1e-4f64 + 2e-4).sqrt()).abs() < 5e-4, "raw {raw}");
            let e = c.rmse_rgb[ch];
            assert!((e - 0.01).abs() < 5e-4, "corrected {e}");
            let n = c.reference_noise_rgb[ch];
            assert!((n - sigma / 2f64.sqrt()).abs() < 3e-4, "noise {n}");
        }
        // L*: first order, so within a few percent of the clean error.
        let truth = compare(&clean, &test, w, all, 1.0).unwrap();
        let l = c.rmse_lab[0];
        assert!(
            (l / truth.rmse_lab[0] - 1.0).abs() < 0.05 && measured.rmse_lab[0] > 1.2 * l,
            "L*: corrected {l}, measured {}, clean {}",
            measured.rmse_lab[0],
            truth.rmse_lab[0]
        );
    }

    #[test]
    fn references_of_different_sizes_are_refused() {
        let e = mean_image(&[[0.0; 4]; 4], &[[0.0; 4]; 5]).unwrap_err();
        assert!(e.to_string().contains("4 and 5 pixels"), "{e}");
    }
}
