//! Random numbers, sample warps and tabulated distributions.
//!
//! Every warp comes as a triplet in the pbrt-v4 / Mitsuba style:
//! `sample_x(u) -> value`, `x_pdf(value) -> density` and `invert_x(value) -> u`, with
//! `invert_x(sample_x(u)) == u` up to rounding wherever the warp is one-to-one. Densities are
//! with respect to solid angle for directions and to area of the unit square for points in
//! `[0,1)²`. No function here returns NaN or infinity for any finite input; a direction outside
//! the support has density 0.
//!
//! Determinism: [`Rng`] is a PCG32 generator whose output depends only on its seed and stream.
//! Callers derive one stream per (pixel, texel, ...) with [`hash_u64`], so results never depend
//! on thread count or scheduling.

use std::f32::consts::{FRAC_1_PI, FRAC_PI_2, FRAC_PI_4, PI};

use glam::{Vec2, Vec3};

use crate::{BakeError, Result};

/// The largest `f32` below 1, the upper end of every `[0, 1)` sample.
pub const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

const PCG_MULT: u64 = 6_364_136_223_846_793_005;

/// PCG32 (O'Neill 2014, "PCG: a family of simple fast space-efficient statistically good
/// algorithms for random number generation"): 64-bit LCG state, XSH-RR output.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Rng {
    state: u64,
    inc: u64,
}

impl Rng {
    /// A generator seeded with `seed` on stream `stream` (2⁶³ independent streams).
    pub fn new(seed: u64, stream: u64) -> Self {
        let mut rng = Rng {
            state: 0,
            inc: (stream << 1) | 1,
        };
        rng.next_u32();
        rng.state = rng.state.wrapping_add(seed);
        rng.next_u32();
        rng
    }

    /// The next uniformly distributed 32-bit value.
    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old.wrapping_mul(PCG_MULT).wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// A uniform `f32` in `[0, 1)` (24 random bits, so never exactly 1).
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / 16_777_216.0)
    }

    /// Two uniform values in `[0, 1)²` (x drawn first).
    pub fn next_vec2(&mut self) -> Vec2 {
        let x = self.next_f32();
        let y = self.next_f32();
        Vec2::new(x, y)
    }
}

/// SplitMix64 finaliser (Steele et al. 2014): a bijective 64-bit mixer.
fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// Hashes a list of integers (seed, pixel x, pixel y, ...) into one well-mixed 64-bit value,
/// used to derive [`Rng`] streams and seeds. Order matters: `[a, b] != [b, a]` in general.
pub fn hash_u64(values: &[u64]) -> u64 {
    let mut h = mix64(0x9e37_79b9_7f4a_7c15 ^ values.len() as u64);
    for &v in values {
        h = mix64(h ^ mix64(v.wrapping_add(0x9e37_79b9_7f4a_7c15)));
    }
    h
}

/// A jittered sample in stratum `i` of `n` strata of the unit square.
///
/// For `n = k²` the strata are the `k × k` grid cells, visited row by row (`i % k` is the
/// column). For other `n` a `kx × ky` grid with `kx = ⌈√n⌉`, `ky = ⌈n / kx⌉` is used and only
/// its first `n` cells are visited. `i` is taken modulo `n`; `n = 0` is treated as 1. Two
/// values are drawn from `rng` (x first).
pub fn stratified_2d(i: u32, n: u32, rng: &mut Rng) -> Vec2 {
    let n = n.max(1);
    let i = i % n;
    let mut kx = (n as f64).sqrt() as u32;
    while kx * kx < n {
        kx += 1;
    }
    while kx > 1 && (kx - 1) * (kx - 1) >= n {
        kx -= 1;
    }
    let ky = n.div_ceil(kx);
    let j = rng.next_vec2();
    let x = ((i % kx) as f32 + j.x) / kx as f32;
    let y = ((i / kx) as f32 + j.y) / ky as f32;
    Vec2::new(x.min(ONE_MINUS_EPSILON), y.min(ONE_MINUS_EPSILON))
}

/// `atan2(y, x)` mapped to `[0, 1)` (0 on the +x axis, increasing counter-clockwise).
fn azimuth_fraction(y: f32, x: f32) -> f32 {
    let mut f = y.atan2(x) * (0.5 * FRAC_1_PI);
    if f < 0.0 {
        f += 1.0;
    }
    if f.is_finite() {
        f.clamp(0.0, ONE_MINUS_EPSILON)
    } else {
        0.0
    }
}

