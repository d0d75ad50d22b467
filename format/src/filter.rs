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
    /// Id 1: planes of predicted, zig-zag encoded residuals; RGB9E5 texels predicted from
    /// their left and upper neighbours.
    Predict,
    /// Id 2: as [`Filter::Predict`], but RGB9E5 texels are predicted from the row above only
    /// (binary32 arithmetic), so a row decodes without a texel-to-texel dependency. What
    /// writers use for lossless stores ([`Filter::for_store`]).
    #[default]
    PredictRows,
    /// Id 3: filter 2's predictions, but each RGB9E5 texel's exponent and three residuals
    /// (in units of the store's mantissa lattice) packed into `⌈(5 + 3k) / 8⌉` byte planes
    /// for `k` mantissa bits: fewer bytes for zstd to decode. What writers use for RGB9E5
    /// stores that keep at most 6 mantissa bits ([`Filter::for_store`]).
    PredictPacked,
}

impl Filter {
    /// All filters, in id order.
    pub const ALL: [Filter; 4] = [
        Filter::None,
        Filter::Predict,
        Filter::PredictRows,
        Filter::PredictPacked,
    ];

    /// The on-disk id: 0, 1 or 2.
    pub fn id(self) -> u32 {
        match self {
            Filter::None => 0,
            Filter::Predict => 1,
            Filter::PredictRows => 2,
            Filter::PredictPacked => 3,
        }
    }

    /// The filter with on-disk id `id`.
    pub fn from_id(id: u32) -> Option<Self> {
        match id {
            0 => Some(Filter::None),
            1 => Some(Filter::Predict),
            2 => Some(Filter::PredictRows),
            3 => Some(Filter::PredictPacked),
            _ => None,
        }
    }

    /// The filter writers use for a store of `encoding` keeping `mantissa_bits` RGB9E5 mantissa
    /// bits: [`Filter::PredictPacked`] for RGB9E5 with at most 6 bits, where it is smaller
    /// and faster to read than filter 2, [`Filter::PredictRows`] otherwise (with 7 to 9 bits
    /// filter 3's code splits residuals across bytes and compresses worse: docs/measurements.md,
    /// "Quantized RGB9E5"). BC6H stores get [`Filter::PredictRows`] too: filters 1 to 3 leave
    /// BC6H blocks as they are (regrouping their bytes into planes compressed worse: 1.004
    /// against 0.973 bytes per texel on the example scene; crate docs, "BC6H") and predict the
    /// distance plane.
    pub fn for_store(encoding: Encoding, mantissa_bits: u32) -> Self {
        if encoding == Encoding::Rgb9e5 && mantissa_bits <= 6 {
            Filter::PredictPacked
        } else {
            Filter::PredictRows
        }
    }

