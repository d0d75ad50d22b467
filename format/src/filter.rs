//! Reversible, lossless filters applied to a face's raw bytes before zstd and undone after
//! decompression (the byte layout and the exact predictors are in the crate docs, "Face
//! filters").
//!
//! The filters never fail on content: [`unfilter_face`] maps any input of the right size to
//! some output (wrapping arithmetic throughout), and [`filter_face`] followed by
//! [`unfilter_face`] is the identity on every input, canonical or not.

use crate::encoding::Encoding;
use crate::Error;

/// How a face's raw bytes are transformed before compression (header bytes 176..180).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum Filter {
    /// Id 0: the raw bytes are compressed as they are.
    None,
    /// Id 1: planes of predicted, zig-zag encoded residuals (the default for new stores).
    #[default]
    Predict,
}

impl Filter {
    /// All filters, in id order.
    pub const ALL: [Filter; 2] = [Filter::None, Filter::Predict];

    /// The on-disk id: 0 or 1.
    pub fn id(self) -> u32 {
        match self {
            Filter::None => 0,
            Filter::Predict => 1,
        }
    }

    /// The filter with on-disk id `id`.
    pub fn from_id(id: u32) -> Option<Self> {
        match id {
            0 => Some(Filter::None),
            1 => Some(Filter::Predict),
            _ => None,
        }
    }

    /// `"none"` or `"predict"`.
    pub fn name(self) -> &'static str {
        match self {
            Filter::None => "none",
            Filter::Predict => "predict",
        }
    }
}

impl std::fmt::Display for Filter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// `RECIP[s] = floor(2^20 / s)` for `s` in `1..=1022` (`RECIP[0] = 0`, unused).
static RECIP: [u32; 1023] = {
    let mut t = [0u32; 1023];
    let mut s = 1;
    while s < 1023 {
        t[s] = (1 << 20) / s as u32;
        s += 1;
    }
    t
};

fn check_sizes(
    encoding: Encoding,
    resolution: u32,
    distance: bool,
    a: usize,
    b: usize,
) -> Result<(usize, usize), Error> {
    let texels = (resolution as usize)
        .checked_mul(resolution as usize)
        .ok_or(Error::Limit {
            what: "face texels",
            value: u64::from(resolution),
            max: u64::from(crate::MAX_CUBE_RESOLUTION),
        })?;
    let per = encoding.bytes_per_texel() + if distance { 4 } else { 0 };
    let expected = texels.checked_mul(per);
    for (what, len) in [("filter input", a), ("filter output", b)] {
        if expected != Some(len) {
            return Err(Error::BufferSize {
                what,
                expected: expected.unwrap_or(usize::MAX) as u64,
                actual: len as u64,
            });
        }
    }
    Ok((texels, texels * encoding.bytes_per_texel()))
}

/// Filters one face's raw bytes (`raw`, exactly the face raw size) into `out` (same size).
pub fn filter_face(
    filter: Filter,
    encoding: Encoding,
    resolution: u32,
    distance: bool,
    raw: &[u8],
    out: &mut [u8],
) -> Result<(), Error> {
    let (t, color) = check_sizes(encoding, resolution, distance, raw.len(), out.len())?;
    let n = resolution as usize;
    match filter {
        Filter::None => out.copy_from_slice(raw),
        Filter::Predict => {
            let (rc, rd) = raw.split_at(color);
            let (oc, od) = out.split_at_mut(color);
            match encoding {
                Encoding::Rgb9e5 => rgb9e5_forward(n, t, rc, oc),
                Encoding::Rgba16f => ints_forward::<2>(n, t, rc, oc),
                Encoding::Rgba32f => ints_forward::<4>(n, t, rc, oc),
            }
            if distance {
                distance_forward(n, t, rd, od);
            }
        }
    }
    Ok(())
}

