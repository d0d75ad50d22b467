//! Denoising the captured cube maps: a bake-time filter that averages each texel with the
//! neighbours of its face that see the same surface and whose values differ from its own by
//! no more than their noise explains, so that smooth, noisy radiance (indirect light on a
//! shaded ceiling) is averaged while edges, textures and shadows whose contrast stands above
//! the noise are kept. Both capture devices hand their cubes to [`denoise_cube`] before they
//! are encoded, so CPU and GPU stores are filtered by the same code.
//!
//! Per texel i of a face, with luminance `Y`, the variance of its mean `V` (its samples'
//! variance ÷ their count, [`crate::noise`]) and the distance `D` to what it sees:
//!
//! - `V̄ᵢ`: the mean of `V` over the 3 × 3 texels around i that see its surface (a variance
//!   from a texel's own few samples is too unsteady to weigh by; Schied et al. 2017 smooth it
//!   spatially for the same reason);
//! - over the (2R + 1)² window of the face around i, each texel j on the same surface
//!   (`|Dᵢ − Dⱼ| ≤ DEPTH_SLOPE · θ · o · min(Dᵢ, Dⱼ)`, θ a texel's angle, o the offset in texels;
//!   rays that escaped only with rays that escaped) weighs
//!   `wⱼ = exp(−max(0, (Yᵢ − Yⱼ)² − Sᵢⱼ) / (K² Sᵢⱼ))`, `Sᵢⱼ = V̄ᵢ + V̄ⱼ`:
//!   the non-local-means distance of Rousselle et al. 2012 ("Adaptive rendering with non-local
//!   means filtering") for one-texel patches: 1 where the difference is what the noise of the
//!   two would give, falling off as it exceeds it;
//! - the texel's value becomes `Σ wⱼ cⱼ / Σ wⱼ` (RGB; its own weight is 1).
//!
//! `Sᵢⱼ` also holds a floor, `(f Yᵢ)² + (f Yⱼ)²` with f = [`NOISE_FLOOR`], and a texel whose
//! `V̄ᵢ` is below its own `(f Yᵢ)²` counts as noise-free: rounding (the GPU sums luminance in
//! f32) then decides nothing. A texel without noise (the sky seen directly, a surface every
//! sample agrees on)
//! or without an estimate (fewer than two samples: `V` < 0) keeps its value, and texels without
//! an estimate are no one's neighbours. The filter trades noise for a bias where the radiance
//! varies within a window by less than the noise: it flattens such gradients and low-contrast
//! texture; docs/measurements.md ("Denoised cube maps") measures what it gains against a
//! capture of many samples. Without a distance channel, every texel of the window counts as
//! the same surface. Texels are filtered face by face: the window stops at a face's edge.
//!
//! The arithmetic is per texel, in a fixed order, so the result does not depend on the thread
//! count.

use std::f32::consts::FRAC_PI_2;

use oslf_format::CubeImage;

use crate::noise::luminance;

/// Texels on each side of a texel that its filtered value may average: a 5 × 5 window.
pub const RADIUS: usize = 2;
/// How far past the noise a difference may go before it stops counting as noise, in the
/// noise's standard deviations (Rousselle et al. 2012's k). Measured on the gazebo and the
/// room's teapot at 1, 2, 3 and 4 (docs/measurements.md, "Denoised cube maps"): 2 gains on
/// both; wider blurs the gazebo's shaded checkerboard, narrower leaves the teapot's speckle.
pub const RANGE_SCALE: f32 = 2.0;
/// Noise below this share of a texel's luminance counts as none: such a texel keeps its value,
/// and the two texels' share is added to every comparison's `S`. It sits above the rounding of
/// the GPU's f32 luminance sums (whose variance of four nearly equal samples is otherwise
/// mostly rounding), so that both devices make the same choices.
pub const NOISE_FLOOR: f32 = 1e-3;
/// The steepest surface the window follows as one: the distance may change by this many times
/// a texel's angle per texel of offset (a surface seen about 76° from head-on).
pub const DEPTH_SLOPE: f32 = 4.0;

/// The variance of each texel's value (the mean luminance of its samples), face by face in
/// the cube's texel order; negative where it has no estimate (fewer than two samples).
pub type TexelVariance = [Vec<f32>; 6];

/// Denoises `cube` in place, given the variance of each texel's value (module docs).
pub fn denoise_cube(cube: &mut CubeImage, variance: &TexelVariance) {
    let res = cube.resolution as usize;
    let theta = FRAC_PI_2 / cube.resolution.max(1) as f32;
    for face in 0..6 {
        let distance = cube
            .distance
            .as_ref()
            .map(|d| d[face].as_slice())
            .filter(|d| d.len() == res * res);
        let texels = &cube.faces[face];
        let v = &variance[face];
        if texels.len() != res * res || v.len() != res * res {
            continue;
        }
        let window = Window {
            res,
            distance,
            theta,
        };
        let lum: Vec<f32> = texels.iter().map(|c| luminance(*c) as f32).collect();
        let smoothed: Vec<f32> = (0..res * res)
            .map(|i| window.smoothed_variance(i, v))
            .collect();
        let filtered: Vec<[f32; 3]> = (0..res * res)
            .map(|i| window.filter(i, texels, &lum, &smoothed))
            .collect();
        cube.faces[face] = filtered;
    }
}