/// Shirley–Chiu concentric map from `[0,1)²` to the unit disc.
pub fn sample_uniform_disk_concentric(u: Vec2) -> Vec2 {
    let o = 2.0 * u - Vec2::ONE;
    if o.x == 0.0 && o.y == 0.0 {
        return Vec2::ZERO;
    }
    let (r, theta) = if o.x.abs() > o.y.abs() {
        (o.x, FRAC_PI_4 * (o.y / o.x))
    } else {
        (o.y, FRAC_PI_2 - FRAC_PI_4 * (o.x / o.y))
    };
    r * Vec2::new(theta.cos(), theta.sin())
}

/// Density of [`sample_uniform_disk_concentric`] with respect to area: `1/π` inside the disc.
pub fn uniform_disk_concentric_pdf(p: Vec2) -> f32 {
    if p.length_squared() <= 1.0 {
        FRAC_1_PI
    } else {
        0.0
    }
}

/// Inverse of [`sample_uniform_disk_concentric`] (pbrt-v4 `InvertUniformDiskConcentricSample`).
pub fn invert_uniform_disk_concentric(p: Vec2) -> Vec2 {
    let theta = p.y.atan2(p.x); // (-π, π]
    let r = p.length();
    let (ox, oy);
    if theta.abs() < FRAC_PI_4 || theta.abs() > 3.0 * FRAC_PI_4 {
        let r = r.copysign(p.x);
        ox = r;
        oy = if p.x < 0.0 {
            if p.y < 0.0 {
                (PI + theta) * r / FRAC_PI_4
            } else {
                (theta - PI) * r / FRAC_PI_4
            }
        } else {
            theta * r / FRAC_PI_4
        };
    } else {
        let r = r.copysign(p.y);
        oy = r;
        ox = if p.y < 0.0 {
            -(FRAC_PI_2 + theta) * r / FRAC_PI_4
        } else {
            (FRAC_PI_2 - theta) * r / FRAC_PI_4
        };
    }
    let u = Vec2::new((ox + 1.0) * 0.5, (oy + 1.0) * 0.5);
    if u.is_finite() {
        u.clamp(Vec2::ZERO, Vec2::splat(ONE_MINUS_EPSILON))
    } else {
        Vec2::ZERO
    }
}

/// Cosine-weighted direction on the hemisphere around +z (Malley's method on the concentric
/// disc). Returns a unit vector in the local frame.
pub fn sample_cosine_hemisphere(u: Vec2) -> Vec3 {
    let d = sample_uniform_disk_concentric(u);
    let z = (1.0 - d.length_squared()).max(0.0).sqrt();
    Vec3::new(d.x, d.y, z)
}

/// Density of [`sample_cosine_hemisphere`] with respect to solid angle, given `cos θ` (the local
/// z component): `cos θ / π`, and 0 below the horizon.
pub fn cosine_hemisphere_pdf(cos_theta: f32) -> f32 {
    if cos_theta > 0.0 {
        cos_theta * FRAC_1_PI
    } else {
        0.0
    }
}

/// Inverse of [`sample_cosine_hemisphere`]: the `u` that maps to local direction `w`.
pub fn invert_cosine_hemisphere(w: Vec3) -> Vec2 {
    invert_uniform_disk_concentric(Vec2::new(w.x, w.y))
}

/// Uniform direction on the unit sphere: `z = 1 − 2u₀`, `φ = 2πu₁`.
pub fn sample_uniform_sphere(u: Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Density of [`sample_uniform_sphere`]: `1 / 4π` everywhere.
pub fn uniform_sphere_pdf() -> f32 {
    0.25 * FRAC_1_PI
}

/// Inverse of [`sample_uniform_sphere`].
pub fn invert_uniform_sphere(w: Vec3) -> Vec2 {
    let ux = ((1.0 - w.z) * 0.5).clamp(0.0, ONE_MINUS_EPSILON);
    let ux = if ux.is_finite() { ux } else { 0.0 };
    Vec2::new(ux, azimuth_fraction(w.y, w.x))
}

/// An orthonormal frame `(x, y, z)` with `z` a given unit normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    pub x: Vec3,
    pub y: Vec3,
    pub z: Vec3,
}