/// Undoes [`filter_face`]: `filtered` (exactly the face raw size) into `out` (same size).
/// Never fails on content.
pub fn unfilter_face(
    filter: Filter,
    encoding: Encoding,
    resolution: u32,
    distance: bool,
    filtered: &[u8],
    out: &mut [u8],
) -> Result<(), Error> {
    let (t, color) = check_sizes(encoding, resolution, distance, filtered.len(), out.len())?;
    let n = resolution as usize;
    match filter {
        Filter::None => out.copy_from_slice(filtered),
        Filter::Predict => {
            let (fc, fd) = filtered.split_at(color);
            let (oc, od) = out.split_at_mut(color);
            match encoding {
                Encoding::Rgb9e5 => rgb9e5_inverse(n, t, fc, oc),
                Encoding::Rgba16f => ints_inverse::<2>(n, t, fc, oc),
                Encoding::Rgba32f => ints_inverse::<4>(n, t, fc, oc),
            }
            if distance {
                distance_inverse(n, t, fd, od);
            }
        }
    }
    Ok(())
}

/// The two prediction neighbours of texel `(x, y)` (row-major index `i`): `(a, b)` =
/// (left, above); in row 0 both are the left texel, in column 0 both are the texel above.
/// `None` for texel (0, 0).
#[inline(always)]
fn neighbours(n: usize, x: usize, y: usize, i: usize) -> Option<(usize, usize)> {
    match (x > 0, y > 0) {
        (true, true) => Some((i - 1, i - n)),
        (true, false) => Some((i - 1, i - 1)),
        (false, true) => Some((i - n, i - n)),
        (false, false) => None,
    }
}

// ---------------------------------------------------------------------------------------
// RGB9E5
// ---------------------------------------------------------------------------------------

/// A 9-bit mantissa `m` of a texel with exponent `from`, rescaled to exponent `to`.
#[inline(always)]
fn rescale(m: u32, from: u32, to: u32) -> u32 {
    // Branch-free: with `from >= to`, `k = 0` and this is `min(511, m << d)`; otherwise
    // `d = 0` and it is `(m + 2^(k-1)) >> k` (m <= 511).
    let d = from.saturating_sub(to).min(9);
    let k = to.saturating_sub(from).min(31);
    (((m & 511) << d).min(511) + ((1u32 << k) >> 1)) >> k
}

#[inline(always)]
fn zigzag9(r: u32) -> u32 {
    let r = r & 511;
    if r < 256 {
        r << 1
    } else {
        ((512 - r) << 1) - 1
    }
}

#[inline(always)]
fn unzigzag9(z: u32) -> u32 {
    ((z & 511) >> 1 ^ (z & 1).wrapping_neg()) & 511
}

#[inline(always)]
fn fields(v: u32) -> (u32, [u32; 3]) {
    (v >> 27, [v & 511, (v >> 9) & 511, (v >> 18) & 511])
}

/// The neighbour data texel `i`'s predictions need: their exponents and mantissas.
type Nb = Option<((u32, [u32; 3]), (u32, [u32; 3]))>;

#[inline(always)]
fn rgb9e5_neighbours(tex: &[u32], nb: Option<(usize, usize)>) -> Nb {
    let (a, b) = nb?;
    Some((
        fields(tex.get(a).copied().unwrap_or(0)),
        fields(tex.get(b).copied().unwrap_or(0)),
    ))
}

/// Green prediction of a texel with exponent `e`.
#[inline(always)]
fn predict_g(nb: &Nb, e: u32) -> u32 {
    match nb {
        None => 0,
        Some(((ea, ma), (eb, mb))) => (rescale(ma[1], *ea, e) + rescale(mb[1], *eb, e)) >> 1,
    }
}

