//! Filter 1 (predict) on RGB9E5 texels: each predicted from its left and upper neighbours,
//! residuals in four byte planes.

use crate::filter::residual::{fields, neighbours, unzigzag9, zigzag9};

/// `RECIP[s] = floor(2^20 / s)` for `s` in `1..=1022` (`RECIP[0] = 0`, unused).
pub(super) static RECIP: [u32; 1023] = {
    let mut t = [0u32; 1023];
    let mut s = 1;
    while s < 1023 {
        t[s] = (1 << 20) / s as u32;
        s += 1;
    }
    t
};

/// A 9-bit mantissa `m` of a texel with exponent `from`, rescaled to exponent `to`.
#[inline(always)]
pub(super) fn rescale(m: u32, from: u32, to: u32) -> u32 {
    // Branch-free: with `from >= to`, `k = 0` and this is `min(511, m << d)`; otherwise
    // `d = 0` and it is `(m + 2^(k-1)) >> k` (m <= 511).
    let d = from.saturating_sub(to).min(9);
    let k = to.saturating_sub(from).min(31);
    (((m & 511) << d).min(511) + ((1u32 << k) >> 1)) >> k
}

/// The neighbour data texel `i`'s predictions need: their exponents and mantissas.
pub(super) type Nb = Option<((u32, [u32; 3]), (u32, [u32; 3]))>;

#[inline(always)]
pub(super) fn rgb9e5_neighbours(tex: &[u32], nb: Option<(usize, usize)>) -> Nb {
    let (a, b) = nb?;
    Some((
        fields(tex.get(a).copied().unwrap_or(0)),
        fields(tex.get(b).copied().unwrap_or(0)),
    ))
}

/// Green prediction of a texel with exponent `e`.
#[inline(always)]
pub(super) fn predict_g(nb: &Nb, e: u32) -> u32 {
    match nb {
        None => 0,
        Some(((ea, ma), (eb, mb))) => (rescale(ma[1], *ea, e) + rescale(mb[1], *eb, e)) >> 1,
    }
}

/// Prediction of channel `c` (0 red, 2 blue) of a texel with exponent `e` and green `g`.
#[inline(always)]
pub(super) fn predict_rb(nb: &Nb, e: u32, g: u32, c: usize) -> u32 {
    match nb {
        None => 0,
        Some(((ea, ma), (eb, mb))) => {
            let gs = ma[1] + mb[1];
            if gs == 0 {
                (rescale(ma[c], *ea, e) + rescale(mb[c], *eb, e)) >> 1
            } else {
                let cs = u64::from(ma[c] + mb[c]);
                let r = u64::from(RECIP[gs as usize]);
                let p = (u64::from(g) * cs * r + (1 << 19)) >> 20;
                p.min(511) as u32
            }
        }
    }
}

pub(super) fn rgb9e5_forward(n: usize, t: usize, raw: &[u8], out: &mut [u8]) {
    let tex: Vec<u32> = raw
        .chunks_exact(4)
        .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    let (p0, rest) = out.split_at_mut(t);
    let (pg, rest) = rest.split_at_mut(t);
    let (pr, pb) = rest.split_at_mut(t);
    let mut i = 0;
    for y in 0..n {
        for x in 0..n {
            let (e, m) = fields(tex[i]);
            let nb = rgb9e5_neighbours(&tex, neighbours(n, x, y, i));
            let zg = zigzag9(m[1].wrapping_sub(predict_g(&nb, e)));
            let zr = zigzag9(m[0].wrapping_sub(predict_rb(&nb, e, m[1], 0)));
            let zb = zigzag9(m[2].wrapping_sub(predict_rb(&nb, e, m[1], 2)));
            p0[i] = (e | (zr >> 8) << 5 | (zg >> 8) << 6 | (zb >> 8) << 7) as u8;
            pg[i] = zg as u8;
            pr[i] = zr as u8;
            pb[i] = zb as u8;
            i += 1;
        }
    }
}

/// Rows decoded together by [`rgb9e5_inverse`].
pub(super) const ROWS_IN_FLIGHT: usize = 4;