impl Frame {
    /// A right-handed frame around `n` (Duff et al. 2017, "Building an orthonormal basis,
    /// revisited", branchless and continuous except across `n.z = 0`). `n` is normalised first;
    /// a zero or non-finite `n` gives the world frame.
    pub fn from_normal(n: Vec3) -> Self {
        let n = n.try_normalize().unwrap_or(Vec3::Z);
        let sign = 1.0f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let x = Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let y = Vec3::new(b, sign + n.y * n.y * a, -n.y);
        Frame { x, y, z: n }
    }

    /// Local coordinates (z along the normal) to world.
    pub fn to_world(&self, v: Vec3) -> Vec3 {
        self.x * v.x + self.y * v.y + self.z * v.z
    }

    /// World coordinates to local.
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.x), v.dot(self.y), v.dot(self.z))
    }
}

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

    #[test]
    fn rng_is_deterministic_and_streams_differ() {
        let mut a = Rng::new(42, 7);
        let mut b = Rng::new(42, 7);
        let mut c = Rng::new(42, 8);
        let va: Vec<u32> = (0..16).map(|_| a.next_u32()).collect();
        let vb: Vec<u32> = (0..16).map(|_| b.next_u32()).collect();
        let vc: Vec<u32> = (0..16).map(|_| c.next_u32()).collect();
        assert_eq!(va, vb);
        assert_ne!(va, vc);
        let mut r = Rng::new(1, 1);
        let mean: f64 = (0..100_000).map(|_| r.next_f32() as f64).sum::<f64>() / 1e5;
        assert!((mean - 0.5).abs() < 0.005, "{mean}");
    }

    #[test]
    fn pcg32_reference_output() {
        // pcg32_srandom(42, 54) from the PCG reference implementation (pcg32-demo).
        let mut r = Rng::new(42, 54);
        let expected = [
            0xa15c02b7u32,
            0x7b47f409,
            0xba1d3330,
            0x83d2f293,
            0xbfa4784b,
            0xcbed606e,
        ];
        for e in expected {
            assert_eq!(r.next_u32(), e);
        }
    }

    #[test]
    fn hash_depends_on_order() {
        assert_ne!(hash_u64(&[1, 2]), hash_u64(&[2, 1]));
        assert_ne!(hash_u64(&[0]), hash_u64(&[0, 0]));
        assert_eq!(hash_u64(&[3, 4, 5]), hash_u64(&[3, 4, 5]));
    }

    #[test]
    fn stratified_covers_every_stratum() {
        let mut rng = Rng::new(3, 0);
        for n in [1u32, 4, 9, 16, 5, 7] {
            let mut cells = std::collections::HashSet::new();
            let kx = (n as f32).sqrt().ceil() as u32;
            let ky = n.div_ceil(kx);
            for i in 0..n {
                let p = stratified_2d(i, n, &mut rng);
                assert!((0.0..1.0).contains(&p.x) && (0.0..1.0).contains(&p.y));
                cells.insert(((p.x * kx as f32) as u32, (p.y * ky as f32) as u32));
            }
            assert_eq!(cells.len(), n as usize, "n = {n}");
        }
        // n = 0 does not panic.
        let _ = stratified_2d(3, 0, &mut rng);
    }

    #[test]
    fn frame_is_orthonormal() {
        let mut rng = Rng::new(9, 9);
        for _ in 0..1000 {
            let n = sample_uniform_sphere(rng.next_vec2());
            let f = Frame::from_normal(n);
            assert!((f.x.length() - 1.0).abs() < 1e-5);
            assert!((f.y.length() - 1.0).abs() < 1e-5);
            assert!(f.x.dot(f.y).abs() < 1e-5 && f.x.dot(f.z).abs() < 1e-5);
            assert!((f.x.cross(f.y) - f.z).length() < 1e-5);
            let v = sample_uniform_sphere(rng.next_vec2());
            assert!((f.to_world(f.to_local(v)) - v).length() < 1e-5);
        }
        for n in [Vec3::Z, -Vec3::Z, Vec3::ZERO, Vec3::NAN] {
            let f = Frame::from_normal(n);
            assert!(f.x.is_finite() && f.y.is_finite() && f.z.is_finite());
        }
    }

    #[test]
    fn disk_round_trip() {
        let mut rng = Rng::new(5, 5);
        for _ in 0..10_000 {
            let u = rng.next_vec2();
            let p = sample_uniform_disk_concentric(u);
            assert!(p.length() <= 1.0 + 1e-6);
            let back = invert_uniform_disk_concentric(p);
            assert!((back - u).abs().max_element() < 1e-4, "{u} {back}");
        }
    }

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
