//! Colour transfer functions: sRGB (IEC 61966-2-1) both ways, the ACES filmic tone curve the
//! PNG previews and the viewer use, and Rec. 709 luminance. Twin: `color.wgsl`.

use glam::Vec3;

/// The sRGB transfer function, encoded `[0, 1]` to linear.
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// The inverse sRGB transfer function, linear to encoded: clamped to `[0, 1]` first, NaN
/// taken as 0.
pub fn linear_to_srgb(c: f32) -> f32 {
    let x = if c.is_nan() { 0.0 } else { c.clamp(0.0, 1.0) };
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// The ACES filmic tone curve (Narkowicz 2015 fit): `[0, ∞)` to `[0, 1)`; NaN and negative
/// values give 0, values above 10⁶ are taken as 10⁶.
pub fn aces(x: f32) -> f32 {
    if x.is_nan() || x <= 0.0 {
        return 0.0;
    }
    let x = x.min(1e6);
    ((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14)).clamp(0.0, 1.0)
}

/// Rec. 709 / sRGB luminance of linear RGB.
pub fn luminance(c: Vec3) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_round_trips_and_reference_values() {
        for i in 0..=255 {
            let c = i as f32 / 255.0;
            assert!((linear_to_srgb(srgb_to_linear(c)) - c).abs() < 1e-5, "{c}");
        }
        assert!((srgb_to_linear(0.5) - 0.214_041).abs() < 1e-5);
        assert_eq!(linear_to_srgb(f32::NAN), 0.0);
        assert_eq!(linear_to_srgb(-1.0), 0.0);
        assert!((linear_to_srgb(f32::INFINITY) - 1.0).abs() < 1e-6);
    }

    #[test]
    fn aces_is_monotone_and_bounded() {
        assert_eq!(aces(f32::NAN), 0.0);
        assert_eq!(aces(-1.0), 0.0);
        assert!(aces(f32::INFINITY) <= 1.0);
        let mut last = 0.0;
        for i in 0..400 {
            let v = aces(i as f32 * 0.05);
            assert!(v >= last && v <= 1.0);
            last = v;
        }
    }
}
