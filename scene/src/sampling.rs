//! Tabulated distributions: piecewise-constant densities in one and two dimensions (the
//! environment map's importance sampling), with the same `sample`/`pdf`/`invert` triplets as
//! the warps of [`oslf_shading::warp`]. Random numbers and warps are oslf-shading's
//! ([`oslf_shading::random`], [`oslf_shading::warp`]).

use glam::Vec2;
use oslf_shading::random::ONE_MINUS_EPSILON;

use crate::{BakeError, Result};

/// A piecewise-constant density on `[0, 1)` with `n` equal bins.
///
/// Negative or non-finite bin values are treated as 0; an all-zero (or empty) function gives
/// the uniform density, so sampling is always possible.
#[derive(Clone, Debug)]
pub struct Distribution1D {
    func: Vec<f32>,
    /// `n + 1` entries `[cdf_i, pdf_i]`: `cdf_0 = 0`, `cdf_n = 1`, and `pdf_i = func[i] /
    /// integral` (`pdf_n = 0`), side by side so that a sample reads one cache line for both.
    cdf: Vec<[f32; 2]>,
    /// `∫₀¹ f = Σ fᵢ / n` (after the all-zero fallback).
    integral: f32,
    /// Guide table (`n + 1` entries) for [`Self::sample_continuous`]: `guide[g]` is a lower
    /// bound on the number of `cdf` entries `<= u` for every `u` in cell `g = ⌊u·n⌋`, and
    /// `guide[g + 1]` nearly an upper bound, so the search becomes a binary search over that range
    /// (a concentrated density, a sun, puts hundreds of entries in one cell) with the same
    /// result as one over all of `cdf`.
    guide: Vec<u32>,
}

impl Distribution1D {
    /// Tabulates the density proportional to `func`.
    pub fn new(func: &[f32]) -> Self {
        let mut f: Vec<f32> = func
            .iter()
            .map(|&v| if v.is_finite() && v > 0.0 { v } else { 0.0 })
            .collect();
        if f.is_empty() {
            f.push(1.0);
        }
        let n = f.len();
        let mut sum: f64 = f.iter().map(|&v| v as f64).sum();
        if !(sum > 0.0 && sum.is_finite()) {
            f.iter_mut().for_each(|v| *v = 1.0);
            sum = n as f64;
        }
        let mut cdf = Vec::with_capacity(n + 1);
        let mut acc = 0.0f64;
        cdf.push(0.0);
        for &v in &f {
            acc += v as f64;
            cdf.push((acc / sum) as f32);
        }
        cdf[n] = 1.0;
        let integral = (sum / n as f64) as f32;
        // Every f32 `u` with ⌊u·n⌋ = g (f32 product) is ≥ g/n·(1 − 2⁻²³); the threshold sits
        // safely below that, so `guide[g]` never exceeds the true count.
        // Entry n + 1 bounds the last cell from above. (The lower bound of cell g + 1 may
        // undercount cell g's largest `u` by entries within 1e-6 of (g + 1)/n: the scan after
        // the binary search adds those.)
        let guide = (0..=n)
            .map(|g| {
                let lo = g as f64 / n as f64 * (1.0 - 1e-6);
                cdf.partition_point(|&c| f64::from(c) <= lo) as u32
            })
            .collect();
        let cdf = cdf
            .iter()
            .enumerate()
            .map(|(i, &c)| [c, f.get(i).map_or(0.0, |&v| v / integral)])
            .collect();
        Distribution1D {
            func: f,
            cdf,
            integral,
            guide,
        }
    }

    /// Number of bins.
    pub fn len(&self) -> usize {
        self.func.len()
    }

    /// Always false (an empty input becomes one uniform bin).
    pub fn is_empty(&self) -> bool {
        false
    }

    /// `∫₀¹ f`.
    pub fn integral(&self) -> f32 {
        self.integral
    }

    /// The (sanitised) bin values.
    pub fn func(&self) -> &[f32] {
        &self.func
    }

    /// Maps `u ∈ [0,1)` to `(x ∈ [0,1), pdf(x), bin index)`. Bins of zero value are never
    /// returned.
    pub fn sample_continuous(&self, u: f32) -> (f32, f32, usize) {
        sample_tables(&self.cdf, &self.guide, u)
    }

