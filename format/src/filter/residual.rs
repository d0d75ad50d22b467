//! What the filters share: a texel's prediction neighbours, the zig-zag codes of residuals
//! and the fields of an RGB9E5 texel.

/// The two prediction neighbours of texel `(x, y)` (row-major index `i`): `(a, b)` =
/// (left, above); in row 0 both are the left texel, in column 0 both are the texel above.
/// `None` for texel (0, 0).
#[inline(always)]
pub(super) fn neighbours(n: usize, x: usize, y: usize, i: usize) -> Option<(usize, usize)> {
    match (x > 0, y > 0) {
        (true, true) => Some((i - 1, i - n)),
        (true, false) => Some((i - 1, i - 1)),
        (false, true) => Some((i - n, i - n)),
        (false, false) => None,
    }
}

#[inline(always)]
pub(super) fn zigzag9(r: u32) -> u32 {
    let r = r & 511;
    if r < 256 {
        r << 1
    } else {
        ((512 - r) << 1) - 1
    }
}

#[inline(always)]
pub(super) fn unzigzag9(z: u32) -> u32 {
    ((z & 511) >> 1 ^ (z & 1).wrapping_neg()) & 511
}

#[inline(always)]
pub(super) fn fields(v: u32) -> (u32, [u32; 3]) {
    (v >> 27, [v & 511, (v >> 9) & 511, (v >> 18) & 511])
}

#[inline(always)]
pub(super) fn mask<const W: usize>() -> u64 {
    if W >= 8 {
        u64::MAX
    } else {
        (1u64 << (8 * W)) - 1
    }
}

/// Zig-zag of a W-byte residual `r` (read as a signed W-byte integer `s`): `2s` for
/// `s >= 0`, `-2s - 1` otherwise.
#[inline(always)]
pub(super) fn zigzag<const W: usize>(r: u64) -> u64 {
    let bits = 8 * W as u32;
    let s = ((r << (64 - bits)) as i64) >> (64 - bits);
    (((s << 1) ^ (s >> 63)) as u64) & mask::<W>()
}

#[inline(always)]
pub(super) fn unzigzag<const W: usize>(z: u64) -> u64 {
    ((z >> 1) ^ (z & 1).wrapping_neg()) & mask::<W>()
}

#[inline(always)]
pub(super) fn get_w<const W: usize>(b: &[u8], i: usize) -> u64 {
    let mut v = 0u64;
    for k in 0..W {
        v |= u64::from(b.get(i * W + k).copied().unwrap_or(0)) << (8 * k);
    }
    v
}