    /// `"none"`, `"predict"`, `"predict-rows"` or `"predict-packed"`.
    pub fn name(self) -> &'static str {
        match self {
            Filter::None => "none",
            Filter::Predict => "predict",
            Filter::PredictRows => "predict-rows",
            Filter::PredictPacked => "predict-packed",
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

/// Size in bytes of one face after `filter`, i.e. what its zstd frame decompresses to: the
/// raw face size ([`crate::Store::face_raw_size`]), except filter 3 on RGB9E5, whose texel
/// part is `n² × ⌈(5 + 3k) / 8⌉` bytes for `k = mantissa_bits` (the distance plane, if any,
/// keeps `n² × 4`). `None` if the size overflows `usize`.
pub fn filtered_face_size(
    filter: Filter,
    encoding: Encoding,
    resolution: u32,
    distance: bool,
    mantissa_bits: u32,
) -> Option<usize> {
    let texels = (resolution as usize).checked_mul(resolution as usize)?;
    let color = match (filter, encoding) {
        (Filter::PredictPacked, Encoding::Rgb9e5) => {
            texels.checked_mul(packed_planes(mantissa_bits))?
        }
        _ => encoding.face_bytes(resolution)?,
    };
    color.checked_add(if distance { texels.checked_mul(4)? } else { 0 })
}

/// Checks the lengths of a filter's input `raw` (the raw face) and output `filtered`;
/// returns the texel count and the lengths of their texel parts.
#[allow(clippy::too_many_arguments)]
fn check_sizes(
    filter: Filter,
    encoding: Encoding,
    resolution: u32,
    distance: bool,
    mantissa_bits: u32,
    raw: usize,
    filtered: usize,
) -> Result<(usize, usize, usize), Error> {
    let overflow = || Error::Limit {
        what: "face texels",
        value: u64::from(resolution),
        max: u64::from(crate::MAX_CUBE_RESOLUTION),
    };
    let texels = (resolution as usize)
        .checked_mul(resolution as usize)
        .ok_or_else(overflow)?;
    let raw_size =
        filtered_face_size(Filter::None, encoding, resolution, distance, 9).ok_or_else(overflow)?;
    let filtered_size = filtered_face_size(filter, encoding, resolution, distance, mantissa_bits)
        .ok_or_else(overflow)?;
    for (what, len, expected) in [
        ("raw face", raw, raw_size),
        ("filtered face", filtered, filtered_size),
    ] {
        if len != expected {
            return Err(Error::BufferSize {
                what,
                expected: expected as u64,
                actual: len as u64,
            });
        }
    }
    let dist = if distance { texels * 4 } else { 0 };
    Ok((texels, raw_size - dist, filtered_size - dist))
}

/// The mantissa lattice of a store keeping `k` RGB9E5 mantissa bits: filter 2 rounds its
/// predictions to multiples of `step = 2^(9 − k)`, so that the residuals of quantized texels
/// are multiples of `step` too. `k = 9` (step 1) leaves every prediction unchanged.
#[derive(Clone, Copy, Debug)]
struct Lattice {
    /// `step / 2`.
    half: u32,
    /// `!(step − 1)` (low bits cleared).
    mask: u32,
    /// `512 − step`, the largest multiple of `step` below 512.
    top: u32,
}

impl Lattice {
    fn new(mantissa_bits: u32) -> Self {
        let step = 1u32 << (9 - mantissa_bits.clamp(1, 9));
        Lattice {
            half: step / 2,
            mask: !(step - 1),
            top: 512 - step,
        }
    }

    /// The multiple of `step` nearest to `p` (ties up), at most `top`; `p` for step 1.
    #[inline(always)]
    fn round(self, p: u32) -> u32 {
        let q = (p + self.half) & self.mask;
        if q < self.top {
            q
        } else {
            self.top
        }
    }
}

/// Filters one face's raw bytes (`raw`, exactly the face raw size) into `out` (same size).
/// For a store of lossless RGB9E5 (`mantissa_bits` 9); see [`filter_face_quantized`].
pub fn filter_face(
    filter: Filter,
    encoding: Encoding,
    resolution: u32,
    distance: bool,
    raw: &[u8],
    out: &mut [u8],
) -> Result<(), Error> {
    filter_face_quantized(filter, encoding, resolution, distance, 9, raw, out)
}

/// [`filter_face`] for a store keeping `mantissa_bits` (1..=9) RGB9E5 mantissa bits. `out`
/// is [`filtered_face_size`] bytes (the raw size except for filter 3).
///
/// Filter 2 rounds its RGB9E5 predictions to the store's mantissa lattice (crate docs, "Face
/// filters"): lossless for every input whatever `mantissa_bits` is, compact when the texels
/// were quantized to those bits. Filter 3 stores residuals in lattice steps, so its RGB9E5
/// input must be quantized ([`crate::encoding::quantize_rgb9e5`]): a mantissa off the
/// lattice is an [`Error::Unquantized`]. Other filters and encodings ignore `mantissa_bits`.
pub fn filter_face_quantized(
    filter: Filter,
    encoding: Encoding,
    resolution: u32,
    distance: bool,
    mantissa_bits: u32,
    raw: &[u8],
    out: &mut [u8],
) -> Result<(), Error> {
    let (t, rc_len, oc_len) = check_sizes(
        filter,
        encoding,
        resolution,
        distance,
        mantissa_bits,
        raw.len(),
        out.len(),
    )?;
    let n = resolution as usize;
    if filter == Filter::None {
        out.copy_from_slice(raw);
        return Ok(());
    }
    let (rc, rd) = raw.split_at(rc_len);
    let (oc, od) = out.split_at_mut(oc_len);
    match (filter, encoding) {
        (Filter::PredictPacked, Encoding::Rgb9e5) => {
            check_quantized(rc, mantissa_bits)?;
            packed_forward(n, t, rc, oc, Packed::new(mantissa_bits))
        }
        (Filter::PredictRows, Encoding::Rgb9e5) => {
            rows_forward::<_, 4>(n, t, rc, oc, Planes9(Lattice::new(mantissa_bits)))
        }
        (_, Encoding::Rgb9e5) => rgb9e5_forward(n, t, rc, oc),
        (_, Encoding::Rgba16f) => ints_forward::<2>(n, t, rc, oc),
        (_, Encoding::Rgba32f) => ints_forward::<4>(n, t, rc, oc),
        // BC6H blocks are left as they are (byte planes of them compress worse).
        (_, Encoding::Bc6h) => oc.copy_from_slice(rc),
    }
    if distance {
        distance_forward(n, t, rd, od);
    }
    Ok(())
}

/// [`Error::Unquantized`] for the first RGB9E5 texel in `raw` whose mantissas are not all
/// multiples of `2^(9 − mantissa_bits)`.
fn check_quantized(raw: &[u8], mantissa_bits: u32) -> Result<(), Error> {
    let step = 1u32 << (9 - mantissa_bits.clamp(1, 9));
    let low = (step - 1) * (1 | 1 << 9 | 1 << 18);
    match raw
        .chunks_exact(4)
        .position(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]) & low != 0)
    {
        None => Ok(()),
        Some(texel) => Err(Error::Unquantized {
            texel,
            mantissa_bits,
        }),
    }
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
    unfilter_face_quantized(filter, encoding, resolution, distance, 9, filtered, out)
}

