//! The noise of the captured cubes, for the report: the estimate of [`oslf_trace::noise`] and, when
//! the noise will show, the samples per texel to ask for and what they cost by the
//! preflight's model ([`crate::preflight`]).

use crate::preflight::Estimate;
use oslf_trace::capture::{sampling_plan, strata_per_side, CaptureSettings};
use oslf_trace::noise::{samples_for, NoiseStats, VISIBLE_RELATIVE_ERROR};

/// How noisy this run's cubes are.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct NoiseReport {
    /// Samples per texel of the capture (rounded up to a square, as captured); with a target,
    /// the most a texel took.
    pub samples_per_texel: u32,
    /// The relative standard error each texel sampled down to (`target_noise`), if any.
    pub target: Option<f64>,
    /// The samples per texel the capture took, on average over every texel: measured.
    pub mean_samples_per_texel: Option<f64>,
    /// Cube texels of this run that see a surface (the estimate is over them).
    pub texels: u64,
    /// Their relative standard error ([`NoiseStats::relative_error`]); `None`: nothing to
    /// estimate from (one sample per texel, only sky, all black).
    pub relative_error: Option<f64>,
    /// Above this, the noise shows ([`VISIBLE_RELATIVE_ERROR`]).
    pub visible_above: f64,
    /// Whether the cubes were denoised before they were stored (`oslf_trace::denoise`): the
    /// error above is the capture's, before the filter.
    pub denoised: bool,
    /// What to raise when it shows; `None` when it does not.
    pub suggestion: Option<NoiseSuggestion>,
}

/// More samples per texel, and what they cost.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct NoiseSuggestion {
    /// `samples_per_texel` to set: 4× the samples, which halve the noise (it falls as
    /// 1/√samples).
    pub samples_per_texel: u32,
    /// The relative error expected then.
    pub expected_relative_error: f64,
    /// The samples per texel (a power of 4 times the present) that bring it to
    /// [`VISIBLE_RELATIVE_ERROR`] or below.
    pub samples_per_texel_below_visible: u32,
    /// The preflight's cube-map time, (optimistic, pessimistic) seconds on `threads`, now
    /// and with the suggested samples (it grows with them linearly).
    pub capture_seconds_now: (f64, f64),
    pub capture_seconds: (f64, f64),
    /// The preflight's whole-bake time with the suggested samples.
    pub total_seconds: (f64, f64),
    pub threads: usize,
}

/// The report of `noise` for the capture `capture`, with the suggestion costed from
/// `estimate` (the preflight's, of this bake's settings). With a target, the suggestion is a
/// higher cap (`samples_per_texel`) where the error achieved is still visible.
pub(super) fn noise_report(
    noise: &NoiseStats,
    capture: &CaptureSettings,
    estimate: &Estimate,
) -> NoiseReport {
    let (k, rounds) = sampling_plan(capture.samples_per_texel, capture.target_noise);
    let samples = k * k * rounds;
    let error = noise.relative_error();
    let suggestion = error.filter(|&m| m > VISIBLE_RELATIVE_ERROR).map(|m| {
        let more = samples.saturating_mul(4);
        let factor = f64::from(more) / f64::from(samples.max(1));
        let now = estimate
            .time
            .iter()
            .find(|t| t.name == "cube maps")
            .map_or((0.0, 0.0), |t| t.seconds);
        let then = (now.0 * factor, now.1 * factor);
        NoiseSuggestion {
            samples_per_texel: more,
            expected_relative_error: m / factor.sqrt(),
            samples_per_texel_below_visible: strata_per_side(samples_for(m, samples)).pow(2),
            capture_seconds_now: now,
            capture_seconds: then,
            total_seconds: (
                estimate.seconds.0 - now.0 + then.0,
                estimate.seconds.1 - now.1 + then.1,
            ),
            threads: estimate.threads,
        }
    });
    NoiseReport {
        samples_per_texel: samples,
        target: (capture.target_noise > 0.0).then_some(f64::from(capture.target_noise)),
        mean_samples_per_texel: noise.samples_per_texel(),
        texels: noise.texels,
        relative_error: error,
        visible_above: VISIBLE_RELATIVE_ERROR,
        denoised: capture.denoise,
        suggestion,
    }
}
