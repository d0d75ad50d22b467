//! Filters 1 to 3 on RGBA16F and RGBA32F texels (W-byte unsigned channel patterns) and on
//! the distance plane (u32 patterns of the f32 distances): predicted from the left and upper
//! neighbours, zig-zagged residuals in byte planes.

use crate::filter::residual::{get_w, mask, neighbours, unzigzag, zigzag};

/// Channel order of the planes: G, R, B, A (channel indices into the texel).
pub(super) const PLANE_CHANNELS: [usize; 4] = [1, 0, 2, 3];

/// Predictions `[R, G, B, A]` of a texel with green `g` from its neighbours' patterns.
#[inline(always)]
pub(super) fn ints_predict<const W: usize>(nb: Option<([u64; 4], [u64; 4])>, g: u64) -> [u64; 4] {
    let m = mask::<W>();
    match nb {
        None => [g, 0, g, 0],
        Some((a, b)) => {
            let chroma = |c: usize| {
                let da = a[c] as i64 - a[1] as i64;
                let db = b[c] as i64 - b[1] as i64;
                (g as i64).wrapping_add((da + db) >> 1) as u64 & m
            };
            [chroma(0), a[1], chroma(2), a[3]]
        }
    }
}

#[inline(always)]
pub(super) fn texel_w<const W: usize>(b: &[u8], i: usize) -> [u64; 4] {
    std::array::from_fn(|c| get_w::<W>(b, 4 * i + c))
}

pub(super) fn ints_forward<const W: usize>(n: usize, t: usize, raw: &[u8], out: &mut [u8]) {
    let mut i = 0;
    for y in 0..n {
        for x in 0..n {
            let v = texel_w::<W>(raw, i);
            let nb =
                neighbours(n, x, y, i).map(|(a, b)| (texel_w::<W>(raw, a), texel_w::<W>(raw, b)));
            let p = ints_predict::<W>(nb, v[1]);
            for (k, c) in PLANE_CHANNELS.iter().enumerate() {
                let z = zigzag::<W>(v[*c].wrapping_sub(p[*c]));
                for j in 0..W {
                    if let Some(o) = out.get_mut((k * W + j) * t + i) {
                        *o = (z >> (8 * j)) as u8;
                    }
                }
            }
            i += 1;
        }
    }
}

pub(super) fn ints_inverse<const W: usize>(n: usize, t: usize, filtered: &[u8], out: &mut [u8]) {
    let m = mask::<W>();
    let mut i = 0;
    let plane = |k: usize, i: usize| {
        let mut z = 0u64;
        for j in 0..W {
            z |= u64::from(filtered.get((k * W + j) * t + i).copied().unwrap_or(0)) << (8 * j);
        }
        unzigzag::<W>(z)
    };
    for y in 0..n {
        for x in 0..n {
            let nb =
                neighbours(n, x, y, i).map(|(a, b)| (texel_w::<W>(out, a), texel_w::<W>(out, b)));
            let g = ints_predict::<W>(nb, 0)[1].wrapping_add(plane(0, i)) & m;
            let p = ints_predict::<W>(nb, g);
            let v = [
                p[0].wrapping_add(plane(1, i)) & m,
                g,
                p[2].wrapping_add(plane(2, i)) & m,
                p[3].wrapping_add(plane(3, i)) & m,
            ];
            for (c, val) in v.iter().enumerate() {
                let at = (4 * i + c) * W;
                if let Some(o) = out.get_mut(at..at + W) {
                    o.copy_from_slice(&val.to_le_bytes()[..W]);
                }
            }
            i += 1;
        }
    }
}
