//! The Monte Carlo noise of the captured cube maps: how far the cube texels' values
//! (each the mean of its `samples_per_texel` stratified samples) may lie from the radiance
//! they estimate, relative to it, gathered over the capture without changing what it writes.
//!
//! Per texel, from the luminance `Y` of its `n` samples: the variance of its mean, `s² / n`
//! (`s²` the samples' variance, with `n − 1`: unbiased), and its mean squared. Over the
//! texels that see a surface of the scene (the sky seen directly is not the capture's noise),
//! the relative standard error is `√(Σ s²/n ÷ Σ mean²)`: the noise's share of the captured
//! radiance, weighted by brightness as the eye sees it. Sums over many texels keep the estimate
//! steady where light arrives by rare paths (a few samples of one texel mostly miss them; the
//! sums over all texels do not), and it falls as 1/√n as the samples grow. The samples are
//! stratified over the texel, so where the radiance varies smoothly across it the true error
//! is lower: the estimate errs on the side of noise. One sample per texel has no variance to
//! measure: no estimate.
//!
//! The sums are f64, added in a fixed order (texels in a band, bands in a cube, cubes in
//! store order), so the estimate does not depend on the thread count.

/// Above this relative standard error, the noise shows: the runtime's mirror and glossy terms
/// read cube texels directly, and a few per cent of speckle is visible on a smooth reflection.
/// The summary then suggests more samples.
pub const VISIBLE_RELATIVE_ERROR: f64 = 0.05;

/// The mean and the unbiased variance (with `n − 1`) of `n` ≥ 2 samples from their sum and sum
/// of squares; rounding can leave a tiny negative variance for equal samples, taken as 0.
fn mean_and_variance(sum: f64, sum_sq: f64, n: u32) -> (f64, f64) {
    let nf = f64::from(n);
    let mean = sum / nf;
    (mean, ((sum_sq - nf * mean * mean) / (nf - 1.0)).max(0.0))
}

/// The variance of the mean of `n` samples' luminance from their sum and sum of squares, as
/// [`crate::denoise`] weighs texels by; −1 (no estimate) for fewer than two samples.
pub fn variance_of_mean(sum: f64, sum_sq: f64, n: u32) -> f32 {
    if n < 2 || !(sum.is_finite() && sum_sq.is_finite()) {
        return -1.0;
    }
    (mean_and_variance(sum, sum_sq, n).1 / f64::from(n)) as f32
}

/// Rounds of `round` samples an adaptive capture's texel takes after its pilot: enough that
/// the relative standard error of their mean luminance, `√(s²/n) / mean`, reaches `target` by
/// the pilot's `n` samples (luminance sum `sum`, sum of squares `sum_sq`; `s²` unbiased, as
/// [`NoiseStats::add_texel`]), within `min_rounds..=max_rounds`. The texel's value is the mean
/// of these later samples alone: they are independent of the pilot that chose their number,
/// so the value is unbiased (a texel stopped by its own samples' variance is biased low where
/// light arrives by rare bright paths: stores of that rule rendered 8–10 % darker on the can).
/// Twin: `rounds_after_pilot` in the GPU bake's capture.wgsl (in f32).
pub fn rounds_after_pilot(
    sum: f64,
    sum_sq: f64,
    n: u32,
    target: f64,
    round: u32,
    (min_rounds, max_rounds): (u32, u32),
) -> u32 {
    let (mean, variance) = mean_and_variance(sum, sum_sq, n.max(2));
    // n s² / (n target² mean²) samples bring the standard error of the mean to target · mean.
    let wanted = variance / (target * target * mean * mean);
    let rounds = if wanted.is_finite() {
        (wanted / f64::from(round.max(1)))
            .ceil()
            .min(f64::from(max_rounds)) as u32
    } else if variance > 0.0 {
        max_rounds
    } else {
        min_rounds
    };
    rounds.clamp(min_rounds, max_rounds.max(min_rounds))
}

/// The noise of a set of cube texels: sums over the texels that see a surface.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct NoiseStats {
    /// Texels with at least two samples, at least one of which hit a surface.
    pub texels: u64,
    /// Every texel counted by [`NoiseStats::count_samples`] (those that see only sky too),
    /// and the samples they took: their ratio is the samples per texel an adaptive capture
    /// spent.
    pub all_texels: u64,
    pub samples: u64,
    /// Σ s² / n over them (luminance).
    pub variance_of_means: f64,
    /// Σ mean² over them.
    pub squared_means: f64,
}