/// One face's geometry: its size, its distance plane if any, and a texel's angle.
struct Window<'a> {
    res: usize,
    distance: Option<&'a [f32]>,
    theta: f32,
}

// `!(v >= 0.0)`: a NaN variance (none reaches here, but no NaN may reach a texel) counts as
// no estimate.
#[allow(clippy::neg_cmp_op_on_partial_ord)]
impl Window<'_> {
    /// Calls `visit(j, offset)` for the texels within `radius` of texel `i` (itself
    /// included), row by row, `offset` in texels (the larger of the two axes').
    fn around(&self, i: usize, radius: usize, mut visit: impl FnMut(usize, f32)) {
        let (x, y) = (i % self.res, i / self.res);
        let (x0, x1) = (x.saturating_sub(radius), (x + radius).min(self.res - 1));
        let (y0, y1) = (y.saturating_sub(radius), (y + radius).min(self.res - 1));
        for v in y0..=y1 {
            let row = v * self.res;
            for u in x0..=x1 {
                visit(row + u, u.abs_diff(x).max(v.abs_diff(y)) as f32);
            }
        }
    }

    /// Whether texels `i` and `j`, `offset` texels apart, see the same surface.
    fn same_surface(&self, i: usize, j: usize, offset: f32) -> bool {
        let Some(d) = self.distance else {
            return true;
        };
        let (a, b) = (d[i], d[j]);
        if a == f32::MAX || b == f32::MAX {
            return a == b;
        }
        (a - b).abs() <= DEPTH_SLOPE * self.theta * offset * a.min(b)
    }

    /// `V̄ᵢ`: the mean variance over the 3 × 3 texels around `i` on its surface that have an
    /// estimate; negative when `i` has none.
    fn smoothed_variance(&self, i: usize, v: &[f32]) -> f32 {
        if !(v[i] >= 0.0) {
            return -1.0;
        }
        let (mut sum, mut count) = (0.0f32, 0.0f32);
        self.around(i, 1, |j, offset| {
            if v[j] >= 0.0 && self.same_surface(i, j, offset) {
                sum += v[j];
                count += 1.0;
            }
        });
        sum / count
    }

    /// Texel `i`'s filtered value.
    fn filter(&self, i: usize, texels: &[[f32; 3]], lum: &[f32], vbar: &[f32]) -> [f32; 3] {
        let floor = |j: usize| (NOISE_FLOOR * lum[j]).powi(2);
        if !(vbar[i] > floor(i)) {
            return texels[i];
        }
        let (mut acc, mut wsum) = ([0.0f32; 3], 0.0f32);
        self.around(i, RADIUS, |j, offset| {
            if !(vbar[j] >= 0.0) || !self.same_surface(i, j, offset) {
                return;
            }
            let s = vbar[i] + vbar[j] + floor(i) + floor(j);
            let diff = lum[i] - lum[j];
            let excess = (diff * diff - s).max(0.0) / (RANGE_SCALE * RANGE_SCALE * s);
            // exp(−16) ≈ 10⁻⁷: nothing a sum of at most 25 weights of which one is 1 keeps.
            if excess < 16.0 {
                let w = (-excess).exp();
                for (a, c) in acc.iter_mut().zip(texels[j]) {
                    *a += w * c;
                }
                wsum += w;
            }
        });
        acc.map(|a| a / wsum)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A one-face cube (the other faces black and noise-free) with `texels` on face 0.
    fn cube(res: u32, texels: Vec<[f32; 3]>, distance: Option<Vec<f32>>) -> CubeImage {
        let n = (res * res) as usize;
        let mut faces: [Vec<[f32; 3]>; 6] = Default::default();
        for f in &mut faces {
            *f = vec![[0.0; 3]; n];
        }
        faces[0] = texels;
        let distance = distance.map(|d| {
            let mut planes: [Vec<f32>; 6] = Default::default();
            for p in &mut planes {
                *p = vec![1.0; n];
            }
            planes[0] = d;
            planes
        });
        CubeImage {
            resolution: res,
            faces,
            distance,
        }
    }

    /// Deterministic standard normal numbers (Box–Muller over a 64-bit LCG).
    fn normals(n: usize, seed: u64) -> Vec<f32> {
        let mut s = seed;
        let mut next = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 11) as f64 + 0.5) / (1u64 << 53) as f64
        };
        (0..n)
            .map(|_| {
                let (u, v) = (next(), next());
                ((-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()) as f32
            })
            .collect()
    }

    /// `clean` plus `sigma` times the normal numbers `z`.
    fn add_noise(clean: &[[f32; 3]], z: &[f32], sigma: f32) -> Vec<[f32; 3]> {
        clean
            .iter()
            .zip(z)
            .map(|(c, n)| c.map(|v| v + sigma * n))
            .collect()
    }

    fn variance(res: u32, face0: Vec<f32>) -> TexelVariance {
        let n = (res * res) as usize;
        let mut v: TexelVariance = Default::default();
        for f in &mut v {
            *f = vec![0.0; n];
        }
        v[0] = face0;
        v
    }

    fn rms(a: &[[f32; 3]], b: &[[f32; 3]]) -> f32 {
        let s: f32 = a.iter().zip(b).map(|(x, y)| (x[1] - y[1]).powi(2)).sum();
        (s / a.len() as f32).sqrt()
    }

    /// On a smooth gradient with noise of known variance, the filter lowers the error against
    /// the noise-free values by at least half and keeps the mean within a tenth of the noise.
    #[test]
    fn noise_on_a_smooth_surface_is_averaged() {
        let res = 32u32;
        let sigma = 0.2f32;
        let z = normals((res * res) as usize, 7);
        let clean: Vec<[f32; 3]> = (0..res * res)
            .map(|i| {
                let v = 1.0 + 0.3 * (i % res) as f32 / res as f32;
                [v, v, v]
            })
            .collect();
        let noisy = add_noise(&clean, &z, sigma);
        let mut c = cube(res, noisy.clone(), Some(vec![2.0; (res * res) as usize]));
        denoise_cube(
            &mut c,
            &variance(res, vec![sigma * sigma; (res * res) as usize]),
        );
        let (before, after) = (rms(&noisy, &clean), rms(&c.faces[0], &clean));
        assert!(after < 0.5 * before, "error {before} → {after}");
        let mean = |t: &[[f32; 3]]| t.iter().map(|c| c[1]).sum::<f32>() / t.len() as f32;
        assert!((mean(&c.faces[0]) - mean(&clean)).abs() < 0.1 * sigma);
        assert!(c.faces[0].iter().flatten().all(|v| v.is_finite()));
    }

    /// An edge whose contrast stands far above the noise is kept: every texel stays within
    /// four noise deviations of its own side's value, and texels of another surface (a distance
    /// step) are not averaged in even where their radiance agrees.
    #[test]
    fn edges_above_the_noise_and_other_surfaces_are_kept() {
        let res = 16u32;
        let sigma = 0.02f32;
        let n = (res * res) as usize;
        let z = normals(n, 3);
        let side = |i: usize| i % res as usize >= 8;
        let clean: Vec<[f32; 3]> = (0..n)
            .map(|i| if side(i) { [2.0; 3] } else { [0.5; 3] })
            .collect();
        let noisy = add_noise(&clean, &z, sigma);
        let mut c = cube(res, noisy.clone(), None);
        denoise_cube(&mut c, &variance(res, vec![sigma * sigma; n]));
        for (i, (f, k)) in c.faces[0].iter().zip(&clean).enumerate() {
            assert!((f[1] - k[1]).abs() < 4.0 * sigma, "texel {i}: {f:?}");
        }
        // Equal radiance, noise only, but rows 0..8 at distance 1 and 8..16 at 10: the
        // filter never mixes across the step, so each half's texels average their own half.
        let flat: Vec<[f32; 3]> = z.iter().map(|n| [1.0 + sigma * n; 3]).collect();
        let dist: Vec<f32> = (0..n)
            .map(|i| if i / res as usize >= 8 { 10.0 } else { 1.0 })
            .collect();
        let mut a = cube(res, flat.clone(), Some(dist.clone()));
        let mut b_top = flat.clone();
        b_top[(8 * res) as usize..].fill([100.0; 3]);
        let mut b = cube(res, b_top, Some(dist));
        let v = variance(res, vec![sigma * sigma; n]);
        denoise_cube(&mut a, &v);
        denoise_cube(&mut b, &v);
        // The top half does not see the bottom half's change.
        assert_eq!(
            a.faces[0][..8 * res as usize],
            b.faces[0][..8 * res as usize]
        );
    }

    /// Texels without noise or without an estimate keep their values bit for bit.
    #[test]
    fn texels_without_noise_or_an_estimate_are_left_alone() {
        let res = 8u32;
        let n = (res * res) as usize;
        let texels: Vec<[f32; 3]> = (0..n).map(|i| [i as f32, 1.0, 2.0]).collect();
        let mut zero = cube(res, texels.clone(), None);
        denoise_cube(&mut zero, &variance(res, vec![0.0; n]));
        assert_eq!(zero.faces[0], texels);
        let mut unknown = cube(res, texels.clone(), None);
        denoise_cube(&mut unknown, &variance(res, vec![-1.0; n]));
        assert_eq!(unknown.faces[0], texels);
    }
}
