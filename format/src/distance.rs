//! The distance plane: how a store holds the distance to the first hit per texel
//! (`docs/format.md`, "Distance plane").
//!
//! The *raw* face ends in `n²` little-endian `f32` distances (`f32::MAX` where the ray
//! escaped). The writer first rounds every distance to a *distance lattice* of `k` mantissa
//! bits (bfloat-like: the `f32` bit pattern with its low `23 − k` mantissa bits zero), `k`
//! chosen from the cube resolution so that the relative error stays below a quarter of a
//! texel's angular size ([`distance_bits`]); the face filters 1 to 3 then store each distance
//! as its `(8 + k)`-bit *code* (the pattern shifted right by `23 − k`) in two byte planes
//! instead of four, predicted from three neighbours. The no-hit value `f32::MAX` is kept
//! exactly (code `0xFF << k`, the pattern of +∞).

/// The value a distance plane holds where the ray escaped (hit nothing).
pub const NO_HIT: f32 = f32::MAX;

/// Largest distance-lattice mantissa bits (8 + 8 = 16-bit codes).
pub const MAX_DISTANCE_BITS: u32 = 8;

/// How a store's faces hold their distance plane.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum DistancePlane {
    /// No distance channel.
    Absent,
    /// Distances on the lattice of `bits` mantissa bits (or [`NO_HIT`]), filtered as two byte
    /// planes of their codes (`bits` from [`distance_bits`]).
    Lattice { bits: u32 },
}

impl DistancePlane {
    /// The plane of a store with cube faces of side `resolution`, with or without a distance
    /// channel.
    pub fn for_store(resolution: u32, distance_channel: bool) -> Self {
        if distance_channel {
            DistancePlane::Lattice {
                bits: distance_bits(resolution),
            }
        } else {
            DistancePlane::Absent
        }
    }

    /// Whether the faces have a distance plane.
    pub fn is_present(self) -> bool {
        self != DistancePlane::Absent
    }

    /// Bytes per texel of the plane after face filter 1, 2 or 3: 0, or 2 for the lattice.
    pub fn filtered_bytes_per_texel(self) -> usize {
        match self {
            DistancePlane::Absent => 0,
            DistancePlane::Lattice { .. } => 2,
        }
    }

    /// Rounds `d` (finite and non-negative, or [`NO_HIT`]) to the plane's lattice; the identity
    /// without a plane.
    pub fn quantize(self, d: f32) -> f32 {
        match self {
            DistancePlane::Lattice { bits } => quantize_distance(d, bits),
            _ => d,
        }
    }
}

impl std::fmt::Display for DistancePlane {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            DistancePlane::Absent => f.write_str("none"),
            DistancePlane::Lattice { bits } => write!(f, "{bits}-bit lattice"),
        }
    }
}

/// The distance-lattice mantissa bits of a store with cube faces of side
/// `resolution`: `clamp(⌈log2 n⌉, 1, 8)` (n = 32 → 5, 64 → 6, 128 → 7, 256 and above → 8),
/// the fewest with `2^−(k+1) ≤ 1 / (2n)`. A texel at the face centre subtends `α ≈ 2 / n`
/// radians, so the rounding changes a distance `d` by at most `d · α / 4`; a lookup from a
/// point at distance `b` from the sample point moves by at most `(b / d) · α / 4`, a quarter
/// of a texel where `b ≤ d`: below what a lookup at texel resolution resolves, and below the
/// spread of the distances within one texel (a surface seen at incidence θ spans a relative
/// `α · tan θ` of distance across a texel). Capped at 8 (16-bit codes): beyond n = 256 the
/// bound is `2^−9`.
pub fn distance_bits(resolution: u32) -> u32 {
    let log2 = u32::BITS - resolution.max(1).saturating_sub(1).leading_zeros(); // ⌈log2 n⌉
    log2.clamp(1, MAX_DISTANCE_BITS)
}

/// `d` rounded to the lattice of `bits` (1..=8) mantissa bits: its `f32` pattern rounded to
/// the nearest multiple of `2^(23 − bits)`, ties to even. [`NO_HIT`] stays itself; a finite
/// value that would round up to the pattern of +∞ takes the largest finite lattice value
/// (relative error still below `2^−bits`). Zero stays zero. For a normal `d` the relative
/// error is at most `2^−(bits+1)`.
pub fn quantize_distance(d: f32, bits: u32) -> f32 {
    if d == NO_HIT || !(d.is_finite() && d >= 0.0) {
        return d;
    }
    let shift = 23 - bits.clamp(1, MAX_DISTANCE_BITS);
    // −0.0 is the distance 0: its sign bit would otherwise read as the largest pattern.
    let b = if d == 0.0 { 0 } else { d.to_bits() };
    let r = ((b + (1 << (shift - 1)) - 1 + ((b >> shift) & 1)) >> shift) << shift;
    let inf = f32::INFINITY.to_bits();
    f32::from_bits(if r >= inf { inf - (1 << shift) } else { r })
}

