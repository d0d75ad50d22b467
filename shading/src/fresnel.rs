//! Schlick's approximation of the Fresnel factor (thesis Eq. 5.7; glTF Appendix B).
//! Twin: `fresnel.wgsl` (`fresnel_` + the same names).

/// `(1 − c)⁵` for `c` the cosine between the view and the half vector, `1 − c` clamped to
/// `[0, 1]`.
pub fn schlick_weight(c: f32) -> f32 {
    let k = (1.0 - c).clamp(0.0, 1.0);
    let k2 = k * k;
    k2 * k2 * k
}

/// Schlick's Fresnel factor `f0 + (1 − f0)(1 − c)⁵` (Eq. 5.7, with `f0` the reflectance at
/// normal incidence: the thesis's `R_s`).
pub fn schlick(f0: f32, c: f32) -> f32 {
    f0 + (1.0 - f0) * schlick_weight(c)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn schlick_at_both_ends() {
        assert_eq!(schlick(0.04, 1.0), 0.04);
        assert_eq!(schlick(0.04, 0.0), 1.0);
        assert_eq!(schlick_weight(-1.0), 1.0, "clamped");
        assert_eq!(schlick_weight(2.0), 0.0, "clamped");
        assert!((schlick_weight(0.5) - 0.03125).abs() < 1e-9);
    }
}