/// Undoes [`filter_face_quantized`] with the same `mantissa_bits`: `filtered`
/// ([`filtered_face_size`] bytes) into `out` (the raw face size). Never fails on content.
pub fn unfilter_face_quantized(
    filter: Filter,
    encoding: Encoding,
    resolution: u32,
    distance: bool,
    mantissa_bits: u32,
    filtered: &[u8],
    out: &mut [u8],
) -> Result<(), Error> {
    let (t, oc_len, fc_len) = check_sizes(
        filter,
        encoding,
        resolution,
        distance,
        mantissa_bits,
        out.len(),
        filtered.len(),
    )?;
    let n = resolution as usize;
    if filter == Filter::None {
        out.copy_from_slice(filtered);
        return Ok(());
    }
    let (fc, fd) = filtered.split_at(fc_len);
    let (oc, od) = out.split_at_mut(oc_len);
    match (filter, encoding) {
        (Filter::PredictPacked, Encoding::Rgb9e5) => {
            packed_inverse(n, t, fc, oc, Packed::new(mantissa_bits))
        }
        (Filter::PredictRows, Encoding::Rgb9e5) => {
            rows_inverse::<_, 4>(n, t, fc, oc, Planes9(Lattice::new(mantissa_bits)))
        }
        (_, Encoding::Rgb9e5) => rgb9e5_inverse(n, t, fc, oc),
        (_, Encoding::Rgba16f) => ints_inverse::<2>(n, t, fc, oc),
        (_, Encoding::Rgba32f) => ints_inverse::<4>(n, t, fc, oc),
        (_, Encoding::Bc6h) => oc.copy_from_slice(fc),
    }
    if distance {
        distance_inverse(n, t, fd, od);
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

/// Rows decoded together by [`rgb9e5_inverse`].
const ROWS_IN_FLIGHT: usize = 4;

/// Decodes one texel from its filtered bytes `(h, zg, zr, zb)` (plane 0 and the green, red
/// and blue low bytes) and its prediction neighbours `nb`.
#[inline(always)]
fn rgb9e5_decode(h: u8, zg: u8, zr: u8, zb: u8, nb: &Nb) -> u32 {
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
fn planes_at(planes: [&[u8]; 4], i: usize) -> [u8; 4] {
    planes.map(|p| p.get(i).copied().unwrap_or(0))
}

fn rgb9e5_inverse(n: usize, t: usize, filtered: &[u8], out: &mut [u8]) {
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

// ---------------------------------------------------------------------------------------
// RGB9E5, filter 2 (predict-rows): binary32 predictions from the row above
// ---------------------------------------------------------------------------------------

/// `2^k` as an f32, for `k` in `-126..=127` (exact: built from the exponent bits).
#[inline(always)]
fn pow2(k: i32) -> f32 {
    f32::from_bits(((k + 127) as u32) << 23)
}

/// A channel's value `m · 2^e` (exact in binary32 for `m <= 511`, `e <= 31`).
#[inline(always)]
fn channel_value(m: u32, e: u32) -> f32 {
    (m & 511) as i32 as f32 * pow2((e & 31) as i32)
}

/// `min(511, trunc(x + 0.5))` for `x >= 0` (x may be +inf; the sum is rounded to binary32).
#[inline(always)]
fn round_mantissa(x: f32) -> u32 {
    // Written as comparisons, not `f32::min`/`max`, so that it vectorises; NaN (which the
    // callers never pass) fails `y < 511.0` and gives 511.
    let y = x + 0.5;
    let y = if y < 511.0 { y } else { 511.0 };
    let y = if y >= 0.0 { y } else { 0.0 };
    // SAFETY: after the two comparisons `y` is in [0, 511] (NaN became 511, anything below 0
    // became 0), so it is finite and its truncation fits an i32.
    unsafe { y.to_int_unchecked::<i32>() as u32 }
}

/// Neighbour sums of one channel: `(a + 2b) + c`, each operation rounded to binary32.
#[inline(always)]
fn tap_sum(a: f32, b: f32, c: f32) -> f32 {
    (a + 2.0 * b) + c
}

/// Green prediction from the neighbour sum `sg` of a texel with exponent `e`.
#[inline(always)]
fn rows_predict_g(sg: f32, e: u32, lat: Lattice) -> u32 {
    // 2^(-e-2): the sums weigh four neighbours and are in units of 2^0.
    lat.round(round_mantissa(sg * pow2(-((e & 31) as i32) - 2)))
}

/// Red or blue prediction from the neighbour sums `sc` (the channel) and `sg` (green) of a
/// texel with exponent `e` and green mantissa `g`.
#[inline(always)]
fn rows_predict_rb(sc: f32, sg: f32, e: u32, g: u32, lat: Lattice) -> u32 {
    let flat = sc * pow2(-((e & 31) as i32) - 2);
    // Division by zero gives inf or NaN only in the branch that is not taken.
    let ratio = (g & 511) as i32 as f32 * (sc / sg);
    lat.round(round_mantissa(if sg == 0.0 { flat } else { ratio }))
}

/// Per-row neighbour values of the three channels, padded by one column on each side with
/// copies of the edge texels: `[x + 1]` holds column `x`.
struct RowValues {
    g: Vec<f32>,
    r: Vec<f32>,
    b: Vec<f32>,
}

impl RowValues {
    fn new(n: usize) -> Self {
        Self {
            g: vec![0.0; n + 2],
            r: vec![0.0; n + 2],
            b: vec![0.0; n + 2],
        }
    }

    /// Makes the row `n` columns wide (contents unspecified until filled).
    fn resize(&mut self, n: usize) {
        for c in [&mut self.g, &mut self.r, &mut self.b] {
            c.resize(n + 2, 0.0);
        }
    }

    /// Fills the row from texels `tex` (length n).
    fn fill(&mut self, tex: &[u32]) {
        let n = tex.len();
        for (x, &v) in tex.iter().enumerate() {
            let (e, m) = fields(v);
            self.g[x + 1] = channel_value(m[1], e);
            self.r[x + 1] = channel_value(m[0], e);
            self.b[x + 1] = channel_value(m[2], e);
        }
        self.pad(n);
    }

    fn pad(&mut self, n: usize) {
        for c in [&mut self.g, &mut self.r, &mut self.b] {
            c[0] = c[1];
            c[n + 1] = c[n];
        }
    }
}

/// How filters 2 and 3 store a texel's exponent and residuals: the residual code of a
/// mantissa against its prediction, and the bytes the codes are written as. Both predict
/// alike (the same [`Lattice`]-rounded binary32 predictions); only the residuals differ.
trait RowCodec: Copy {
    /// The mantissa lattice predictions are rounded to.
    fn lattice(self) -> Lattice;
    /// The residual code of mantissa `m` against prediction `p`.
    fn residual(self, m: u32, p: u32) -> u32;
    /// The mantissa with prediction `p` and residual code `z` (any value: never fails).
    fn apply(self, p: u32, z: u32) -> u32;
    /// A texel's bytes, one per plane (the filter's first `P` are stored: 4 for filter 2,
    /// [`packed_planes`] for filter 3).
    fn pack(self, e: u32, zg: u32, zr: u32, zb: u32) -> [u8; 4];
    /// `(e, zg, zr, zb)` from a texel's bytes (unused bytes 0).
    fn unpack(self, bytes: [u8; 4]) -> (u32, u32, u32, u32);
}

/// Filter 2: four byte planes, `zigzag9` residuals of the whole 9-bit difference.
#[derive(Clone, Copy, Debug)]
struct Planes9(Lattice);

impl RowCodec for Planes9 {
    #[inline(always)]
    fn lattice(self) -> Lattice {
        self.0
    }
    #[inline(always)]
    fn residual(self, m: u32, p: u32) -> u32 {
        zigzag9(m.wrapping_sub(p))
    }
    #[inline(always)]
    fn apply(self, p: u32, z: u32) -> u32 {
        (p + unzigzag9(z)) & 511
    }
    #[inline(always)]
    fn pack(self, e: u32, zg: u32, zr: u32, zb: u32) -> [u8; 4] {
        [
            (e | (zr >> 8) << 5 | (zg >> 8) << 6 | (zb >> 8) << 7) as u8,
            zg as u8,
            zr as u8,
            zb as u8,
        ]
    }
    #[inline(always)]
    fn unpack(self, [h, zg, zr, zb]: [u8; 4]) -> (u32, u32, u32, u32) {
        let h = u32::from(h);
        (
            h & 31,
            u32::from(zg) | (h >> 6 & 1) << 8,
            u32::from(zr) | (h >> 5 & 1) << 8,
            u32::from(zb) | (h >> 7) << 8,
        )
    }
}

/// Filter 3: residuals in units of the lattice step `2^(9 − k)`, zig-zagged in `k` bits, and
/// packed with the exponent into one `(5 + 3k)`-bit code per texel: `e | zG << 5 | zR << (5
/// + k) | zB << (5 + 2k)`, stored as `⌈(5 + 3k) / 8⌉` byte planes (least significant first).
#[derive(Clone, Copy, Debug)]
struct Packed {
    lat: Lattice,
    /// `k`.
    bits: u32,
    /// `9 − k`.
    shift: u32,
    /// `2^k − 1`.
    mask: u32,
}

impl Packed {
    fn new(mantissa_bits: u32) -> Self {
        let bits = mantissa_bits.clamp(1, 9);
        Packed {
            lat: Lattice::new(bits),
            bits,
            shift: 9 - bits,
            mask: (1 << bits) - 1,
        }
    }
}

/// Byte planes of filter 3's texel code with `mantissa_bits` (1..=9) bits: `⌈(5 + 3k) / 8⌉`.
pub fn packed_planes(mantissa_bits: u32) -> usize {
    (5 + 3 * mantissa_bits.clamp(1, 9) as usize).div_ceil(8)
}

impl RowCodec for Packed {
    #[inline(always)]
    fn lattice(self) -> Lattice {
        self.lat
    }
    #[inline(always)]
    fn residual(self, m: u32, p: u32) -> u32 {
        // zigzag in k bits of q = the difference in lattice steps (mod 2^k).
        let q = (m.wrapping_sub(p) & 511) >> self.shift;
        let half = 1 << (self.bits - 1);
        if q < half {
            q << 1
        } else {
            (((self.mask + 1) - q) << 1) - 1
        }
    }
    #[inline(always)]
    fn apply(self, p: u32, z: u32) -> u32 {
        let q = ((z & self.mask) >> 1 ^ (z & 1).wrapping_neg()) & self.mask;
        (p + (q << self.shift)) & 511
    }
    #[inline(always)]
    fn pack(self, e: u32, zg: u32, zr: u32, zb: u32) -> [u8; 4] {
        let k = self.bits;
        (e | zg << 5 | zr << (5 + k) | zb << (5 + 2 * k)).to_le_bytes()
    }
    #[inline(always)]
    fn unpack(self, bytes: [u8; 4]) -> (u32, u32, u32, u32) {
        let (k, m) = (self.bits, self.mask);
        let c = u32::from_le_bytes(bytes);
        (
            c & 31,
            (c >> 5) & m,
            (c >> (5 + k)) & m,
            (c >> (5 + 2 * k)) & m,
        )
    }
}

/// Neighbour sums `(S_G, S_R, S_B)` of a texel in row 0 of filters 2 and 3: its left
/// neighbour as all three taps, or zeros for texel 0.
#[inline(always)]
fn first_row_sums(left: Option<u32>) -> (f32, f32, f32) {
    match left {
        None => (0.0, 0.0, 0.0),
        Some(l) => {
            let (el, ml) = fields(l);
            let (g, r, b) = (
                channel_value(ml[1], el),
                channel_value(ml[0], el),
                channel_value(ml[2], el),
            );
            (tap_sum(g, g, g), tap_sum(r, r, r), tap_sum(b, b, b))
        }
    }
}

/// The bytes of texel `v` with neighbour sums `sums`.
#[inline(always)]
fn rows_encode_texel<C: RowCodec>(v: u32, (sg, sr, sb): (f32, f32, f32), codec: C) -> [u8; 4] {
    let lat = codec.lattice();
    let (e, m) = fields(v);
    let zg = codec.residual(m[1], rows_predict_g(sg, e, lat));
    let zr = codec.residual(m[0], rows_predict_rb(sr, sg, e, m[1], lat));
    let zb = codec.residual(m[2], rows_predict_rb(sb, sg, e, m[1], lat));
    codec.pack(e, zg, zr, zb)
}

/// Texel from its bytes and neighbour sums `sums`.
#[inline(always)]
fn rows_decode_texel<C: RowCodec>(bytes: [u8; 4], (sg, sr, sb): (f32, f32, f32), codec: C) -> u32 {
    let lat = codec.lattice();
    let (e, zg, zr, zb) = codec.unpack(bytes);
    let g = codec.apply(rows_predict_g(sg, e, lat), zg);
    let r = codec.apply(rows_predict_rb(sr, sg, e, g, lat), zr);
    let b = codec.apply(rows_predict_rb(sb, sg, e, g, lat), zb);
    r | g << 9 | b << 18 | e << 27
}

/// The bytes of texel `x` in `P` planes (the rest 0).
#[inline(always)]
fn bytes_at<const P: usize>(planes: &[&[u8]; P], x: usize) -> [u8; 4] {
    let mut b = [0u8; 4];
    for (o, p) in b.iter_mut().zip(planes) {
        *o = p[x];
    }
    b
}

/// Filters 2 and 3 forward: `out` holds `P` planes of `t` bytes.
fn rows_forward<C: RowCodec, const P: usize>(
    n: usize,
    t: usize,
    raw: &[u8],
    out: &mut [u8],
    codec: C,
) {
    if n == 0 {
        return;
    }
    let tex: Vec<u32> = raw
        .chunks_exact(4)
        .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    let mut planes: Vec<&mut [u8]> = out.chunks_exact_mut(t).take(P).collect();
    let mut put = |i: usize, bytes: [u8; 4]| {
        for (p, byte) in planes.iter_mut().zip(bytes) {
            p[i] = byte;
        }
    };
    let mut left = None;
    for (x, &v) in tex[..n].iter().enumerate() {
        put(x, rows_encode_texel(v, first_row_sums(left), codec));
        left = Some(v);
    }
    let mut above = RowValues::new(n);
    for y in 1..n {
        above.fill(&tex[(y - 1) * n..y * n]);
        let row = &tex[y * n..(y + 1) * n];
        for (x, &v) in row.iter().enumerate() {
            let sg = tap_sum(above.g[x], above.g[x + 1], above.g[x + 2]);
            let sr = tap_sum(above.r[x], above.r[x + 1], above.r[x + 2]);
            let sb = tap_sum(above.b[x], above.b[x + 1], above.b[x + 2]);
            put(y * n + x, rows_encode_texel(v, (sg, sr, sb), codec));
        }
    }
}

/// Decodes one row (y >= 1) of filters 2 and 3: `planes` the row's bytes, `above` the
/// previous row's values; writes the texels to `row` and their values to `cur` (unpadded).
#[inline(always)]
fn decode_row<C: RowCodec, const P: usize>(
    planes: [&[u8]; P],
    above: &RowValues,
    cur: &mut RowValues,
    row: &mut [u32],
    codec: C,
) {
    let n = row.len();
    let planes = planes.map(|p| &p[..n]);
    let (ag, ar, ab) = (&above.g[..n + 2], &above.r[..n + 2], &above.b[..n + 2]);
    let (cg, cr, cb) = (
        &mut cur.g[1..n + 1],
        &mut cur.r[1..n + 1],
        &mut cur.b[1..n + 1],
    );
    // Blocks of LANES texels through fixed-size arrays, which the compiler turns into
    // straight-line vector code (no aliasing checks between the row buffers), then the rest
    // texel by texel.
    const LANES: usize = 8;
    let blocks = n / LANES;
    for k in 0..blocks {
        let x0 = k * LANES;
        let fixed = |c: &[f32]| -> [f32; LANES + 2] {
            c[x0..x0 + LANES + 2].try_into().unwrap_or([0.0; LANES + 2])
        };
        let (tg, tr, tb) = (fixed(ag), fixed(ar), fixed(ab));
        let bytes: [[u8; LANES]; P] =
            planes.map(|p| p[x0..x0 + LANES].try_into().unwrap_or([0; LANES]));
        let mut v = [0u32; LANES];
        for i in 0..LANES {
            let sg = tap_sum(tg[i], tg[i + 1], tg[i + 2]);
            let sr = tap_sum(tr[i], tr[i + 1], tr[i + 2]);
            let sb = tap_sum(tb[i], tb[i + 1], tb[i + 2]);
            let mut t = [0u8; 4];
            for (o, p) in t.iter_mut().zip(&bytes) {
                *o = p[i];
            }
            v[i] = rows_decode_texel(t, (sg, sr, sb), codec);
        }
        let (mut g, mut r, mut b) = ([0f32; LANES], [0f32; LANES], [0f32; LANES]);
        for i in 0..LANES {
            let scale = pow2((v[i] >> 27) as i32);
            g[i] = ((v[i] >> 9) & 511) as i32 as f32 * scale;
            r[i] = (v[i] & 511) as i32 as f32 * scale;
            b[i] = ((v[i] >> 18) & 511) as i32 as f32 * scale;
        }
        row[x0..x0 + LANES].copy_from_slice(&v);
        cg[x0..x0 + LANES].copy_from_slice(&g);
        cr[x0..x0 + LANES].copy_from_slice(&r);
        cb[x0..x0 + LANES].copy_from_slice(&b);
    }
    for x in blocks * LANES..n {
        let sg = tap_sum(ag[x], ag[x + 1], ag[x + 2]);
        let sr = tap_sum(ar[x], ar[x + 1], ar[x + 2]);
        let sb = tap_sum(ab[x], ab[x + 1], ab[x + 2]);
        let v = rows_decode_texel(bytes_at(&planes, x), (sg, sr, sb), codec);
        row[x] = v;
        let scale = pow2((v >> 27) as i32);
        cg[x] = ((v >> 9) & 511) as i32 as f32 * scale;
        cr[x] = (v & 511) as i32 as f32 * scale;
        cb[x] = ((v >> 18) & 511) as i32 as f32 * scale;
    }
}

/// [`decode_row`] compiled for AVX2 (8 texels per vector instead of 4). IEEE-754 binary32
/// arithmetic gives the same bits whichever instructions compute it.
///
/// # Safety
/// The processor must support AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn decode_row_avx2<C: RowCodec, const P: usize>(
    planes: [&[u8]; P],
    above: &RowValues,
    cur: &mut RowValues,
    row: &mut [u32],
    codec: C,
) {
    decode_row(planes, above, cur, row, codec)
}

/// [`decode_row`] with the widest vectors the processor has.
fn decode_row_dispatch<C: RowCodec, const P: usize>(
    planes: [&[u8]; P],
    above: &RowValues,
    cur: &mut RowValues,
    row: &mut [u32],
    codec: C,
) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: AVX2 support was just detected.
        unsafe { decode_row_avx2(planes, above, cur, row, codec) };
        return;
    }
    decode_row(planes, above, cur, row, codec)
}

/// Reusable buffers of [`rows_inverse`]: the previous and current row's values, one row of
/// texels.
struct RowsScratch {
    above: RowValues,
    cur: RowValues,
    row: Vec<u32>,
}

thread_local! {
    static ROWS_SCRATCH: std::cell::RefCell<RowsScratch> = std::cell::RefCell::new(RowsScratch {
        above: RowValues::new(0),
        cur: RowValues::new(0),
        row: Vec::new(),
    });
}

/// Filters 2 and 3 inverse: `filtered` holds `P` planes of `t` bytes.
fn rows_inverse<C: RowCodec, const P: usize>(
    n: usize,
    t: usize,
    filtered: &[u8],
    out: &mut [u8],
    codec: C,
) {
    if n == 0 {
        return;
    }
    ROWS_SCRATCH.with(|cell| match cell.try_borrow_mut() {
        Ok(mut scratch) => rows_inverse_with::<C, P>(n, t, filtered, out, &mut scratch, codec),
        // Only reachable through re-entrance, which this module never does; stay correct.
        Err(_) => rows_inverse_with::<C, P>(
            n,
            t,
            filtered,
            out,
            &mut RowsScratch {
                above: RowValues::new(n),
                cur: RowValues::new(n),
                row: Vec::new(),
            },
            codec,
        ),
    })
}

fn rows_inverse_with<C: RowCodec, const P: usize>(
    n: usize,
    t: usize,
    filtered: &[u8],
    out: &mut [u8],
    s: &mut RowsScratch,
    codec: C,
) {
    for v in [&mut s.above, &mut s.cur] {
        v.resize(n);
    }
    s.row.resize(n, 0);
    let mut planes: [&[u8]; P] = [&[]; P];
    for (p, chunk) in planes.iter_mut().zip(filtered.chunks_exact(t)) {
        *p = chunk;
    }
    let mut left = None;
    for (x, v) in s.row.iter_mut().enumerate() {
        *v = rows_decode_texel(bytes_at(&planes, x), first_row_sums(left), codec);
        left = Some(*v);
    }
    let mut out_rows = out.chunks_exact_mut(4 * n);
    if let Some(o) = out_rows.next() {
        for (o, v) in o.chunks_exact_mut(4).zip(&s.row) {
            o.copy_from_slice(&v.to_le_bytes());
        }
    }
    s.above.fill(&s.row);
    for (y, o) in (1..n).zip(out_rows) {
        let span = y * n..(y + 1) * n;
        let row_planes = planes.map(|p| &p[span.clone()]);
        decode_row_dispatch(row_planes, &s.above, &mut s.cur, &mut s.row, codec);
        for (o, v) in o.chunks_exact_mut(4).zip(s.row.iter()) {
            o.copy_from_slice(&v.to_le_bytes());
        }
        s.cur.pad(n);
        std::mem::swap(&mut s.above, &mut s.cur);
    }
}

/// Filter 3 forward with `P = packed_planes(k)` planes.
fn packed_forward(n: usize, t: usize, raw: &[u8], out: &mut [u8], codec: Packed) {
    match packed_planes(codec.bits) {
        1 => rows_forward::<Packed, 1>(n, t, raw, out, codec),
        2 => rows_forward::<Packed, 2>(n, t, raw, out, codec),
        3 => rows_forward::<Packed, 3>(n, t, raw, out, codec),
        _ => rows_forward::<Packed, 4>(n, t, raw, out, codec),
    }
}

/// Filter 3 inverse with `P = packed_planes(k)` planes.
fn packed_inverse(n: usize, t: usize, filtered: &[u8], out: &mut [u8], codec: Packed) {
    match packed_planes(codec.bits) {
        1 => rows_inverse::<Packed, 1>(n, t, filtered, out, codec),
        2 => rows_inverse::<Packed, 2>(n, t, filtered, out, codec),
        3 => rows_inverse::<Packed, 3>(n, t, filtered, out, codec),
        _ => rows_inverse::<Packed, 4>(n, t, filtered, out, codec),
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
                    let len = filtered_face_size(Filter::None, enc, res, distance, 9).unwrap();
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
                            // Lossless with any mantissa lattice, on texels that are not
                            // on it as well.
                            for bits in [1, 4, 5, 8] {
                                let packed = f == Filter::PredictPacked && enc == Encoding::Rgb9e5;
                                // Filter 3 takes texels on the lattice only: others are an
                                // error, and the rest of the round trip runs on the texels
                                // quantized to `bits`.
                                let raw = if packed {
                                    let q = lattice_floor(&raw, (res * res) as usize, bits);
                                    let size = filtered_face_size(f, enc, res, distance, bits);
                                    let mut out = vec![0u8; size.unwrap()];
                                    let r = filter_face_quantized(
                                        f, enc, res, distance, bits, &raw, &mut out,
                                    );
                                    if q != raw {
                                        assert!(
                                            matches!(r, Err(Error::Unquantized { .. })),
                                            "{r:?}"
                                        );
                                    }
                                    q
                                } else {
                                    raw.clone()
                                };
                                let mut filtered =
                                    vec![
                                        0u8;
                                        filtered_face_size(f, enc, res, distance, bits).unwrap()
                                    ];
                                let q = |a: &[u8], o: &mut [u8], inv: bool| {
                                    let g = if inv {
                                        unfilter_face_quantized
                                    } else {
                                        filter_face_quantized
                                    };
                                    g(f, enc, res, distance, bits, a, o).unwrap()
                                };
                                q(&raw, &mut filtered, false);
                                q(&filtered, &mut back, true);
                                assert_eq!(back, raw, "{enc} {f} res {res} bits {bits}");
                            }
                        }
                    }
                }
            }
        }
    }

    /// Filter 2's RGB9E5 residuals computed texel by texel from the spec in lib.rs ("Face
    /// filters"), independently of the row code.
    fn predict_rows_reference(n: usize, tex: &[u32], bits: u32) -> Vec<u8> {
        let t = n * n;
        let mut out = vec![0u8; 4 * t];
        for (i, (&v, [pr, pg, pb])) in tex
            .iter()
            .zip(rows_predictions_reference(n, tex, bits))
            .enumerate()
        {
            let e = v >> 27;
            let (r, g, b) = (v & 511, (v >> 9) & 511, (v >> 18) & 511);
            let z = |c: u32, p: u32| zigzag9(c.wrapping_sub(p));
            let (zr, zg, zb) = (z(r, pr), z(g, pg), z(b, pb));
            out[i] = (e | (zr >> 8) << 5 | (zg >> 8) << 6 | (zb >> 8) << 7) as u8;
            out[t + i] = zg as u8;
            out[2 * t + i] = zr as u8;
            out[3 * t + i] = zb as u8;
        }
        out
    }

    /// Texel `i` of a face of `kind` for the spec tests: 0 any bit pattern, 1 a smooth HDR
    /// gradient with a few exponents, 2 that gradient quantized to `bits`, 3 zeros and
    /// extremes.
    fn spec_texel(kind: usize, i: usize, bits: u32, rng: &mut Rng) -> u32 {
        let gradient = || {
            crate::encoding::encode_rgb9e5([
                0.01 + i as f32 * 0.37,
                0.02 + i as f32 * 0.5,
                0.005 + (i % 5) as f32,
            ])
        };
        match kind {
            0 => rng.next() as u32,
            1 => gradient(),
            2 => crate::encoding::quantize_rgb9e5(gradient(), bits),
            _ => [0u32, u32::MAX, 1 << 27, 511][(rng.next() % 4) as usize],
        }
    }

    /// `raw` with the mantissas of its first `t` RGB9E5 texels rounded down to multiples of
    /// `2^(9 − bits)`.
    fn lattice_floor(raw: &[u8], t: usize, bits: u32) -> Vec<u8> {
        let s = (1u32 << (9 - bits)) - 1;
        let mut q = raw.to_vec();
        for c in q[..4 * t].chunks_exact_mut(4) {
            let v = u32::from_le_bytes([c[0], c[1], c[2], c[3]]);
            c.copy_from_slice(&(v & !(s | s << 9 | s << 18)).to_le_bytes());
        }
        q
    }

    /// Filter 3's planes from the spec, on the predictions of [`rows_predictions_reference`].
    fn predict_packed_reference(n: usize, tex: &[u32], bits: u32) -> Vec<u8> {
        let t = n * n;
        let planes = (5 + 3 * bits as usize).div_ceil(8);
        let s = 1u32 << (9 - bits);
        let zk = |c: u32, p: u32| {
            let q = (c + 512 - p) % 512 / s;
            if q < 1 << (bits - 1) {
                2 * q
            } else {
                2 * ((1 << bits) - q) - 1
            }
        };
        let mut out = vec![0u8; planes * t];
        for (i, (&v, [pr, pg, pb])) in tex
            .iter()
            .zip(rows_predictions_reference(n, tex, bits))
            .enumerate()
        {
            let e = v >> 27;
            let (r, g, b) = (v & 511, (v >> 9) & 511, (v >> 18) & 511);
            let code = u64::from(e)
                | u64::from(zk(g, pg)) << 5
                | u64::from(zk(r, pr)) << (5 + bits)
                | u64::from(zk(b, pb)) << (5 + 2 * bits);
            for j in 0..planes {
                out[j * t + i] = (code >> (8 * j)) as u8;
            }
        }
        out
    }

    /// Filter 2's (and 3's) predictions `[pR, pG, pB]` of every texel, texel by texel from
    /// the spec in lib.rs ("Face filters").
    fn rows_predictions_reference(n: usize, tex: &[u32], bits: u32) -> Vec<[u32; 3]> {
        let value = |v: u32, shift: u32| ((v >> shift) & 511) as f32 * 2f32.powi((v >> 27) as i32);
        // Round to nearest, then to the lattice of multiples of s = 2^(9 - bits), at most
        // 512 - s.
        let s = 1u32 << (9 - bits);
        let lattice = |p: u32| ((p + s / 2) / s * s).min(512 - s);
        let round = |x: f32| lattice((x + 0.5).clamp(0.0, 511.0).trunc() as u32);
        let mut out = vec![[0u32; 3]; n * n];
        for y in 0..n {
            for x in 0..n {
                let i = y * n + x;
                let v = tex[i];
                let e = v >> 27;
                let g = (v >> 9) & 511;
                let taps = match (x, y) {
                    (0, 0) => None,
                    (_, 0) => Some([i - 1; 3]),
                    _ => Some([
                        (y - 1) * n + x.saturating_sub(1),
                        (y - 1) * n + x,
                        (y - 1) * n + (x + 1).min(n - 1),
                    ]),
                };
                let sum = |shift: u32| {
                    taps.map_or(0.0, |[a, b, c]| {
                        (value(tex[a], shift) + 2.0 * value(tex[b], shift)) + value(tex[c], shift)
                    })
                };
                let (sr, sg, sb) = (sum(0), sum(9), sum(18));
                let q = 2f32.powi(-(e as i32) - 2);
                let pg = round(sg * q);
                let pc = |sc: f32| {
                    if sg == 0.0 {
                        round(sc * q)
                    } else {
                        round(g as f32 * (sc / sg))
                    }
                };
                out[i] = [pc(sr), pg, pc(sb)];
            }
        }
        out
    }

    #[test]
    fn predict_packed_matches_the_spec() {
        let mut rng = Rng(0x5eed_0f9a_cced);
        for res in [1usize, 2, 3, 7, 16, 33] {
            for bits in 1..=9u32 {
                for kind in 0..3 {
                    let t = res * res;
                    // Any bit pattern, the quantized gradient, zeros and extremes (all put on
                    // the lattice below).
                    let tex: Vec<u32> = (0..t)
                        .map(|i| spec_texel([0, 2, 3][kind], i, bits, &mut rng))
                        .collect();
                    let raw: Vec<u8> = tex.iter().flat_map(|v| v.to_le_bytes()).collect();
                    let raw = lattice_floor(&raw, t, bits);
                    let tex: Vec<u32> = raw
                        .chunks_exact(4)
                        .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                        .collect();
                    let n = res as u32;
                    let size =
                        filtered_face_size(Filter::PredictPacked, Encoding::Rgb9e5, n, false, bits);
                    assert_eq!(size, Some(t * packed_planes(bits)));
                    let mut filtered = vec![0u8; t * packed_planes(bits)];
                    let f = Filter::PredictPacked;
                    filter_face_quantized(f, Encoding::Rgb9e5, n, false, bits, &raw, &mut filtered)
                        .unwrap();
                    let want = predict_packed_reference(res, &tex, bits);
                    assert_eq!(filtered, want, "res {res} kind {kind} bits {bits}");
                    let mut back = vec![0u8; raw.len()];
                    unfilter_face_quantized(
                        f,
                        Encoding::Rgb9e5,
                        n,
                        false,
                        bits,
                        &filtered,
                        &mut back,
                    )
                    .unwrap();
                    assert_eq!(back, raw, "res {res} kind {kind} bits {bits}");
                    // Any bytes decode to texels on the lattice.
                    let junk: Vec<u8> = (0..filtered.len()).map(|_| rng.next() as u8).collect();
                    unfilter_face_quantized(f, Encoding::Rgb9e5, n, false, bits, &junk, &mut back)
                        .unwrap();
                    assert_eq!(lattice_floor(&back, t, bits), back, "res {res} bits {bits}");
                }
            }
        }
    }

    #[test]
    fn predict_rows_matches_the_spec() {
        let mut rng = Rng(0x0dd_ba11_cafe_f00d);
        for (res, kind, bits) in [1usize, 2, 3, 7, 16, 33]
            .into_iter()
            .flat_map(|r| (0..4).map(move |k| (r, k)))
            .flat_map(|(r, k)| [9u32, 7, 5, 2, 1].map(|b| (r, k, b)))
        {
            {
                let tex: Vec<u32> = (0..res * res)
                    .map(|i| spec_texel(kind, i, bits, &mut rng))
                    .collect();
                let raw: Vec<u8> = tex.iter().flat_map(|v| v.to_le_bytes()).collect();
                let mut filtered = vec![0u8; raw.len()];
                let n = res as u32;
                filter_face_quantized(
                    Filter::PredictRows,
                    Encoding::Rgb9e5,
                    n,
                    false,
                    bits,
                    &raw,
                    &mut filtered,
                )
                .unwrap();
                assert_eq!(
                    filtered,
                    predict_rows_reference(res, &tex, bits),
                    "res {res} kind {kind} bits {bits}"
                );
                if kind == 2 && res > 1 {
                    // Quantized texels leave residuals on the lattice: zigzag9 of a
                    // multiple of s is 2js or 2js - 1 (low bits all zero or all one).
                    let s = 1u32 << (9 - bits);
                    let t = res * res;
                    for i in 0..t {
                        let h = u32::from(filtered[i]);
                        for (plane, hi) in [(1, 6), (2, 5), (3, 7)] {
                            let z = u32::from(filtered[plane * t + i]) | (h >> hi & 1) << 8;
                            let r = unzigzag9(z);
                            assert_eq!(r % s, 0, "res {res} bits {bits} texel {i}");
                        }
                    }
                }
                // The decoder (vectorised where the processor allows) inverts it.
                let mut back = vec![0u8; raw.len()];
                unfilter_face_quantized(
                    Filter::PredictRows,
                    Encoding::Rgb9e5,
                    n,
                    false,
                    bits,
                    &filtered,
                    &mut back,
                )
                .unwrap();
                assert_eq!(back, raw, "res {res} kind {kind} bits {bits}");
            }
        }
    }

    #[test]
    fn predict_rows_of_a_constant_face_is_zero_after_the_first_texel() {
        let n = 8u32;
        let v = crate::encoding::encode_rgb9e5([1.5, 0.75, 0.2]);
        let raw: Vec<u8> = (0..n * n).flat_map(|_| v.to_le_bytes()).collect();
        let mut filtered = vec![0u8; raw.len()];
        filter_face(
            Filter::PredictRows,
            Encoding::Rgb9e5,
            n,
            false,
            &raw,
            &mut filtered,
        )
        .unwrap();
        let t = (n * n) as usize;
        for i in 1..t {
            assert_eq!(filtered[i], (v >> 27) as u8, "exponent plane, texel {i}");
            for p in 1..4 {
                assert_eq!(filtered[p * t + i], 0, "plane {p}, texel {i}");
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
        assert!(Filter::from_id(4).is_none());
        for f in Filter::ALL {
            assert_eq!(Filter::from_id(f.id()), Some(f));
        }
    }
}