    /// Density at `x` (0 outside `[0, 1]`).
    pub fn pdf(&self, x: f32) -> f32 {
        if !(0.0..=1.0).contains(&x) {
            return 0.0;
        }
        self.cdf[self.bin(x)][1]
    }

    /// Inverse of [`Self::sample_continuous`]: the `u` that maps to `x`.
    pub fn invert(&self, x: f32) -> f32 {
        if !x.is_finite() {
            return 0.0;
        }
        let x = x.clamp(0.0, 1.0);
        let n = self.func.len();
        let i = self.bin(x);
        let frac = (x * n as f32 - i as f32).clamp(0.0, 1.0);
        let (c0, c1) = (self.cdf[i][0], self.cdf[i + 1][0]);
        let u = c0 + frac * (c1 - c0);
        u.clamp(0.0, ONE_MINUS_EPSILON)
    }

    fn bin(&self, x: f32) -> usize {
        let n = self.func.len();
        ((x * n as f32) as usize).min(n - 1)
    }
}

/// [`Distribution1D::sample_continuous`] on its tables (`n + 1` entries each, `n ≥ 1`).
#[inline]
fn sample_tables(cdf: &[[f32; 2]], guide: &[u32], u: f32) -> (f32, f32, usize) {
    let n = cdf.len() - 1;
    let u = if u.is_finite() {
        u.clamp(0.0, ONE_MINUS_EPSILON)
    } else {
        0.0
    };
    // Largest i with cdf[i] <= u; cdf[n] = 1 > u so i <= n - 1. `count` is the number of
    // cdf entries <= u (cdf is non-decreasing), found by a binary search between the
    // guide's bounds and a scan up from there (in case the upper bound undercounts): the
    // same value as `cdf.partition_point(|&c| c <= u)`.
    let g = ((u * n as f32) as usize).min(n - 1);
    let lo = guide[g] as usize;
    let hi = (guide[g + 1] as usize).clamp(lo, cdf.len());
    let mut count = lo + cdf[lo..hi].partition_point(|c| c[0] <= u);
    while count < cdf.len() && cdf[count][0] <= u {
        count += 1;
    }
    debug_assert_eq!(count, cdf.partition_point(|c| c[0] <= u));
    let i = (count.max(1) - 1).min(n - 1);
    let [c, pdf] = cdf[i];
    let width = cdf[i + 1][0] - c;
    let du = if width > 0.0 {
        ((u - c) / width).clamp(0.0, ONE_MINUS_EPSILON)
    } else {
        0.0
    };
    let x = ((i as f32 + du) / n as f32).min(ONE_MINUS_EPSILON);
    (x, pdf, i)
}

/// A piecewise-constant density on `[0,1)²` over a `width × height` grid (row-major, row 0 at
/// `y ∈ [0, 1/height)`): a marginal over rows and one conditional per row.
#[derive(Clone, Debug)]
pub struct Distribution2D {
    conditional: Vec<Distribution1D>,
    marginal: Distribution1D,
    /// Every row's `cdf` table, row after row (`width + 1` entries each), and likewise the
    /// guide tables: sampling a row reads these directly, not through the row's own vectors
    /// (one dependent cache miss fewer).
    conditional_cdf: Vec<[f32; 2]>,
    conditional_guide: Vec<u32>,
}

impl Distribution2D {
    /// Tabulates the density proportional to `func` (`width × height` values, row-major).
    /// Errors if the size does not match or is zero.
    pub fn new(func: &[f32], width: usize, height: usize) -> Result<Self> {
        if width == 0 || height == 0 || width.checked_mul(height) != Some(func.len()) {
            return Err(BakeError::Invalid(format!(
                "Distribution2D: {} values for a {width} × {height} grid",
                func.len()
            )));
        }
        let conditional: Vec<Distribution1D> =
            func.chunks_exact(width).map(Distribution1D::new).collect();
        // Marginal from the raw row sums, so an all-zero row gets zero probability.
        let row_integrals: Vec<f32> = func
            .chunks_exact(width)
            .map(|row| {
                let s: f64 = row
                    .iter()
                    .map(|&v| {
                        if v.is_finite() && v > 0.0 {
                            v as f64
                        } else {
                            0.0
                        }
                    })
                    .sum();
                (s / width as f64) as f32
            })
            .collect();
        let marginal = Distribution1D::new(&row_integrals);
        Ok(Distribution2D {
            conditional_cdf: conditional
                .iter()
                .flat_map(|d| d.cdf.iter().copied())
                .collect(),
            conditional_guide: conditional
                .iter()
                .flat_map(|d| d.guide.iter().copied())
                .collect(),
            conditional,
            marginal,
        })
    }

