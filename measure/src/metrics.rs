//! Image error metrics (thesis §6.1): RMSE in CIELAB and in linear RGB over a mask, and PSNR.
//!
//! **From linear HDR RGB to CIELAB.** Pixels are linear RGB with the sRGB / Rec. 709 primaries
//! and white point D65 (what the bake and the renderer produce). A pixel is divided by the
//! *reference white* `white` (default 1.0: a linear value of 1 is diffuse white), taken to
//! CIE XYZ by the sRGB matrix (IEC 61966-2-1), and to L*a*b* with the D65 white
//! (Xn, Yn, Zn) = (0.95047, 1, 1.08883) and the CIE 1976 formulas (with the linear segment
//! below (6/29)³). L* is 0..100 for 0..white and grows past 100 above it (HDR values are not
//! clipped); negative or non-finite channels are errors, not silently clamped.
//!
//! **Reported numbers.** RMSE per channel over the masked pixels, in L*a*b* units (L* 0..100),
//! and *normalized* by 100 (so that L* runs 0..1), which is the scale of the thesis's tables
//! (Table 6.2: 0.137 for the OSLF mirror, 0.198 for the environment map); RMSE per linear RGB
//! channel; PSNR = 10 log10(white² / MSE) over the three RGB channels together.

use serde::{Deserialize, Serialize};

use crate::error::{MeasureError, Result};

/// The D65 reference white in XYZ (Y = 1).
pub const D65: [f64; 3] = [0.95047, 1.0, 1.08883];

/// Linear sRGB (D65) to CIE XYZ (IEC 61966-2-1).
const RGB_TO_XYZ: [[f64; 3]; 3] = [
    [0.4124564, 0.3575761, 0.1804375],
    [0.2126729, 0.7151522, 0.0721750],
    [0.0193339, 0.1191920, 0.9503041],
];

fn lab_f(t: f64) -> f64 {
    const DELTA: f64 = 6.0 / 29.0;
    if t > DELTA * DELTA * DELTA {
        t.cbrt()
    } else {
        t / (3.0 * DELTA * DELTA) + 4.0 / 29.0
    }
}

/// Linear RGB to L*a*b* (L* 0..100 at `white`).
pub fn rgb_to_lab(rgb: [f32; 3], white: f64) -> [f64; 3] {
    let c = rgb.map(|v| f64::from(v) / white);
    let mut xyz = [0.0; 3];
    for (x, row) in xyz.iter_mut().zip(RGB_TO_XYZ) {
        *x = row[0] * c[0] + row[1] * c[1] + row[2] * c[2];
    }
    let [fx, fy, fz] = [0, 1, 2].map(|i| lab_f(xyz[i] / D65[i]));
    [116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)]
}

/// The comparison of two images over a mask.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Metrics {
    /// Pixels compared (inside the mask).
    pub pixels: u64,
    /// RMSE of L*, a*, b* (CIELAB units, L* 0..100).
    pub rmse_lab: [f64; 3],
    /// The same divided by 100: the thesis's scale.
    pub rmse_lab_normalized: [f64; 3],
    /// RMSE of linear R, G, B.
    pub rmse_rgb: [f64; 3],
    /// 10 log10(white² / MSE of RGB), in dB (infinite for identical images is reported as
    /// `None`).
    pub psnr_db: Option<f64>,
    /// The reference white used.
    pub white: f64,
}

