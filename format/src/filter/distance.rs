//! Filters 1 to 3 on a distance plane quantized to the distance lattice (`docs/format.md`,
//! "Face filters"): each distance's lattice code predicted from its
//! left, upper and upper-left neighbours by the median edge detector, the zig-zagged 16-bit
//! residuals in two byte planes.

use crate::distance::{code_pattern, distance_code};
use crate::filter::residual::{get_w, unzigzag, zigzag};
use crate::Error;

/// The prediction of the code at `(x, y)` from the codes `c` decoded so far (row-major, side
/// `n`): 0 at (0, 0), the left code in row 0, the upper in column 0, elsewhere the median
/// edge detector of left `a`, upper `b` and upper-left `d`: `min(a, b)` if `d ≥ max(a, b)`,
/// `max(a, b)` if `d ≤ min(a, b)`, else `a + b − d`.
#[inline(always)]
fn predict(c: &[u32], n: usize, x: usize, y: usize) -> u32 {
    let i = y * n + x;
    match (x > 0, y > 0) {
        (false, false) => 0,
        (true, false) => c[i - 1],
        (false, true) => c[i - n],
        (true, true) => {
            let (a, b, d) = (c[i - 1], c[i - n], c[i - n - 1]);
            if d >= a.max(b) {
                a.min(b)
            } else if d <= a.min(b) {
                a.max(b)
            } else {
                a + b - d
            }
        }
    }
}

/// Filters the `t = n²` distances of `raw` (`f32` patterns, each on the lattice of `bits` or
/// [`crate::distance::NO_HIT`]) into two planes of `t` bytes in `out`: plane `j` byte `i` =
/// byte `j` of `zigzag((code − prediction) mod 2¹⁶)`. A distance off the lattice is an
/// [`Error::UnquantizedDistance`] naming its texel.
pub(super) fn lattice_forward(
    n: usize,
    t: usize,
    bits: u32,
    raw: &[u8],
    out: &mut [u8],
) -> Result<(), Error> {
    let mut codes = vec![0u32; t];
    for (i, code) in codes.iter_mut().enumerate() {
        let pattern = get_w::<4>(raw, i) as u32;
        *code = distance_code(pattern, bits).ok_or(Error::UnquantizedDistance {
            texel: i,
            value: f32::from_bits(pattern),
            bits,
        })?;
    }
    for y in 0..n {
        for x in 0..n {
            let i = y * n + x;
            let p = predict(&codes, n, x, y);
            let z = zigzag::<2>(u64::from(codes[i].wrapping_sub(p)));
            out[i] = z as u8;
            out[t + i] = (z >> 8) as u8;
        }
    }
    Ok(())
}

/// Undoes [`lattice_forward`]: two planes of `t` bytes in `filtered` into `t` `f32` patterns
/// in `out`. Never fails on content: codes are taken mod 2¹⁶ and decoded as
/// [`code_pattern`] says (so always to a finite, non-negative distance).
pub(super) fn lattice_inverse(n: usize, t: usize, bits: u32, filtered: &[u8], out: &mut [u8]) {
    let mut codes = vec![0u32; t];
    for y in 0..n {
        for x in 0..n {
            let i = y * n + x;
            let z = u64::from(filtered[i]) | u64::from(filtered[t + i]) << 8;
            let p = predict(&codes, n, x, y);
            let code = (u64::from(p).wrapping_add(unzigzag::<2>(z)) & 0xFFFF) as u32;
            codes[i] = code;
            out[4 * i..4 * i + 4].copy_from_slice(&code_pattern(code, bits).to_le_bytes());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::distance::{quantize_distance, NO_HIT};
    use crate::filter::{filter_face, filtered_face_size, unfilter_face, Filter};
    use crate::{DistancePlane, Encoding};

    #[test]
    fn lattice_planes_round_trip_and_others_are_refused() {
        let mut s = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            s
        };
        for res in [1u32, 2, 3, 7, 16] {
            for bits in [1, 4, 8] {
                let plane = DistancePlane::Lattice { bits };
                let t = (res * res) as usize;
                let enc = Encoding::Rgba16f;
                let texel_bytes = enc.face_bytes(res).unwrap();
                let d: Vec<f32> = (0..t)
                    .map(|i| match next() % 5 {
                        0 => NO_HIT,
                        1 => 0.0,
                        2 => f32::from_bits(next() as u32 & 0x7f7f_ffff),
                        _ => 1.0 + (i as f32 * 0.37).sin() * 0.5,
                    })
                    .collect();
                let mut raw = vec![0u8; texel_bytes];
                raw.extend(
                    d.iter()
                        .flat_map(|v| quantize_distance(*v, bits).to_le_bytes()),
                );
                for f in [Filter::Predict, Filter::PredictRows, Filter::PredictPacked] {
                    let size = filtered_face_size(f, enc, res, plane, 9).unwrap();
                    assert_eq!(size, texel_bytes + 2 * t);
                    let mut filtered = vec![0u8; size];
                    filter_face(f, enc, res, plane, &raw, &mut filtered).unwrap();
                    let mut back = vec![0u8; raw.len()];
                    unfilter_face(f, enc, res, plane, &filtered, &mut back).unwrap();
                    assert_eq!(back, raw, "res {res} bits {bits} {f}");
                    // Any filtered bytes decode, to finite non-negative distances.
                    let junk: Vec<u8> = (0..size).map(|_| next() as u8).collect();
                    unfilter_face(f, enc, res, plane, &junk, &mut back).unwrap();
                    for v in back[texel_bytes..].chunks_exact(4) {
                        let v = f32::from_le_bytes(v.try_into().unwrap());
                        assert!(v.is_finite() && v >= 0.0, "{v}");
                    }
                }
                // A distance off the lattice is refused, naming its texel.
                if bits < 8 {
                    let mut off = raw.clone();
                    let at = texel_bytes + 4 * (t - 1);
                    off[at..at + 4].copy_from_slice(&(1.0f32 + f32::EPSILON).to_le_bytes());
                    let mut filtered = vec![0u8; texel_bytes + 2 * t];
                    let e = filter_face(Filter::PredictRows, enc, res, plane, &off, &mut filtered);
                    assert!(
                        matches!(e, Err(Error::UnquantizedDistance { texel, bits: b, .. }) if texel == t - 1 && b == bits),
                        "{e:?}"
                    );
                }
            }
        }
    }
}