    /// Grid width.
    /// The tables [`Distribution2D::sample_continuous`] and [`Distribution2D::pdf`] read,
    /// for another implementation of them (the GPU path tracer): the marginal's
    /// `height + 1` entries `[cdf, pdf]`, and the conditionals' `width + 1` entries per row,
    /// row after row. The sample with `u` is in row `i` = the last marginal entry whose cdf
    /// is ≤ `u.y` (at most `height − 1`), at `(i + (u.y − cdf_i) / (cdf_{i+1} − cdf_i)) /
    /// height`, and likewise along the row; the pdf of a bin is its entry's second value.
    pub fn tables(&self) -> (&[[f32; 2]], &[[f32; 2]]) {
        (&self.marginal.cdf, &self.conditional_cdf)
    }

    pub fn width(&self) -> usize {
        self.conditional[0].len()
    }

    /// Grid height.
    pub fn height(&self) -> usize {
        self.conditional.len()
    }

    /// Maps `u ∈ [0,1)²` to a point of `[0,1)²` and its density (`u.y` picks the row, `u.x`
    /// the column).
    pub fn sample_continuous(&self, u: Vec2) -> (Vec2, f32) {
        let (y, pdf_y, row) = self.marginal.sample_continuous(u.y);
        let stride = self.width() + 1;
        let rows = row * stride..(row + 1) * stride;
        let (x, pdf_x, _) = sample_tables(
            &self.conditional_cdf[rows.clone()],
            &self.conditional_guide[rows],
            u.x,
        );
        (Vec2::new(x, y), pdf_x * pdf_y)
    }

    /// Density at `p` (0 outside the unit square).
    pub fn pdf(&self, p: Vec2) -> f32 {
        if !(0.0..=1.0).contains(&p.x) || !(0.0..=1.0).contains(&p.y) {
            return 0.0;
        }
        let row = self.marginal.bin(p.y);
        // `self.conditional[row].pdf(p.x)` from the flat table.
        let width = self.width();
        let column = ((p.x * width as f32) as usize).min(width - 1);
        self.marginal.pdf(p.y) * self.conditional_cdf[row * (width + 1) + column][1]
    }

    /// Inverse of [`Self::sample_continuous`].
    pub fn invert(&self, p: Vec2) -> Vec2 {
        if !p.is_finite() {
            return Vec2::ZERO;
        }
        let y = p.y.clamp(0.0, 1.0);
        let row = self.marginal.bin(y);
        Vec2::new(self.conditional[row].invert(p.x), self.marginal.invert(y))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use oslf_shading::random::Rng;

    #[test]
    fn distribution1d_zero_bins_and_round_trip() {
        let d = Distribution1D::new(&[0.0, 1.0, 0.0, 3.0, f32::NAN, -2.0]);
        assert!((d.integral() - 4.0 / 6.0).abs() < 1e-6);
        let mut rng = Rng::new(1, 2);
        for _ in 0..1000 {
            let u = rng.next_f32();
            let (x, pdf, i) = d.sample_continuous(u);
            assert!(i == 1 || i == 3, "{i}");
            assert!(pdf > 0.0 && (pdf - d.pdf(x)).abs() < 1e-5);
            assert!((d.invert(x) - u).abs() < 1e-5);
        }
        let z = Distribution1D::new(&[0.0, 0.0]);
        assert_eq!(z.pdf(0.3), 1.0);
        let e = Distribution1D::new(&[]);
        assert_eq!(e.sample_continuous(0.5).0, 0.5);
    }

    #[test]
    fn distribution2d_rejects_bad_sizes() {
        assert!(Distribution2D::new(&[1.0; 5], 2, 2).is_err());
        assert!(Distribution2D::new(&[], 0, 0).is_err());
        assert!(Distribution2D::new(&[1.0; 6], 3, 2).is_ok());
    }
}
