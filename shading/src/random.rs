//! Random numbers: the PCG32 generator, the stream hash that derives one stream per pixel,
//! texel or path, and stratified samples. Twin: `random.wgsl` (the GPU bake's streams, bit for
//! bit, with 64-bit integers as `vec2<u32>`).
//!
//! Determinism: [`Rng`]'s output depends only on its seed and stream. Callers derive one stream
//! per (pixel, texel, ...) with [`hash_u64`], so results never depend on thread count or
//! scheduling.

use glam::Vec2;

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
}