/// Prediction of channel `c` (0 red, 2 blue) of a texel with exponent `e` and green `g`.
#[inline(always)]
fn predict_rb(nb: &Nb, e: u32, g: u32, c: usize) -> u32 {
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

fn rgb9e5_forward(n: usize, t: usize, raw: &[u8], out: &mut [u8]) {
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

fn rgb9e5_inverse(n: usize, t: usize, filtered: &[u8], out: &mut [u8]) {
    let (p0, rest) = filtered.split_at(t);
    let (pg, rest) = rest.split_at(t);
    let (pr, pb) = rest.split_at(t);
    let mut tex = vec![0u32; t];
    let decode = |i: usize, nb: Nb| {
        let h = u32::from(p0[i]);
        let e = h & 31;
        let g =
            predict_g(&nb, e).wrapping_add(unzigzag9(u32::from(pg[i]) | (h >> 6 & 1) << 8)) & 511;
        let r = predict_rb(&nb, e, g, 0)
            .wrapping_add(unzigzag9(u32::from(pr[i]) | (h >> 5 & 1) << 8))
            & 511;
        let b = predict_rb(&nb, e, g, 2).wrapping_add(unzigzag9(u32::from(pb[i]) | (h >> 7) << 8))
            & 511;
        r | g << 9 | b << 18 | e << 27
    };
    for y in 0..n {
        let row = y * n;
        // Column 0 (and texel (0, 0)) through the general path.
        tex[row] = decode(row, rgb9e5_neighbours(&tex, neighbours(n, 0, y, row)));
        if y == 0 {
            for i in 1..n {
                let l = fields(tex[i - 1]);
                tex[i] = decode(i, Some((l, l)));
            }
        } else {
            let (above, cur) = tex.split_at_mut(row);
            let above = &above[row - n..];
            let cur = &mut cur[..n];
            let mut left = fields(cur[0]);
            for x in 1..n {
                let v = decode(row + x, Some((left, fields(above[x]))));
                cur[x] = v;
                left = fields(v);
            }
        }
    }
    for (o, v) in out.chunks_exact_mut(4).zip(&tex) {
        o.copy_from_slice(&v.to_le_bytes());
    }
}

// ---------------------------------------------------------------------------------------
// RGBA16F / RGBA32F: W-byte unsigned channel patterns
// ---------------------------------------------------------------------------------------

#[inline(always)]
fn mask<const W: usize>() -> u64 {
    if W >= 8 {
        u64::MAX
    } else {
        (1u64 << (8 * W)) - 1
    }
}

/// Zig-zag of a W-byte residual `r` (read as a signed W-byte integer `s`): `2s` for
/// `s >= 0`, `-2s - 1` otherwise.
#[inline(always)]
fn zigzag<const W: usize>(r: u64) -> u64 {
    let bits = 8 * W as u32;
    let s = ((r << (64 - bits)) as i64) >> (64 - bits);
    (((s << 1) ^ (s >> 63)) as u64) & mask::<W>()
}

#[inline(always)]
fn unzigzag<const W: usize>(z: u64) -> u64 {
    ((z >> 1) ^ (z & 1).wrapping_neg()) & mask::<W>()
}

#[inline(always)]
fn get_w<const W: usize>(b: &[u8], i: usize) -> u64 {
    let mut v = 0u64;
    for k in 0..W {
        v |= u64::from(b.get(i * W + k).copied().unwrap_or(0)) << (8 * k);
    }
    v
}

/// Channel order of the planes: G, R, B, A (channel indices into the texel).
const PLANE_CHANNELS: [usize; 4] = [1, 0, 2, 3];

/// Predictions `[R, G, B, A]` of a texel with green `g` from its neighbours' patterns.
#[inline(always)]
fn ints_predict<const W: usize>(nb: Option<([u64; 4], [u64; 4])>, g: u64) -> [u64; 4] {
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
fn texel_w<const W: usize>(b: &[u8], i: usize) -> [u64; 4] {
    std::array::from_fn(|c| get_w::<W>(b, 4 * i + c))
}

fn ints_forward<const W: usize>(n: usize, t: usize, raw: &[u8], out: &mut [u8]) {
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

fn ints_inverse<const W: usize>(n: usize, t: usize, filtered: &[u8], out: &mut [u8]) {
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

// ---------------------------------------------------------------------------------------
// Distance plane: u32 patterns of the f32 distances
// ---------------------------------------------------------------------------------------

fn distance_forward(n: usize, t: usize, raw: &[u8], out: &mut [u8]) {
    let mut i = 0;
    for y in 0..n {
        for x in 0..n {
            let v = get_w::<4>(raw, i);
            let p = neighbours(n, x, y, i).map_or(0, |(a, _)| get_w::<4>(raw, a));
            let z = zigzag::<4>(v.wrapping_sub(p));
            for j in 0..4 {
                if let Some(o) = out.get_mut(j * t + i) {
                    *o = (z >> (8 * j)) as u8;
                }
            }
            i += 1;
        }
    }
}

fn distance_inverse(n: usize, t: usize, filtered: &[u8], out: &mut [u8]) {
    let mut i = 0;
    for y in 0..n {
        for x in 0..n {
            let mut z = 0u64;
            for j in 0..4 {
                z |= u64::from(filtered.get(j * t + i).copied().unwrap_or(0)) << (8 * j);
            }
            let p = neighbours(n, x, y, i).map_or(0, |(a, _)| get_w::<4>(out, a));
            let v = p.wrapping_add(unzigzag::<4>(z)) & mask::<4>();
            if let Some(o) = out.get_mut(4 * i..4 * i + 4) {
                o.copy_from_slice(&(v as u32).to_le_bytes());
            }
            i += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> u64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            self.0
        }
    }

    #[test]
    fn zigzags_are_inverse() {
        for r in 0..512 {
            assert_eq!(unzigzag9(zigzag9(r)), r);
        }
        assert_eq!(zigzag9(0), 0);
        assert_eq!(zigzag9(511), 1);
        assert_eq!(zigzag9(1), 2);
        for r in 0..=0xffffu64 {
            assert_eq!(unzigzag::<2>(zigzag::<2>(r)), r);
        }
        for r in [0u64, 1, 0x7fff_ffff, 0x8000_0000, 0xffff_ffff, 12345678] {
            assert_eq!(unzigzag::<4>(zigzag::<4>(r)), r);
        }
        assert_eq!(zigzag::<4>(0xffff_ffff), 1);
    }

    #[test]
    fn round_trips_any_bytes() {
        let mut rng = Rng(0x1234_5678_9abc_def1);
        for enc in Encoding::ALL {
            for res in [1u32, 2, 3, 5, 16] {
                for distance in [false, true] {
                    let len = (res * res) as usize
                        * (enc.bytes_per_texel() + if distance { 4 } else { 0 });
                    for kind in 0..3 {
                        let raw: Vec<u8> = (0..len)
                            .map(|i| match kind {
                                0 => rng.next() as u8,
                                1 => (i / 7) as u8,
                                _ => [0u8, 0xff][(rng.next() & 1) as usize],
                            })
                            .collect();
                        for f in Filter::ALL {
                            let mut filtered = vec![0u8; len];
                            filter_face(f, enc, res, distance, &raw, &mut filtered).unwrap();
                            let mut back = vec![0u8; len];
                            unfilter_face(f, enc, res, distance, &filtered, &mut back).unwrap();
                            assert_eq!(back, raw, "{enc} {f} res {res} distance {distance}");
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn wrong_sizes_are_errors() {
        let mut out = vec![0u8; 16];
        assert!(matches!(
            filter_face(
                Filter::Predict,
                Encoding::Rgb9e5,
                2,
                false,
                &[0; 15],
                &mut out
            ),
            Err(Error::BufferSize { .. })
        ));
        assert!(matches!(
            unfilter_face(
                Filter::Predict,
                Encoding::Rgb9e5,
                2,
                true,
                &[0; 16],
                &mut out
            ),
            Err(Error::BufferSize { .. })
        ));
        assert!(Filter::from_id(2).is_none());
        for f in Filter::ALL {
            assert_eq!(Filter::from_id(f.id()), Some(f));
        }
    }
}