/// Compares `test` against `reference` (RGBA, row-major, equal sizes) over the pixels where
/// `mask` is true. Errors name the first pixel that is negative or not finite.
pub fn compare(
    reference: &[[f32; 4]],
    test: &[[f32; 4]],
    width: usize,
    mask: impl Fn(usize) -> bool,
    white: f64,
) -> Result<Metrics> {
    if reference.len() != test.len() {
        return Err(MeasureError::Invalid(format!(
            "invalid parameter: images differ in size: {} and {} pixels",
            reference.len(),
            test.len()
        )));
    }
    // Beyond this range every pixel is L* 0 or L* 100 and the metric says nothing.
    if !(1e-6..=1e6).contains(&white) {
        return Err(MeasureError::Invalid(format!(
            "invalid parameter: reference white {white} must be between 1e-6 and 1e6 (the linear value that is L* = 100)"
        )));
    }
    let check = |which: &str, i: usize, p: &[f32; 4]| {
        if p[..3].iter().all(|c| c.is_finite() && *c >= 0.0) {
            Ok(())
        } else {
            Err(MeasureError::Invalid(format!(
                "invalid parameter: {which} image: pixel ({}, {}) is {:?} (must be finite and non-negative)",
                i % width.max(1),
                i / width.max(1),
                &p[..3]
            )))
        }
    };
    let (mut n, mut lab, mut rgb) = (0u64, [0f64; 3], [0f64; 3]);
    for (i, (r, t)) in reference.iter().zip(test).enumerate() {
        if !mask(i) {
            continue;
        }
        check("reference", i, r)?;
        check("test", i, t)?;
        let (lr, lt) = (
            rgb_to_lab([r[0], r[1], r[2]], white),
            rgb_to_lab([t[0], t[1], t[2]], white),
        );
        for k in 0..3 {
            lab[k] += (lr[k] - lt[k]).powi(2);
            rgb[k] += (f64::from(r[k]) - f64::from(t[k])).powi(2);
        }
        n += 1;
    }
    let denom = n.max(1) as f64;
    let rmse_lab = lab.map(|s| (s / denom).sqrt());
    let rmse_rgb = rgb.map(|s| (s / denom).sqrt());
    let mse = rgb.iter().sum::<f64>() / (3.0 * denom);
    Ok(Metrics {
        pixels: n,
        rmse_lab,
        rmse_lab_normalized: rmse_lab.map(|v| v / 100.0),
        rmse_rgb,
        psnr_db: (mse > 0.0).then(|| 10.0 * (white * white / mse).log10()),
        white,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Reference values: Bruce Lindbloom's calculator (sRGB, D65, Bradford off), i.e. the
    /// CIE formulas with the matrix above.
    #[test]
    fn lab_matches_published_values() {
        for (rgb, lab) in [
            ([1.0, 1.0, 1.0], [100.0, 0.0, 0.0]),
            ([1.0, 0.0, 0.0], [53.2408, 80.0925, 67.2032]),
            ([0.0, 1.0, 0.0], [87.7347, -86.1827, 83.1793]),
            ([0.0, 0.0, 1.0], [32.2970, 79.1875, -107.8602]),
            ([0.18, 0.18, 0.18], [49.4961, 0.0, 0.0]),
            ([0.0, 0.0, 0.0], [0.0, 0.0, 0.0]),
        ] {
            let got = rgb_to_lab(rgb, 1.0);
            for k in 0..3 {
                assert!(
                    (got[k] - lab[k]).abs() < 0.01,
                    "{rgb:?}: {got:?} vs {lab:?}"
                );
            }
        }
        // The reference white scales: 4 at white 4 is white.
        let w = rgb_to_lab([4.0, 4.0, 4.0], 4.0);
        assert!((w[0] - 100.0).abs() < 1e-4, "{w:?}");
        // HDR above white is not clipped.
        assert!(rgb_to_lab([8.0, 8.0, 8.0], 1.0)[0] > 200.0);
    }

    #[test]
    fn rmse_and_psnr_of_a_known_difference() {
        let a = vec![[0.5f32, 0.5, 0.5, 1.0]; 4];
        let mut b = a.clone();
        b[0] = [0.6, 0.5, 0.5, 1.0];
        let m = compare(&a, &b, 2, |_| true, 1.0).unwrap();
        assert_eq!(m.pixels, 4);
        assert!((m.rmse_rgb[0] - (0.01f64 / 4.0).sqrt()).abs() < 1e-6);
        assert_eq!(m.rmse_rgb[1], 0.0);
        let mse: f64 = 0.01 / 12.0;
        assert!((m.psnr_db.unwrap() - 10.0 * (1.0 / mse).log10()).abs() < 1e-3);
        assert!(m.rmse_lab[0] > 0.0 && m.rmse_lab[1] > 0.0);
        assert!((m.rmse_lab_normalized[0] - m.rmse_lab[0] / 100.0).abs() < 1e-12);
        // Masked out, the difference vanishes.
        let m = compare(&a, &b, 2, |i| i != 0, 1.0).unwrap();
        assert_eq!((m.pixels, m.rmse_lab, m.psnr_db), (3, [0.0; 3], None));
    }

    #[test]
    fn bad_pixels_are_named() {
        let a = vec![[0.5f32, 0.5, 0.5, 1.0]; 4];
        let mut b = a.clone();
        b[3][1] = f32::NAN;
        let e = compare(&a, &b, 2, |_| true, 1.0).unwrap_err().to_string();
        assert!(e.contains("test image") && e.contains("(1, 1)"), "{e}");
        b[3][1] = -1.0;
        assert!(compare(&a, &b, 2, |_| true, 1.0).is_err());
        assert!(compare(&a, &a[..3], 2, |_| true, 1.0).is_err());
    }
}