/// Decodes one texel from its filtered bytes `(h, zg, zr, zb)` (plane 0 and the green, red
/// and blue low bytes) and its prediction neighbours `nb`.
#[inline(always)]
pub(super) fn rgb9e5_decode(h: u8, zg: u8, zr: u8, zb: u8, nb: &Nb) -> u32 {
    let h = u32::from(h);
    let e = h & 31;
    let g = predict_g(nb, e).wrapping_add(unzigzag9(u32::from(zg) | (h >> 6 & 1) << 8)) & 511;
    let r =
        predict_rb(nb, e, g, 0).wrapping_add(unzigzag9(u32::from(zr) | (h >> 5 & 1) << 8)) & 511;
    let b = predict_rb(nb, e, g, 2).wrapping_add(unzigzag9(u32::from(zb) | (h >> 7) << 8)) & 511;
    r | g << 9 | b << 18 | e << 27
}

/// The filtered bytes of texel `i`: plane 0, green, red and blue (0 past the end).
#[inline(always)]
pub(super) fn planes_at(planes: [&[u8]; 4], i: usize) -> [u8; 4] {
    planes.map(|p| p.get(i).copied().unwrap_or(0))
}

pub(super) fn rgb9e5_inverse(n: usize, t: usize, filtered: &[u8], out: &mut [u8]) {
    let (p0, rest) = filtered.split_at(t);
    let (pg, rest) = rest.split_at(t);
    let (pr, pb) = rest.split_at(t);
    let planes = [p0, pg, pr, pb];
    let mut tex = vec![0u32; t];
    // Texel (x, y) in the general way (any position).
    let general = |tex: &mut [u32], x: usize, y: usize| {
        let i = y * n + x;
        let [h, zg, zr, zb] = planes_at(planes, i);
        let v = rgb9e5_decode(
            h,
            zg,
            zr,
            zb,
            &rgb9e5_neighbours(tex, neighbours(n, x, y, i)),
        );
        if let Some(o) = tex.get_mut(i) {
            *o = v;
        }
    };
    // Row 0: each texel from its left neighbour.
    for x in 0..n {
        general(&mut tex, x, 0);
    }
    // Rows 1.. in groups of ROWS_IN_FLIGHT, staggered by one texel per row: at step `s` row
    // `y0 + r` decodes column `s - r`, whose left and above neighbours were decoded at step
    // `s - 1`. The texels of one step are independent, so the processor overlaps their
    // dependency chains (the format is unchanged: every texel sees the same neighbours).
    let mut y0 = 1;
    while y0 + ROWS_IN_FLIGHT <= n {
        const R: usize = ROWS_IN_FLIGHT;
        // Prologue: steps 0..R (columns < R - r, including column 0, by the general path).
        for s in 0..R.min(n) {
            for r in 0..=s {
                general(&mut tex, s - r, y0 + r);
            }
        }
        // Steady state: steps R..n, every row interior (x = s - r >= 1).
        let mut left = [0u32; R];
        for (r, l) in left.iter_mut().enumerate() {
            // Column R - 1 - r of row y0 + r was the last the prologue decoded.
            *l = tex.get((y0 + r) * n + (R - 1 - r)).copied().unwrap_or(0);
        }
        for s in R..n {
            for (r, l) in left.iter_mut().enumerate() {
                let i = (y0 + r) * n + s - r;
                let [h, zg, zr, zb] = planes_at(planes, i);
                let above = tex.get(i - n).copied().unwrap_or(0);
                let v = rgb9e5_decode(h, zg, zr, zb, &Some((fields(*l), fields(above))));
                if let Some(o) = tex.get_mut(i) {
                    *o = v;
                }
                *l = v;
            }
        }
        // Epilogue: the last columns of rows y0 + 1.. (steps n..n + R - 1).
        for s in n.max(R)..n + R - 1 {
            for r in s + 1 - n..R {
                general(&mut tex, s - r, y0 + r);
            }
        }
        y0 += R;
    }
    // The remaining rows one by one.
    for y in y0..n {
        for x in 0..n {
            general(&mut tex, x, y);
        }
    }
    for (o, v) in out.chunks_exact_mut(4).zip(&tex) {
        o.copy_from_slice(&v.to_le_bytes());
    }
}
