//! Filters 2 (predict-rows) and 3 (predict-packed) on RGB9E5 texels: binary32 predictions
//! from the row above, rounded to the store's mantissa lattice; filter 2 stores the residuals
//! in four byte planes, filter 3 packs them with the exponent in lattice steps.

use crate::filter::residual::{fields, unzigzag9, zigzag9};

/// The mantissa lattice of a store keeping `k` RGB9E5 mantissa bits: filter 2 rounds its
/// predictions to multiples of `step = 2^(9 − k)`, so that the residuals of quantized texels
/// are multiples of `step` too. `k = 9` (step 1) leaves every prediction unchanged.
#[derive(Clone, Copy, Debug)]
pub(super) struct Lattice {
    /// `step / 2`.
    half: u32,
    /// `!(step − 1)` (low bits cleared).
    mask: u32,
    /// `512 − step`, the largest multiple of `step` below 512.
    top: u32,
}

impl Lattice {
    pub(super) fn new(mantissa_bits: u32) -> Self {
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

/// `2^k` as an f32, for `k` in `-126..=127` (exact: built from the exponent bits).
#[inline(always)]
pub(super) fn pow2(k: i32) -> f32 {
    f32::from_bits(((k + 127) as u32) << 23)
}

/// A channel's value `m · 2^e` (exact in binary32 for `m <= 511`, `e <= 31`).
#[inline(always)]
pub(super) fn channel_value(m: u32, e: u32) -> f32 {
    (m & 511) as i32 as f32 * pow2((e & 31) as i32)
}

/// `min(511, trunc(x + 0.5))` for `x >= 0` (x may be +inf; the sum is rounded to binary32).
#[inline(always)]
pub(super) fn round_mantissa(x: f32) -> u32 {
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
pub(super) fn tap_sum(a: f32, b: f32, c: f32) -> f32 {
    (a + 2.0 * b) + c
}

/// Green prediction from the neighbour sum `sg` of a texel with exponent `e`.
#[inline(always)]
pub(super) fn rows_predict_g(sg: f32, e: u32, lat: Lattice) -> u32 {
    // 2^(-e-2): the sums weigh four neighbours and are in units of 2^0.
    lat.round(round_mantissa(sg * pow2(-((e & 31) as i32) - 2)))
}

/// Red or blue prediction from the neighbour sums `sc` (the channel) and `sg` (green) of a
/// texel with exponent `e` and green mantissa `g`.
#[inline(always)]
pub(super) fn rows_predict_rb(sc: f32, sg: f32, e: u32, g: u32, lat: Lattice) -> u32 {
    let flat = sc * pow2(-((e & 31) as i32) - 2);
    // Division by zero gives inf or NaN only in the branch that is not taken.
    let ratio = (g & 511) as i32 as f32 * (sc / sg);
    lat.round(round_mantissa(if sg == 0.0 { flat } else { ratio }))
}

/// Per-row neighbour values of the three channels, padded by one column on each side with
/// copies of the edge texels: `[x + 1]` holds column `x`.
pub(super) struct RowValues {
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
pub(super) trait RowCodec: Copy {
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
pub(super) struct Planes9(pub(super) Lattice);

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
pub(super) struct Packed {
    lat: Lattice,
    /// `k`.
    bits: u32,
    /// `9 − k`.
    shift: u32,
    /// `2^k − 1`.
    mask: u32,
}

impl Packed {
    pub(super) fn new(mantissa_bits: u32) -> Self {
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
pub(super) fn first_row_sums(left: Option<u32>) -> (f32, f32, f32) {
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
pub(super) fn rows_encode_texel<C: RowCodec>(
    v: u32,
    (sg, sr, sb): (f32, f32, f32),
    codec: C,
) -> [u8; 4] {
    let lat = codec.lattice();
    let (e, m) = fields(v);
    let zg = codec.residual(m[1], rows_predict_g(sg, e, lat));
    let zr = codec.residual(m[0], rows_predict_rb(sr, sg, e, m[1], lat));
    let zb = codec.residual(m[2], rows_predict_rb(sb, sg, e, m[1], lat));
    codec.pack(e, zg, zr, zb)
}

/// Texel from its bytes and neighbour sums `sums`.
#[inline(always)]
pub(super) fn rows_decode_texel<C: RowCodec>(
    bytes: [u8; 4],
    (sg, sr, sb): (f32, f32, f32),
    codec: C,
) -> u32 {
    let lat = codec.lattice();
    let (e, zg, zr, zb) = codec.unpack(bytes);
    let g = codec.apply(rows_predict_g(sg, e, lat), zg);
    let r = codec.apply(rows_predict_rb(sr, sg, e, g, lat), zr);
    let b = codec.apply(rows_predict_rb(sb, sg, e, g, lat), zb);
    r | g << 9 | b << 18 | e << 27
}

/// The bytes of texel `x` in `P` planes (the rest 0).
#[inline(always)]
pub(super) fn bytes_at<const P: usize>(planes: &[&[u8]; P], x: usize) -> [u8; 4] {
    let mut b = [0u8; 4];
    for (o, p) in b.iter_mut().zip(planes) {
        *o = p[x];
    }
    b
}

/// Filters 2 and 3 forward: `out` holds `P` planes of `t` bytes.
pub(super) fn rows_forward<C: RowCodec, const P: usize>(
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
pub(super) fn decode_row<C: RowCodec, const P: usize>(
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
pub(super) fn decode_row_dispatch<C: RowCodec, const P: usize>(
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
pub(super) struct RowsScratch {
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
pub(super) fn rows_inverse<C: RowCodec, const P: usize>(
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

pub(super) fn rows_inverse_with<C: RowCodec, const P: usize>(
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
pub(super) fn packed_forward(n: usize, t: usize, raw: &[u8], out: &mut [u8], codec: Packed) {
    match packed_planes(codec.bits) {
        1 => rows_forward::<Packed, 1>(n, t, raw, out, codec),
        2 => rows_forward::<Packed, 2>(n, t, raw, out, codec),
        3 => rows_forward::<Packed, 3>(n, t, raw, out, codec),
        _ => rows_forward::<Packed, 4>(n, t, raw, out, codec),
    }
}

/// Filter 3 inverse with `P = packed_planes(k)` planes.
pub(super) fn packed_inverse(n: usize, t: usize, filtered: &[u8], out: &mut [u8], codec: Packed) {
    match packed_planes(codec.bits) {
        1 => rows_inverse::<Packed, 1>(n, t, filtered, out, codec),
        2 => rows_inverse::<Packed, 2>(n, t, filtered, out, codec),
        3 => rows_inverse::<Packed, 3>(n, t, filtered, out, codec),
        _ => rows_inverse::<Packed, 4>(n, t, filtered, out, codec),
    }
}