impl NoiseStats {
    /// Adds one texel from the sum and the sum of squares of its `n` samples' luminance;
    /// `sees_surface`: whether a sample hit a surface. Does nothing for `n` < 2 or a texel
    /// that sees only the sky.
    pub fn add_texel(&mut self, sum: f64, sum_sq: f64, n: u32, sees_surface: bool) {
        if n < 2 || !sees_surface || !(sum.is_finite() && sum_sq.is_finite()) {
            return;
        }
        let nf = f64::from(n);
        let (mean, variance) = mean_and_variance(sum, sum_sq, n);
        self.texels += 1;
        self.variance_of_means += variance / nf;
        self.squared_means += mean * mean;
    }

    /// Counts one texel that took `n` samples.
    pub fn count_samples(&mut self, n: u32) {
        self.all_texels += 1;
        self.samples += u64::from(n);
    }

    /// Samples per texel, on average over the texels counted; `None` without any.
    pub fn samples_per_texel(&self) -> Option<f64> {
        (self.all_texels > 0).then(|| self.samples as f64 / self.all_texels as f64)
    }

    /// Adds `other`'s texels.
    pub fn merge(&mut self, other: &NoiseStats) {
        self.texels += other.texels;
        self.all_texels += other.all_texels;
        self.samples += other.samples;
        self.variance_of_means += other.variance_of_means;
        self.squared_means += other.squared_means;
    }

    /// The relative standard error of the texels, `√(Σ s²/n ÷ Σ mean²)`; `None` without a
    /// texel (one sample per texel, only sky) or where all are black.
    pub fn relative_error(&self) -> Option<f64> {
        let r = (self.variance_of_means / self.squared_means).sqrt();
        (self.texels > 0 && self.squared_means > 0.0 && r.is_finite()).then_some(r)
    }
}

/// Luminance (Rec. 709) of a linear RGB radiance, in f64 for the sums of squares.
pub fn luminance(rgb: [f32; 3]) -> f64 {
    0.2126 * f64::from(rgb[0]) + 0.7152 * f64::from(rgb[1]) + 0.0722 * f64::from(rgb[2])
}

/// Samples per texel that bring a relative error of `relative` at `samples` down to
/// [`VISIBLE_RELATIVE_ERROR`] or below: the error falls as 1/√samples, so each halving costs
/// four times the samples. At least four times `samples` (halving the noise).
pub fn samples_for(relative: f64, samples: u32) -> u32 {
    let mut n = u64::from(samples.max(1)) * 4;
    let mut error = relative / 2.0;
    while error > VISIBLE_RELATIVE_ERROR && n < u64::from(u32::MAX) / 4 {
        n *= 4;
        error /= 2.0;
    }
    n.min(u64::from(u32::MAX)) as u32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_texels_relative_error_is_the_standard_error_of_its_mean_over_the_mean() {
        // Samples 0 and 2: mean 1, s² = 2, standard error √(2/2) = 1.
        let mut h = NoiseStats::default();
        h.add_texel(2.0, 4.0, 2, true);
        assert!((h.relative_error().unwrap() - 1.0).abs() < 1e-12);
        // Samples 1, 1, 1, 3: mean 1.5, s² = 1, standard error 0.5, relative 1/3.
        let mut h = NoiseStats::default();
        h.add_texel(6.0, 12.0, 4, true);
        assert!((h.relative_error().unwrap() * 3.0 - 1.0).abs() < 1e-12);
    }

    #[test]
    fn sky_texels_and_single_samples_are_not_counted_equal_samples_are_noise_free() {
        let mut h = NoiseStats::default();
        h.add_texel(6.0, 12.0, 4, false);
        h.add_texel(1.0, 1.0, 1, true);
        assert_eq!(h.relative_error(), None);
        h.add_texel(4.0 * 0.3, 4.0 * 0.09, 4, true);
        assert_eq!(h.texels, 1);
        assert!(h.relative_error().unwrap() < 1e-6);
    }

    #[test]
    fn merged_texels_weigh_by_brightness() {
        // A bright texel with relative error 1/3 and a dark one with 1: √((0.25 + 0.01·1) /
        // (2.25 + 0.01)) — the bright one's noise dominates.
        let (mut a, mut b) = (NoiseStats::default(), NoiseStats::default());
        a.add_texel(6.0, 12.0, 4, true);
        b.add_texel(0.2, 0.04, 2, true);
        a.merge(&b);
        let expected = ((0.25 + 0.01f64) / (2.25 + 0.01)).sqrt();
        assert!((a.relative_error().unwrap() - expected).abs() < 1e-12);
        assert_eq!(a.texels, 2);
    }

    #[test]
    fn the_suggested_samples_halve_the_error_at_least_and_reach_the_visible_limit() {
        assert_eq!(samples_for(0.08, 4), 16);
        assert_eq!(samples_for(0.12, 4), 64);
        assert_eq!(samples_for(0.3, 16), 1024);
    }
}