/// The code of an `f32` distance pattern `pattern` on the lattice of `bits`: `pattern >>
/// (23 − bits)`, [`no_hit_code`] for [`NO_HIT`]; `None` for a pattern off the lattice
/// (low bits set), negative, infinite or NaN.
pub(crate) fn distance_code(pattern: u32, bits: u32) -> Option<u32> {
    let shift = 23 - bits;
    if pattern == NO_HIT.to_bits() {
        return Some(no_hit_code(bits));
    }
    let on_lattice = pattern & ((1 << shift) - 1) == 0;
    (on_lattice && pattern < f32::INFINITY.to_bits()).then_some(pattern >> shift)
}

/// The `f32` pattern of code `code` on the lattice of `bits`: bits above `8 + bits` ignored,
/// [`no_hit_code`] and above (never written) read as [`NO_HIT`], so every code decodes to a
/// finite, non-negative distance.
pub(crate) fn code_pattern(code: u32, bits: u32) -> u32 {
    let code = code & ((1 << (8 + bits)) - 1);
    if code >= no_hit_code(bits) {
        NO_HIT.to_bits()
    } else {
        code << (23 - bits)
    }
}

/// The code of [`NO_HIT`] on the lattice of `bits`: `0xFF << bits`, the pattern of +∞.
pub(crate) fn no_hit_code(bits: u32) -> u32 {
    0xFF << bits
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bits_follow_the_resolution() {
        let got: Vec<u32> = [1, 2, 3, 4, 16, 32, 33, 64, 128, 256, 16384]
            .iter()
            .map(|&n| distance_bits(n))
            .collect();
        assert_eq!(got, [1, 1, 2, 2, 4, 5, 6, 6, 7, 8, 8]);
        for n in 1..=256u32 {
            let k = distance_bits(n);
            // The bound holds, and one bit fewer would break it.
            assert!(0.5f64.powi(k as i32 + 1) <= 1.0 / (2.0 * n as f64), "n {n}");
            assert!(
                k == 1 || 0.5f64.powi(k as i32) > 1.0 / (2.0 * n as f64),
                "n {n}"
            );
        }
    }

    #[test]
    fn quantization_is_bounded_and_codes_round_trip() {
        for bits in 1..=MAX_DISTANCE_BITS {
            let bound = 0.5f64.powi(bits as i32 + 1);
            let mut d = 1e-30f32;
            while d < 1e30 {
                let q = quantize_distance(d, bits);
                let rel = ((q as f64 - d as f64) / d as f64).abs();
                assert!(rel <= bound, "bits {bits}: {d} → {q} ({rel})");
                // On the lattice: its own quantization, and its code decodes to it.
                assert_eq!(quantize_distance(q, bits), q);
                let code = distance_code(q.to_bits(), bits).unwrap();
                assert!(code < no_hit_code(bits));
                assert_eq!(code_pattern(code, bits), q.to_bits());
                d *= 1.37;
            }
            // The extremes: zero, the smallest subnormal, the largest finite, no hit.
            assert_eq!(quantize_distance(0.0, bits), 0.0);
            let tiny = f32::from_bits(1);
            assert!(quantize_distance(tiny, bits) <= tiny);
            let big = quantize_distance(3.4e38, bits);
            assert!(big.is_finite() && big < NO_HIT);
            assert!(((big as f64 - 3.4e38) / 3.4e38).abs() < 0.5f64.powi(bits as i32));
            assert_eq!(quantize_distance(NO_HIT, bits), NO_HIT);
            assert_eq!(
                distance_code(NO_HIT.to_bits(), bits),
                Some(no_hit_code(bits))
            );
            assert_eq!(code_pattern(no_hit_code(bits), bits), NO_HIT.to_bits());
            // Off the lattice, infinite, NaN or negative: no code. Codes never written read
            // as finite, non-negative distances.
            for bad in [f32::INFINITY, f32::NAN, -1.0] {
                assert_eq!(distance_code(bad.to_bits(), bits), None, "{bad}");
            }
            assert_eq!(distance_code(1.0f32.to_bits() | 1, bits), None);
            for code in [no_hit_code(bits) + 1, 0xFFFF, u32::MAX] {
                let d = f32::from_bits(code_pattern(code, bits));
                assert!(d.is_finite() && d >= 0.0, "{code:#x}");
            }
        }
    }

    #[test]
    fn negative_zero_is_the_distance_zero() {
        for bits in 1..=MAX_DISTANCE_BITS {
            let q = quantize_distance(-0.0, bits);
            assert_eq!(q.to_bits(), 0, "{bits}");
            assert_eq!(distance_code(q.to_bits(), bits), Some(0));
        }
    }

    #[test]
    fn planes_of_a_store() {
        assert_eq!(
            DistancePlane::for_store(32, true),
            DistancePlane::Lattice { bits: 5 }
        );
        assert_eq!(
            DistancePlane::for_store(256, true),
            DistancePlane::Lattice { bits: 8 }
        );
        assert_eq!(DistancePlane::for_store(32, false), DistancePlane::Absent);
        assert_eq!(DistancePlane::Absent.quantize(1.2345), 1.2345);
    }
}
